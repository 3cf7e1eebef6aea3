"""Body rate and angular acceleration feed-forward from the flat outputs (free flight).

For a quadrotor the desired attitude follows from the desired force F = m (p'' + g z_W)
and the heading psi: R_d = [x_d, y_d, z_d] with z_d = F/||F||, y_d = z_d x x_C/||.||,
x_d = y_d x z_d, x_C = [cos psi, sin psi, 0] (:func:`rotation_from_z_and_yaw`). Its rate
and acceleration follow from F' = m p''' (jerk) and F'' = m p'''' (snap) for a constant
heading:

  omega_d^ = R_d^T R_d',   omega_d'^ = R_d^T R_d'' - (omega_d^)^2   (hat map, F_B of R_d)

with the derivatives of a normalised vector n = v/r, r = ||v||:
  n'  = (v' - n r')/r,  r' = n . v',
  n'' = (v'' - 2 n' r' - n r'')/r,  r'' = n' . v' + n . v''.

:func:`attitude_feedforward` is the plain reference; :func:`attitude_feedforward_fast`
is the same computation compiled with numba (one call, scalar arithmetic), which the
controllers use every tick. A property test checks that both agree to 1e-9.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.errors import SingularityError
from tetherland.geometry import FloatArray
from tetherland.rotations import vee

_EPS = 1e-9


def _normalised(
    v: FloatArray, dv: FloatArray, ddv: FloatArray, what: str
) -> tuple[FloatArray, FloatArray, FloatArray]:
    r = float(np.linalg.norm(v))
    if r < _EPS:
        raise SingularityError(f"{what} is zero: its direction is undefined")
    n = v / r
    dr = float(n @ dv)
    dn = (dv - n * dr) / r
    ddr = float(dn @ dv + n @ ddv)
    ddn = (ddv - 2.0 * dn * dr - n * ddr) / r
    return n, dn, ddn


def attitude_feedforward(
    F: FloatArray, dF: FloatArray, ddF: FloatArray, yaw: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Desired attitude, body rate and angular acceleration for a force profile.

    Parameters
    ----------
    F, dF, ddF : (3,) arrays
        Desired force m (p'' + g z_W) and its first two time derivatives, F_W [N, N/s,
        N/s^2].
    yaw : float
        Heading psi (held constant) [rad].

    Returns
    -------
    R_d : (3, 3) array
        Desired attitude R_WB.
    omega_d, omega_dot_d : (3,) arrays
        Its angular velocity [rad/s] and acceleration [rad/s^2] in the desired body frame.

    Raises
    ------
    SingularityError
        When F is zero or z_d is along the heading x_C (yaw undefined).
    """
    z, dz, ddz = _normalised(np.asarray(F, float), np.asarray(dF, float),
                             np.asarray(ddF, float), "desired force")  # fmt: skip
    x_C = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    y, dy, ddy = _normalised(np.cross(z, x_C), np.cross(dz, x_C), np.cross(ddz, x_C),
                             "z_d x x_C (thrust axis along the heading)")  # fmt: skip
    x = np.cross(y, z)
    dx = np.cross(dy, z) + np.cross(y, dz)
    ddx = np.cross(ddy, z) + 2.0 * np.cross(dy, dz) + np.cross(y, ddz)
    R = np.column_stack((x, y, z))
    dR = np.column_stack((dx, dy, dz))
    ddR = np.column_stack((ddx, ddy, ddz))
    W = R.T @ dR
    omega = vee(W)
    omega_dot = vee(R.T @ ddR - W @ W)
    return R, omega, omega_dot


@njit(cache=True)
def _unit_with_rates(v, dv, ddv, out_n, out_dn, out_ddn) -> bool:  # pragma: no cover - numba
    r = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if r < _EPS:
        return False
    dr = 0.0
    for i in range(3):
        out_n[i] = v[i] / r
        dr += out_n[i] * dv[i]
    ddr = 0.0
    for i in range(3):
        out_dn[i] = (dv[i] - out_n[i] * dr) / r
        ddr += out_dn[i] * dv[i] + out_n[i] * ddv[i]
    for i in range(3):
        out_ddn[i] = (ddv[i] - 2.0 * out_dn[i] * dr - out_n[i] * ddr) / r
    return True


