"""Shared pieces of the compiled control laws (numba), each beside its plain counterpart.

- :func:`tmul3`, :func:`mul3_into`: ``A.T @ B``, ``A @ B`` of 3x3 matrices;
- :func:`quat_rotmat3`: :func:`tetherland.rotations.quat_to_rotmat`;
- :func:`rot_y_x_z`: ``rot_y(theta_e) @ rot_x(roll) @ rot_z(psi)`` of
  :mod:`tetherland.control.common`;
- :func:`attitude_torque`: :func:`tetherland.control.attitude.attitude_torque`;
- :func:`cancel_cable_torque`: :func:`cancel_cable_torque_reference`;
- :func:`remainder`: :func:`math.remainder`.

Two packed fields are shared by the laws' ``par``: the attitude law's gains
(:func:`pack_attitude`: J, J k_R, J k_w at ``ATT_*``) and the cable's geometry for the
offset-torque cancellation (:func:`pack_cable`: on or off, r_att, R_WA at ``CABLE_*``);
both copies of each law read them there. tests/test_kernels_control.py checks every
pair to 1e-9 on random inputs.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.control.common import cable_torque
from tetherland.control.kernels.packing import Fields
from tetherland.geometry import FloatArray

_att = Fields()
ATT_J = _att.vector(3)
"""Principal inertia J (F_B) [kg m^2]."""
ATT_J_K_R = _att.vector(3)
"""J k_R: attitude stiffness per axis [N m/rad]."""
ATT_J_K_W = _att.vector(3)
"""J k_w: rate damping per axis [N m s/rad]."""
ATT_WIDTH = _att.width

_cable = Fields()
CABLE_COMPENSATE = _cable.scalar()
"""1: cancel the cable's torque at the attachment offset."""
CABLE_R_ATT = _cable.vector(3)
"""Cable attachment r_att, F_B [m]."""
CABLE_R_WA = _cable.vector(9)
"""Anchor frame R_WA, row-major."""
CABLE_WIDTH = _cable.width


def pack_attitude(inertia: FloatArray, k_R: FloatArray, k_w: FloatArray) -> FloatArray:
    """The attitude field (:data:`ATT_WIDTH`) of principal inertia [kg m^2] and per-axis
    gains k_R [1/s^2], k_w [1/s] (:class:`tetherland.control.attitude.AttitudeGains`)."""
    J = np.asarray(inertia, dtype=float)
    att = np.empty(ATT_WIDTH)
    att[ATT_J], att[ATT_J_K_R], att[ATT_J_K_W] = J, J * k_R, J * k_w
    return att


def pack_cable(compensate: bool, r_att_B: FloatArray, R_WA: FloatArray) -> FloatArray:
    """The cable field (:data:`CABLE_WIDTH`): whether to cancel the cable's torque, the
    attachment r_att in F_B [m] and the anchor frame R_WA."""
    cable = np.empty(CABLE_WIDTH)
    cable[CABLE_COMPENSATE] = float(compensate)
    cable[CABLE_R_ATT] = r_att_B
    cable[CABLE_R_WA] = np.asarray(R_WA, dtype=float).reshape(9)
    return cable


@njit(cache=True)
def tmul3(A: FloatArray, B: FloatArray) -> FloatArray:
    """A^T B of 3x3 matrices (loops: no BLAS call for tiny matrices)."""
    C = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            C[i, j] = A[0, i] * B[0, j] + A[1, i] * B[1, j] + A[2, i] * B[2, j]
    return C


@njit(cache=True)
def mul3_into(A: FloatArray, B: FloatArray, C: FloatArray) -> None:
    """C = A B of 3x3 matrices."""
    for i in range(3):
        for j in range(3):
            C[i, j] = A[i, 0] * B[0, j] + A[i, 1] * B[1, j] + A[i, 2] * B[2, j]


