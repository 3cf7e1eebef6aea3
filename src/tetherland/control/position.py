"""Geometric position control for free flight (Lee, Leok, McClamroch 2010).

    F_d = m (a_d - k_x e_x - k_v e_v) - m g_W,   f_R = F_d . z_B,
    z_B,d = F_d/||F_d||,  R_d from (z_B,d, psi_d),  tau from :mod:`attitude`.

Optional feed-forward: with the reference's jerk (and snap), the desired body rate (and
angular acceleration) of the nominal attitude of the flat outputs enter the attitude law
(:mod:`tetherland.control.feedforward`).

The commanded tilt is limited (``max_tilt_deg``) and the vertical thrust kept positive, so
z_B,d never becomes horizontal or undefined (the singularity of R_d is avoided, not hit).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from tetherland import GRAVITY
from tetherland.config.control import FreeFlightGains
from tetherland.control.attitude import AttitudeController, AttitudeGains
from tetherland.control.feedforward import attitude_feedforward_fast
from tetherland.geometry import FloatArray
from tetherland.rotations import rotation_from_z_and_yaw
from tetherland.state import RigidBodyState

_ZERO3 = np.zeros(3)


@dataclass(frozen=True, slots=True)
class PositionReference:
    """Desired flat outputs of free flight (F_W).

    Attributes
    ----------
    p_W, v_W, a_W : (3,) arrays
        Desired position [m], velocity [m/s], acceleration [m/s^2] of the centre of mass.
    yaw : float
        Desired heading psi [rad] (held constant by the feed-forward).
    j_W, s_W : (3,) arrays or None
        Desired jerk [m/s^3] and snap [m/s^4]. When ``j_W`` is given, the controller adds
        the desired body rate (and, with ``s_W``, angular acceleration) of the flat outputs
        as attitude feed-forward (:mod:`tetherland.control.feedforward`); None: no
        feed-forward (the default behaviour).
    """

    p_W: FloatArray
    v_W: FloatArray = field(default_factory=lambda: _ZERO3.copy())
    a_W: FloatArray = field(default_factory=lambda: _ZERO3.copy())
    yaw: float = 0.0
    j_W: FloatArray | None = None
    s_W: FloatArray | None = None

    @classmethod
    def from_rows(cls, rows: FloatArray, yaw: float = 0.0) -> PositionReference:
        """From ``Reference.p_W``: rows p, v, a, jerk, snap (the first k given) [F_W]."""
        r = np.asarray(rows, dtype=float).reshape(-1, 3)
        k = len(r)
        return cls(
            p_W=r[0],
            v_W=r[1] if k > 1 else _ZERO3.copy(),
            a_W=r[2] if k > 2 else _ZERO3.copy(),
            yaw=float(yaw),
            j_W=r[3] if k > 3 else None,
            s_W=r[4] if k > 4 else None,
        )


@dataclass(frozen=True, slots=True)
class WrenchCommand:
    """Total thrust and body torque requested from the allocation.

    Attributes
    ----------
    thrust : float
        f_R along z_B [N].
    torque_B : (3,) array
        tau_B [N m].
    R_d : (3, 3) array
        Desired attitude R_WB,d (for logs and plots).
    limited : bool
        The tilt or vertical-thrust limit was active.
    """

    thrust: float
    torque_B: FloatArray
    R_d: FloatArray
    limited: bool = False


class PositionController:
    """Free-flight position and attitude controller producing a wrench.

    Parameters
    ----------
    mass : float
        [kg]
    inertia : (3,) array
        Principal inertia [kg m^2].
    gains : FreeFlightGains
    min_thrust : float
        Smallest vertical component of F_d [N] (e.g. n f_min); keeps F_d away from zero.
    """

    def __init__(
        self,
        mass: float,
        inertia: FloatArray,
        gains: FreeFlightGains,
        min_thrust: float = 0.0,
        g: float = GRAVITY,
    ):
        self.mass = mass
        self.g = g
        wn, zeta = gains.position_frequency, gains.position_damping
        self.k_x = wn * wn
        self.k_v = 2.0 * zeta * wn
        self.k_i = gains.position_integral
        self.integral_max = gains.integral_force_max * mass * g  # [N] per axis
        self._integral = np.zeros(3)  # integral of the position error [m s]
        self.tan_max_tilt = math.tan(math.radians(gains.max_tilt_deg))
        self.min_vertical = max(min_thrust, 0.05 * mass * g)
        self.attitude = AttitudeController(inertia, AttitudeGains.from_config(gains))

    def reset(self) -> None:
        """Clear the integral of the position error (call when the controller takes over)."""
        self._integral[:] = 0.0

    def seed_integral(self, force_W: FloatArray) -> None:
        """Start the integral at the force ``force_W`` F_W [N] (clamped per axis like the
        integral itself): the bumpless hand-over from a controller that was already
        holding the model error (mass, thrust coefficient) this one would integrate."""
        if self.k_i <= 0.0:
            return
        bound = self.integral_max / (self.mass * self.k_i)
        np.clip(-np.asarray(force_W, float) / (self.mass * self.k_i), -bound, bound,
                out=self._integral)  # fmt: skip

    @property
    def integral(self) -> FloatArray:
        """Integral of the position error [m s] (the live array: compiled controllers
        update it in place)."""
        return self._integral

    @property
    def integral_force(self) -> FloatArray:
        """Current integral force -m k_i int(e) in F_W [N]."""
        return -self.mass * self.k_i * self._integral

    def desired_force(
        self, state: RigidBodyState, ref: PositionReference, dt: float | None = None
    ) -> tuple[FloatArray, bool]:
        """F_d in F_W [N] (after the tilt and vertical-thrust limits) and whether a limit acted.

        With ``dt`` [s] the position error is integrated (PID; the integral force is clamped
        to ``integral_force_max`` m g per axis and frozen while a limit acts).
        """
        e_x = state.p_W - ref.p_W
        e_v = state.v_W - ref.v_W
        F = self.mass * (ref.a_W - self.k_x * e_x - self.k_v * e_v) + self.integral_force
        F[2] += self.mass * self.g
        limited = False
        if F[2] < self.min_vertical:
            F[2] = self.min_vertical
            limited = True
        horiz = math.hypot(F[0], F[1])
        max_horiz = F[2] * self.tan_max_tilt
        if horiz > max_horiz:
            F[0:2] *= max_horiz / horiz
            limited = True
        if dt is not None and self.k_i > 0.0 and not limited:
            bound = self.integral_max / (self.mass * self.k_i)
            np.clip(self._integral + e_x * dt, -bound, bound, out=self._integral)
        return F, limited

    def update(
        self,
        state: RigidBodyState,
        ref: PositionReference,
        dt: float | None = None,
        rates: tuple[FloatArray, FloatArray] | None = None,
    ) -> WrenchCommand:
        """Wrench tracking ``ref`` from ``state`` (``dt`` [s] since the last call: integral).

        ``rates``: :meth:`feedforward_rates` of ``ref`` when the caller has them already.
        """
        F, limited = self.desired_force(state, ref, dt)
        R = state.R_WB
        R_d = rotation_from_z_and_yaw(F, ref.yaw)
        thrust = float(F @ R[:, 2])
        omega_d = omega_dot_d = None
        if ref.j_W is not None:
            omega_d, omega_dot_d = rates if rates is not None else self.feedforward_rates(ref)
        tau = self.attitude.torque(R, state.omega_B, R_d, omega_d, omega_dot_d)
        return WrenchCommand(thrust=thrust, torque_B=tau, R_d=R_d, limited=limited)

    def feedforward_rates(self, ref: PositionReference) -> tuple[FloatArray, FloatArray]:
        """Body rate and angular acceleration of the reference's flat outputs (F_B of the
        desired attitude) [rad/s, rad/s^2]; zero snap when ``s_W`` is None."""
        m = self.mass
        F_n = m * np.asarray(ref.a_W, dtype=float)
        F_n[2] += m * self.g
        dF = m * np.asarray(ref.j_W, dtype=float)
        ddF = _ZERO3 if ref.s_W is None else m * np.asarray(ref.s_W, dtype=float)
        _, omega_d, omega_dot_d = attitude_feedforward_fast(F_n, dF, ddF, ref.yaw)
        return omega_d, omega_dot_d