@njit(cache=True)
def _cross_into(a, b, out, scale: float, add: bool) -> None:  # pragma: no cover - numba
    c0 = a[1] * b[2] - a[2] * b[1]
    c1 = a[2] * b[0] - a[0] * b[2]
    c2 = a[0] * b[1] - a[1] * b[0]
    if add:
        out[0] += scale * c0
        out[1] += scale * c1
        out[2] += scale * c2
    else:
        out[0] = scale * c0
        out[1] = scale * c1
        out[2] = scale * c2


@njit(cache=True)
def _feedforward_kernel(F, dF, ddF, yaw, out) -> int:  # pragma: no cover - numba
    """``out`` (15,) <- R_d (row-major 9), omega_d (3), omega_dot_d (3); status 0 ok,
    1 zero force, 2 thrust axis along the heading."""
    z = np.empty(3)
    dz = np.empty(3)
    ddz = np.empty(3)
    if not _unit_with_rates(F, dF, ddF, z, dz, ddz):
        return 1
    x_C = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    a = np.empty(3)
    da = np.empty(3)
    dda = np.empty(3)
    _cross_into(z, x_C, a, 1.0, False)
    _cross_into(dz, x_C, da, 1.0, False)
    _cross_into(ddz, x_C, dda, 1.0, False)
    y = np.empty(3)
    dy = np.empty(3)
    ddy = np.empty(3)
    if not _unit_with_rates(a, da, dda, y, dy, ddy):
        return 2
    x = np.empty(3)
    dx = np.empty(3)
    ddx = np.empty(3)
    _cross_into(y, z, x, 1.0, False)
    _cross_into(dy, z, dx, 1.0, False)
    _cross_into(y, dz, dx, 1.0, True)
    _cross_into(ddy, z, ddx, 1.0, False)
    _cross_into(dy, dz, ddx, 2.0, True)
    _cross_into(y, ddz, ddx, 1.0, True)
    R = np.empty((3, 3))
    dR = np.empty((3, 3))
    ddR = np.empty((3, 3))
    for i in range(3):
        R[i, 0], R[i, 1], R[i, 2] = x[i], y[i], z[i]
        dR[i, 0], dR[i, 1], dR[i, 2] = dx[i], dy[i], dz[i]
        ddR[i, 0], ddR[i, 1], ddR[i, 2] = ddx[i], ddy[i], ddz[i]
    W = R.T @ dR
    A = R.T @ ddR - W @ W
    for i in range(3):
        for j in range(3):
            out[3 * i + j] = R[i, j]
    # vee of the antisymmetric parts (as tetherland.rotations.vee)
    out[9] = 0.5 * (W[2, 1] - W[1, 2])
    out[10] = 0.5 * (W[0, 2] - W[2, 0])
    out[11] = 0.5 * (W[1, 0] - W[0, 1])
    out[12] = 0.5 * (A[2, 1] - A[1, 2])
    out[13] = 0.5 * (A[0, 2] - A[2, 0])
    out[14] = 0.5 * (A[1, 0] - A[0, 1])
    return 0


def attitude_feedforward_fast(
    F: FloatArray, dF: FloatArray, ddF: FloatArray, yaw: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """:func:`attitude_feedforward`, compiled (same arguments, results and errors)."""
    out = np.empty(15)
    status = _feedforward_kernel(
        np.asarray(F, dtype=float), np.asarray(dF, dtype=float), np.asarray(ddF, dtype=float),
        float(yaw), out,
    )  # fmt: skip
    if status == 1:
        raise SingularityError("desired force is zero: its direction is undefined")
    if status == 2:
        raise SingularityError(
            "z_d x x_C (thrust axis along the heading) is zero: its direction is undefined"
        )
    return out[:9].reshape(3, 3), out[9:12], out[12:15]
