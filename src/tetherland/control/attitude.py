"""Geometric attitude control on SO(3) (Lee, Leok, McClamroch 2010).

    e_R = 1/2 vee(R_d^T R - R^T R_d),   e_w = w - R^T R_d w_d
    tau = -J (k_R e_R + k_w e_w) + w x J w - J (hat(w) R^T R_d w_d - R^T R_d w_d')

with per-axis gains k_R = omega_n^2, k_w = 2 zeta omega_n (roll, pitch, yaw), so that for
small errors each axis follows e'' + k_w e' + k_R e = 0. Frames: R = R_WB, w in F_B.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland.config.control import FreeFlightGains, TetheredGains
from tetherland.geometry import FloatArray
from tetherland.rotations import cross3


@dataclass(frozen=True)
class AttitudeGains:
    """Per-axis attitude gains (roll, pitch, yaw): k_R [1/s^2] and k_w [1/s]."""

    k_R: FloatArray
    k_w: FloatArray

    @classmethod
    def from_config(cls, gains: FreeFlightGains | TetheredGains) -> AttitudeGains:
        """Gains from natural frequencies and damping ratios of a gains section."""
        w, z = gains.attitude_frequency, gains.attitude_damping
        wy, zy = gains.yaw_frequency, gains.yaw_damping
        return cls(
            k_R=np.array([w * w, w * w, wy * wy]),
            k_w=np.array([2 * z * w, 2 * z * w, 2 * zy * wy]),
        )


def attitude_error(R: FloatArray, R_d: FloatArray) -> FloatArray:
    """e_R = 1/2 vee(R_d^T R - R^T R_d) (F_B); |e_R| = sin(angle) for a single-axis error."""
    E = R_d.T @ R
    return 0.5 * np.array([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]])


def attitude_torque(
    J: FloatArray,
    J_k_R: FloatArray,
    J_k_w: FloatArray,
    R: FloatArray,
    omega_B: FloatArray,
    R_d: FloatArray,
    omega_d: FloatArray | None = None,
    omega_dot_d: FloatArray | None = None,
) -> FloatArray:
    """Body torque tau_B [N m] of the law above for attitude R_WB, rate omega_B [rad/s] and
    the desired R_d; principal inertia ``J`` [kg m^2] and the gains as J k_R [N m/rad] and
    J k_w [N m s/rad] per axis.

    ``omega_d``, ``omega_dot_d`` are the desired angular velocity [rad/s] and acceleration
    [rad/s^2] in the desired frame (feed-forward; zero when omitted). Compiled:
    :func:`tetherland.control.kernels.so3.attitude_torque`.
    """
    e_R = attitude_error(R, R_d)
    Jw = J * omega_B
    tau = cross3(omega_B, Jw)
    if omega_d is None:
        e_w = omega_B
    else:
        Rt_Rd = R.T @ R_d
        w_d_B = Rt_Rd @ omega_d
        e_w = omega_B - w_d_B
        ff = cross3(omega_B, w_d_B)
        if omega_dot_d is not None:
            ff = ff - Rt_Rd @ omega_dot_d
        tau = tau - J * ff
    return tau - J_k_R * e_R - J_k_w * e_w


class AttitudeController:
    """Torque command tracking a desired attitude.

    Parameters
    ----------
    inertia : (3,) array
        Principal moments of inertia J_xx, J_yy, J_zz [kg m^2] (F_B).
    gains : AttitudeGains
    """

    def __init__(self, inertia: ArrayLike, gains: AttitudeGains):
        self.J = np.asarray(inertia, dtype=float)
        self.gains = gains
        self._JkR = self.J * gains.k_R
        self._Jkw = self.J * gains.k_w

    def torque(
        self,
        R: FloatArray,
        omega_B: FloatArray,
        R_d: FloatArray,
        omega_d: FloatArray | None = None,
        omega_dot_d: FloatArray | None = None,
    ) -> FloatArray:
        """Body torque tau_B [N m] for attitude R_WB, rate omega_B and the desired R_d
        (:func:`attitude_torque` with this controller's inertia and gains)."""
        return attitude_torque(self.J, self._JkR, self._Jkw, R, omega_B, R_d, omega_d, omega_dot_d)
