"""State records shared by models, simulation, control and estimation.

All vectors in F_W unless the name says otherwise; quaternions scalar-first.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tetherland.geometry import FloatArray
from tetherland.rotations import quat_to_rotmat


@dataclass(frozen=True, slots=True)
class RigidBodyState:
    """Pose and twist of the vehicle's centre of mass.

    Attributes
    ----------
    p_W : (3,) array
        Position of the centre of mass O_R [m].
    v_W : (3,) array
        Velocity of O_R [m/s].
    q_WB : (4,) array
        Attitude as a unit quaternion (w, x, y, z), F_B -> F_W.
    omega_B : (3,) array
        Angular velocity in F_B [rad/s].
    """

    p_W: FloatArray
    v_W: FloatArray
    q_WB: FloatArray
    omega_B: FloatArray

    @property
    def R_WB(self) -> FloatArray:
        """Rotation matrix F_B -> F_W."""
        return quat_to_rotmat(self.q_WB)

    @property
    def z_B(self) -> FloatArray:
        """Thrust axis in F_W."""
        return self.R_WB[:, 2]

    @classmethod
    def at_rest(cls, p_W: FloatArray, q_WB: FloatArray | None = None) -> RigidBodyState:
        """A state at ``p_W`` with zero velocity (level attitude by default)."""
        return cls(
            p_W=np.asarray(p_W, dtype=float),
            v_W=np.zeros(3),
            q_WB=np.array([1.0, 0.0, 0.0, 0.0]) if q_WB is None else np.asarray(q_WB, dtype=float),
            omega_B=np.zeros(3),
        )


@dataclass(frozen=True, slots=True)
class LinkState:
    """Taut-link configuration q = (phi, delta) and its rates (section 6.2.2) [rad, rad/s]."""

    phi: float
    delta: float
    phi_dot: float = 0.0
    delta_dot: float = 0.0

    def as_array(self) -> FloatArray:
        return np.array([self.phi, self.delta, self.phi_dot, self.delta_dot])