@njit(cache=True)
def quat_rotmat3(q: FloatArray) -> FloatArray:
    """R_WB of a unit quaternion (w, x, y, z) (:func:`tetherland.rotations.quat_to_rotmat`)."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    R = np.empty((3, 3))
    R[0, 0], R[0, 1], R[0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
    R[1, 0], R[1, 1], R[1, 2] = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
    R[2, 0], R[2, 1], R[2, 2] = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
    return R


@njit(cache=True)
def rot_y_x_z(theta_e: float, roll: float, psi: float) -> FloatArray:
    """R_y(theta_e) R_x(roll) R_z(psi) (the attitude parametrisation of control.common)."""
    ct, st = math.cos(theta_e), math.sin(theta_e)
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(psi), math.sin(psi)
    M = np.empty((3, 3))  # R_y R_x
    M[0, 0], M[0, 1], M[0, 2] = ct, st * sr, st * cr
    M[1, 0], M[1, 1], M[1, 2] = 0.0, cr, -sr
    M[2, 0], M[2, 1], M[2, 2] = -st, ct * sr, ct * cr
    R = np.empty((3, 3))
    for i in range(3):
        R[i, 0] = M[i, 0] * cp + M[i, 1] * sp
        R[i, 1] = -M[i, 0] * sp + M[i, 1] * cp
        R[i, 2] = M[i, 2]
    return R


@njit(cache=True)
def attitude_torque(
    R: FloatArray,
    omega: FloatArray,
    R_d: FloatArray,
    omega_d: FloatArray,
    omega_dot_d: FloatArray,
    feedforward: bool,
    att: FloatArray,
) -> tuple[float, float, float]:
    """SO(3) attitude law of :class:`AttitudeController` (Lee et al. 2010), compiled
    :func:`tetherland.control.attitude.attitude_torque`; gains ``att`` (:data:`ATT_WIDTH`),
    feed-forward ``omega_d``, ``omega_dot_d`` (F_B of R_d) used only when ``feedforward``."""
    E = tmul3(R_d, R)
    e0, e1, e2 = 0.5 * (E[2, 1] - E[1, 2]), 0.5 * (E[0, 2] - E[2, 0]), 0.5 * (E[1, 0] - E[0, 1])
    J, kR, kw = att[ATT_J], att[ATT_J_K_R], att[ATT_J_K_W]
    J0, J1, J2 = J[0], J[1], J[2]
    w0, w1, w2 = omega[0], omega[1], omega[2]
    a0, a1, a2 = J0 * w0, J1 * w1, J2 * w2
    t0, t1, t2 = w1 * a2 - w2 * a1, w2 * a0 - w0 * a2, w0 * a1 - w1 * a0  # w x J w
    ew0, ew1, ew2 = w0, w1, w2
    if feedforward:
        M = tmul3(R, R_d)
        d0 = M[0, 0] * omega_d[0] + M[0, 1] * omega_d[1] + M[0, 2] * omega_d[2]
        d1 = M[1, 0] * omega_d[0] + M[1, 1] * omega_d[1] + M[1, 2] * omega_d[2]
        d2 = M[2, 0] * omega_d[0] + M[2, 1] * omega_d[1] + M[2, 2] * omega_d[2]
        ew0, ew1, ew2 = w0 - d0, w1 - d1, w2 - d2
        f0, f1, f2 = w1 * d2 - w2 * d1, w2 * d0 - w0 * d2, w0 * d1 - w1 * d0  # w x w_d
        f0 -= M[0, 0] * omega_dot_d[0] + M[0, 1] * omega_dot_d[1] + M[0, 2] * omega_dot_d[2]
        f1 -= M[1, 0] * omega_dot_d[0] + M[1, 1] * omega_dot_d[1] + M[1, 2] * omega_dot_d[2]
        f2 -= M[2, 0] * omega_dot_d[0] + M[2, 1] * omega_dot_d[1] + M[2, 2] * omega_dot_d[2]
        t0, t1, t2 = t0 - J0 * f0, t1 - J1 * f1, t2 - J2 * f2
    return (
        t0 - kR[0] * e0 - kw[0] * ew0,
        t1 - kR[1] * e1 - kw[1] * ew1,
        t2 - kR[2] * e2 - kw[2] * ew2,
    )


def cancel_cable_torque_reference(
    tau: FloatArray, R: FloatArray, x_L_A: FloatArray, tension: float, cable: FloatArray
) -> FloatArray:
    """tau - r_att x (-f_L d_B), d_B = R^T R_WA x_L the link direction (anchor -> vehicle,
    ``x_L_A`` in F_A) in F_B: the torque that cancels the cable's at the attachment offset
    (docs/theory.md section 7.7; :func:`tetherland.control.common.cable_torque`), when the
    ``cable`` field asks for it and the tension f_L [N] pulls; else ``tau``."""
    if not (cable[CABLE_COMPENSATE] and tension > 0.0):
        return tau
    d_B = R.T @ (cable[CABLE_R_WA].reshape(3, 3) @ x_L_A)
    return tau - cable_torque(cable[CABLE_R_ATT], tension, d_B)


@njit(cache=True)
def cancel_cable_torque(
    t0: float, t1: float, t2: float, R: FloatArray, xa0: float, xa1: float, xa2: float,
    tension: float, cable: FloatArray,
) -> tuple[float, float, float]:  # fmt: skip
    """Compiled :func:`cancel_cable_torque_reference` of tau = (t0, t1, t2) and x_L in F_A
    given as (xa0, xa1, xa2)."""
    if not (cable[CABLE_COMPENSATE] != 0.0 and tension > 0.0):
        return t0, t1, t2
    r_att, R_WA = cable[CABLE_R_ATT], cable[CABLE_R_WA].reshape(3, 3)
    r0, r1, r2 = r_att[0], r_att[1], r_att[2]
    dw = np.empty(3)
    for i in range(3):
        dw[i] = R_WA[i, 0] * xa0 + R_WA[i, 1] * xa1 + R_WA[i, 2] * xa2
    db0 = R[0, 0] * dw[0] + R[1, 0] * dw[1] + R[2, 0] * dw[2]
    db1 = R[0, 1] * dw[0] + R[1, 1] * dw[1] + R[2, 1] * dw[2]
    db2 = R[0, 2] * dw[0] + R[1, 2] * dw[1] + R[2, 2] * dw[2]
    f0, f1, f2 = -tension * db0, -tension * db1, -tension * db2
    return t0 - (r1 * f2 - r2 * f1), t1 - (r2 * f0 - r0 * f2), t2 - (r0 * f1 - r1 * f0)


@njit(cache=True)
def remainder(x: float, y: float) -> float:
    """IEEE remainder x - n y, n the integer nearest x/y (ties to even), as math.remainder."""
    n = round(x / y)  # rounds half to even, like math.remainder
    r = x - n * y
    if abs(r) > 0.5 * y:  # x / y rounded across a tie
        r -= math.copysign(y, r)
    return r
