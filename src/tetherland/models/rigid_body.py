"""Free-flight rigid-body dynamics of the quadrotor (6.1)-(6.2), docs/theory.md section 4.

  m p''_R = -m g z_W + f_R z_B + f_ext          (F_W)
  J w'    = -w x J w + tau_B + tau_ext           (F_B)
  q'      = 0.5 q * (0, w)                       (q = q_WB, scalar-first)

``f_ext`` and ``tau_ext`` carry anything else acting on the body (cable, contact). The
chapter's thrust term -f_R z_R is +f_R z_B here (z_R = -z_B).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland import GRAVITY
from tetherland.config import VehicleConfig
from tetherland.geometry import FloatArray
from tetherland.models.integrators import rk4
from tetherland.rotations import quat_multiply, quat_to_rotmat
from tetherland.state import RigidBodyState

STATE_SIZE = 13
"""Length of the flat state vector [p_W (3), v_W (3), q_WB (4), omega_B (3)]."""


@dataclass(frozen=True)
class RigidBodyParams:
    """Mass properties of the vehicle.

    Attributes
    ----------
    mass : float
        m [kg].
    inertia : (3, 3) array
        J about the centre of mass in F_B [kg m^2].
    gravity : float
        g [m/s^2].
    """

    mass: float
    inertia: FloatArray
    gravity: float = GRAVITY

    def __post_init__(self) -> None:
        J = np.asarray(self.inertia, dtype=float)
        if J.shape == (3,):
            J = np.diag(J)
        if J.shape != (3, 3):
            raise ValueError(f"inertia must be (3,) or (3, 3), got shape {J.shape}")
        if self.mass <= 0:
            raise ValueError(f"mass must be > 0, got {self.mass}")
        object.__setattr__(self, "inertia", J)

    @classmethod
    def from_config(cls, vehicle: VehicleConfig) -> RigidBodyParams:
        return cls(mass=vehicle.mass, inertia=np.diag(vehicle.inertia))

    @property
    def inertia_inverse(self) -> FloatArray:
        return np.linalg.inv(self.inertia)


@dataclass(frozen=True)
class RigidBodyDerivative:
    """Time derivative of a :class:`RigidBodyState`.

    Attributes
    ----------
    p_dot_W, v_dot_W : (3,) arrays
        Velocity [m/s] and acceleration [m/s^2] of the centre of mass, F_W.
    q_dot : (4,) array
        Quaternion rate (w, x, y, z) [1/s].
    omega_dot_B : (3,) array
        Angular acceleration in F_B [rad/s^2].
    """

    p_dot_W: FloatArray
    v_dot_W: FloatArray
    q_dot: FloatArray
    omega_dot_B: FloatArray


def rigid_body_derivative(
    state: RigidBodyState,
    f_R: float,
    tau_B: ArrayLike,
    params: RigidBodyParams,
    f_ext_W: ArrayLike | None = None,
    tau_ext_B: ArrayLike | None = None,
) -> RigidBodyDerivative:
    """Right-hand side of (6.1)-(6.2) for thrust ``f_R`` [N] and rotor torque ``tau_B`` [N m]."""
    R_WB = quat_to_rotmat(state.q_WB)
    force = f_R * R_WB[:, 2] - params.mass * params.gravity * np.array([0.0, 0.0, 1.0])
    if f_ext_W is not None:
        force = force + np.asarray(f_ext_W, dtype=float)
    w = np.asarray(state.omega_B, dtype=float)
    J = params.inertia
    torque = np.asarray(tau_B, dtype=float) - np.cross(w, J @ w)
    if tau_ext_B is not None:
        torque = torque + np.asarray(tau_ext_B, dtype=float)
    return RigidBodyDerivative(
        p_dot_W=np.asarray(state.v_W, dtype=float).copy(),
        v_dot_W=force / params.mass,
        q_dot=0.5 * quat_multiply(state.q_WB, np.concatenate(([0.0], w))),
        omega_dot_B=np.linalg.solve(J, torque),
    )


def state_to_vector(state: RigidBodyState) -> FloatArray:
    """[p_W, v_W, q_WB, omega_B] as one (13,) vector."""
    return np.concatenate((state.p_W, state.v_W, state.q_WB, state.omega_B)).astype(float)


def state_from_vector(x: ArrayLike, normalize: bool = True) -> RigidBodyState:
    """Inverse of :func:`state_to_vector`; the quaternion is renormalised by default."""
    x = np.asarray(x, dtype=float)
    if x.shape != (STATE_SIZE,):
        raise ValueError(f"rigid-body state vector must have shape (13,), got {x.shape}")
    q = x[6:10]
    if normalize:
        q = q / np.linalg.norm(q)
    return RigidBodyState(
        p_W=x[0:3].copy(), v_W=x[3:6].copy(), q_WB=q.copy(), omega_B=x[10:13].copy()
    )


def rigid_body_rhs(
    x: ArrayLike,
    f_R: float,
    tau_B: ArrayLike,
    params: RigidBodyParams,
    f_ext_W: ArrayLike | None = None,
    tau_ext_B: ArrayLike | None = None,
) -> FloatArray:
    """:func:`rigid_body_derivative` on the flat (13,) state vector (for integrators)."""
    d = rigid_body_derivative(
        state_from_vector(x, normalize=False), f_R, tau_B, params, f_ext_W, tau_ext_B
    )
    return np.concatenate((d.p_dot_W, d.v_dot_W, d.q_dot, d.omega_dot_B))


def rk4_step(
    state: RigidBodyState,
    f_R: float,
    tau_B: ArrayLike,
    dt: float,
    params: RigidBodyParams,
    f_ext_W: ArrayLike | None = None,
    tau_ext_B: ArrayLike | None = None,
) -> RigidBodyState:
    """One classical Runge-Kutta step with inputs held constant; renormalises q."""

    def f(v: FloatArray, _u: None) -> FloatArray:
        return rigid_body_rhs(v, f_R, tau_B, params, f_ext_W, tau_ext_B)

    return state_from_vector(rk4(f, state_to_vector(state), None, dt))


def kinetic_energy(state: RigidBodyState, params: RigidBodyParams) -> float:
    """0.5 m |v|^2 + 0.5 w.J w [J]."""
    v = np.asarray(state.v_W, dtype=float)
    w = np.asarray(state.omega_B, dtype=float)
    return float(0.5 * params.mass * v @ v + 0.5 * w @ params.inertia @ w)
