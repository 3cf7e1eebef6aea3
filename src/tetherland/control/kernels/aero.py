"""The controllers' believed aerodynamics (issue 23), plain and compiled side by side (issue 25).

Two controller wrappers act on every control tick:
:class:`~tetherland.control.rotor_drag.RotorDragCompensation` adds the believed rotor drag
to the reference and :class:`~tetherland.control.ground_effect.GroundEffectCompensation`
divides the rotor speeds by the root of the believed ground-effect factors one motor lag
ahead. Each is one compiled call per tick here, beside its plain form:

- :func:`drag_rows_into` (:func:`drag_rows_reference`, built on
  :func:`drag_acceleration`): the position rows with the drag feed-forward on the
  acceleration and jerk rows;
- :func:`link_drag_into` (:func:`link_drag_acceleration`): the link accelerations that
  cancel the drag of a tethered reference;
- :func:`ground_effect_speeds_into` (:func:`ground_effect_speeds_reference`): the pose one
  motor lag ahead (:func:`predicted_attitude`, :func:`predicted_attitude_reference`), the
  believed factors there (:func:`~tetherland.estimation.ground_effect.
  believed_factors_into`, whose plain form is :func:`~tetherland.models.aero.
  aero_reference`) and the divided speeds.

The drag's parameters are packed once per wrapper (:func:`pack_drag`, fields ``DRAG_*``).

Bits. The plain forms multiply 3x3 matrices by vectors with numpy, which hands them to
BLAS. On this project's machines (OpenBLAS, x86-64 with FMA) ``R @ v`` of a C-ordered R
rounds each row as fma(R_i2, v_2, fma(R_i0, v_0, R_i1 v_1)) and ``R.T @ v`` as the plain
sum left to right; the kernels do the same (:func:`fma`), so that the missions' logs keep
the bits they had with the plain forms. Where a BLAS rounds otherwise, the two agree to
rounding (tests/test_control_aero_kernels.py: exactly where this machine's BLAS rounds
so, to 1e-12 always).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba.core import types
from numba.extending import intrinsic

from tetherland import GRAVITY
from tetherland.control.kernels.packing import Fields
from tetherland.estimation.ground_effect import (
    B_FAR,
    BelievedGroundEffect,
    believed_distance,
    believed_factors_into,
)
from tetherland.geometry import FloatArray, link_frame
from tetherland.models.aero import aero_reference
from tetherland.rotations import SMALL_ANGLE, quat_multiply, rotvec_to_quat

# ------------------------------------------------------------------ drag: the packed drag
_drag = Fields()
DRAG_D = _drag.vector(2)
"""Believed rotor drag (d_x, d_y) at the hover rotor speed [N s/m]."""
DRAG_MASS = _drag.scalar()
"""Believed vehicle mass [kg]."""
DRAG_LENGTH = _drag.scalar()
"""Believed link length l [m] (tethered references)."""
DRAG_R_WA = _drag.vector(9)
"""Believed anchor frame R_WA, row-major (tethered references)."""
DRAG_WIDTH = _drag.width
_D_X, _D_Y = DRAG_D.start, DRAG_D.start + 1  # (the kernels index scalars)


def pack_drag(d_xy: FloatArray, mass: float, length: float, R_WA: FloatArray) -> FloatArray:
    """The drag field (:data:`DRAG_WIDTH`) of the believed rotor drag (d_x, d_y) [N s/m],
    vehicle ``mass`` [kg], link ``length`` [m] and anchor frame ``R_WA``."""
    drag = np.empty(DRAG_WIDTH)
    drag[DRAG_D] = np.asarray(d_xy, dtype=float)
    drag[DRAG_MASS] = mass
    drag[DRAG_LENGTH] = length
    drag[DRAG_R_WA] = np.asarray(R_WA, dtype=float).reshape(9)
    return drag


# ------------------------------------------------------------------ plain forms
def drag_acceleration(
    R_WB: FloatArray, v_W: FloatArray, a_W: FloatArray, d_xy: FloatArray, mass: float
) -> FloatArray:
    """Acceleration [m/s^2] the thrust must add to fly at ``v_W`` [m/s] with acceleration
    ``a_W`` [m/s^2] through the rotor drag diag(d_x, d_y, 0) [N s/m] (at the hover rotor
    speed) of a vehicle of ``mass`` [kg] at attitude ``R_WB``.

    The drag grows with the mean rotor speed, w / w_h = sqrt(f / (m g)) for the thrust
    f = m ||a + g z_W|| that the acceleration needs.
    """
    v_B = R_WB.T @ np.asarray(v_W, dtype=float)
    f_B = np.array([d_xy[0] * v_B[0], d_xy[1] * v_B[1], 0.0])
    a = np.asarray(a_W, dtype=float).copy()
    a[2] += GRAVITY
    scale = math.sqrt(float(np.linalg.norm(a)) / GRAVITY)
    return R_WB @ f_B * (scale / mass)


def drag_rows_reference(
    R_WB: FloatArray, rows: FloatArray, d_xy: FloatArray, mass: float
) -> FloatArray:
    """Position rows (p, v, a, ...) of a reference (k >= 2 rows of F_W vectors) with the
    believed drag as feed-forward at attitude ``R_WB``: the acceleration row (added when
    there is none) gets :func:`drag_acceleration` of the reference velocity, the jerk row
    (if any) its rate along the reference at the present attitude, D a_ref / m
    [m, m/s, m/s^2, ...]."""
    rows = np.asarray(rows, dtype=float)
    a_W = rows[2] if len(rows) > 2 else np.zeros(3)
    a_ff = drag_acceleration(R_WB, rows[1], a_W, d_xy, mass)
    if len(rows) == 2:
        return np.vstack((rows, a_ff))
    rows = rows.copy()
    rows[2] += a_ff
    if len(rows) > 3:  # its rate along the reference (attitude held): D a_ref / m
        rows[3] += drag_acceleration(R_WB, a_W, a_W, d_xy, mass)
    return rows


def link_drag_acceleration(
    R_WB: FloatArray, R_WA: FloatArray, Y: FloatArray, thrust: float, d_xy: FloatArray,
    mass: float, length: float,
) -> tuple[float, float]:  # fmt: skip
    """(phi'', delta'') [rad/s^2] the tethered laws must add to fly the link reference
    ``Y`` (rows y, y' of [phi, delta, ...]) through the rotor drag diag(d_x, d_y, 0)
    [N s/m] at attitude ``R_WB``, for a vehicle of ``mass`` [kg] on a link of ``length``
    [m] whose thrust is ``thrust`` [N] (the rotor-speed scale sqrt(thrust / (m g)); 0 or
    less: the hover speed).

    The centre of mass moves with the link end, v_A = l (cos(delta) phi' z_L - delta' y_L)
    (the attachment offset's own motion is left out); the drag D = -R_WB diag(d) R_WB^T v
    is cancelled across the link by phi'' += -D.z_L / (m l cos(delta)) and
    delta'' += D.y_L / (m l).
    """
    phi, delta = float(Y[0, 0]), float(Y[0, 1])
    R_AL = link_frame(phi, delta)
    cd = math.cos(delta)
    v_W = R_WA @ (length * (cd * float(Y[1, 0]) * R_AL[:, 2] - float(Y[1, 1]) * R_AL[:, 1]))
    scale = math.sqrt(thrust / (mass * GRAVITY)) if thrust > 0.0 else 1.0
    v_B = R_WB.T @ v_W
    D_W = -(R_WB @ np.array([d_xy[0] * v_B[0], d_xy[1] * v_B[1], 0.0])) * scale
    D_L = R_AL.T @ (R_WA.T @ D_W)
    return -float(D_L[2]) / (mass * length * cd), float(D_L[1]) / (mass * length)


def predicted_attitude(q_WB: FloatArray, omega_B: FloatArray, tau: float) -> list[float]:
    """q_WB exp(tau omega_B / 2), normalised, as four floats [-] (scalar form, the same bits
    as :func:`predicted_attitude_reference`; compiled: :func:`predicted_attitude_of`).

    ``omega_B`` in [rad/s], ``tau`` in [s].
    """
    w, x, y, z = np.asarray(q_WB, dtype=float).tolist()
    ox, oy, oz = np.asarray(omega_B, dtype=float).tolist()
    return list(predicted_attitude_of(w, x, y, z, ox, oy, oz, tau))


def predicted_attitude_reference(q_WB: FloatArray, omega_B: FloatArray, tau: float) -> FloatArray:
    """:func:`predicted_attitude` written plainly with the rotation helpers [-]."""
    q = quat_multiply(q_WB, rotvec_to_quat(tau * np.asarray(omega_B, dtype=float)))
    return q / np.linalg.norm(q)


def ground_effect_speeds_reference(
    p_W: FloatArray, v_W: FloatArray, q_WB: FloatArray, omega_B: FloatArray,
    w: FloatArray, tau: float, belief: BelievedGroundEffect,
) -> FloatArray | None:  # fmt: skip
    """Rotor speeds ``w`` [rad/s] divided by the root of the believed factors at the pose
    predicted ``tau`` [s] ahead, (p + tau v, q exp(tau omega / 2)) [rad/s]; None when
    every speed is 0 or the predicted pose is beyond the rotors' reach (the command is
    left as it is). The factors of :func:`~tetherland.models.aero.aero_reference`."""
    w = np.asarray(w, dtype=float)
    p = np.asarray(p_W, dtype=float) + tau * np.asarray(v_W, dtype=float)
    if not w.any() or belief.distance_reference(p) > belief.far:
        return None
    q = predicted_attitude_reference(q_WB, omega_B, tau)
    k = aero_reference(belief.model, np.concatenate((p, q)), np.zeros(3), np.ones(4)).factors
    return w / np.sqrt(k)


# ------------------------------------------------------------------ compiled
@intrinsic
def fma(typingctx, a, b, c):  # type: ignore[no-untyped-def]
    """a b + c rounded once (IEEE fused multiply-add; compiled code only)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):  # type: ignore[no-untyped-def]
        return builder.fma(*args)

    return sig, codegen


@njit(cache=True)
def predicted_attitude_of(w: float, x: float, y: float, z: float, ox: float, oy: float,
                        oz: float, tau: float) -> tuple[float, float, float, float]:  # fmt: skip
    """:func:`predicted_attitude` compiled: q exp(tau omega / 2), normalised, of
    q = (w, x, y, z) [-], omega = (ox, oy, oz) [rad/s], ``tau`` [s]."""
    ax, ay, az = tau * ox, tau * oy, tau * oz
    angle = math.sqrt(ax * ax + ay * ay + az * az)  # (np.linalg.norm's bits: a test checks)
    if angle < SMALL_ANGLE:
        bw, bx, by, bz = 1.0, 0.5 * ax, 0.5 * ay, 0.5 * az
        n = math.sqrt(bw * bw + bx * bx + by * by + bz * bz)
        bw, bx, by, bz = bw / n, bx / n, by / n, bz / n
    else:
        s = math.sin(0.5 * angle)
        bw, bx, by, bz = math.cos(0.5 * angle), s * (ax / angle), s * (ay / angle), s * (az / angle)
    qw = w * bw - x * bx - y * by - z * bz
    qx = w * bx + x * bw + y * bz - z * by
    qy = w * by - x * bz + y * bw + z * bx
    qz = w * bz + x * by - y * bx + z * bw
    n = math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    return qw / n, qx / n, qy / n, qz / n


@njit(cache=True)
def ground_effect_speeds_into(p_W: FloatArray, v_W: FloatArray, q_WB: FloatArray,
                              omega_B: FloatArray, w: FloatArray, tau: float,
                              believed: FloatArray, out: FloatArray) -> bool:  # fmt: skip
    """:func:`ground_effect_speeds_reference` compiled, on the packed belief ``believed``
    (:func:`~tetherland.estimation.ground_effect.pack_believed`): the divided speeds into
    ``out`` (4,) [rad/s]; False (``out`` not written) where the reference gives None."""
    if not (w[0] != 0.0 or w[1] != 0.0 or w[2] != 0.0 or w[3] != 0.0):  # (not w.any())
        return False
    px, py, pz = p_W[0] + tau * v_W[0], p_W[1] + tau * v_W[1], p_W[2] + tau * v_W[2]
    if believed_distance(px, py, pz, believed) > believed[B_FAR]:
        return False  # every believed factor is 1: the command as it is
    qw, qx, qy, qz = predicted_attitude_of(
        q_WB[0], q_WB[1], q_WB[2], q_WB[3], omega_B[0], omega_B[1], omega_B[2], tau
    )
    k = np.empty(4)
    believed_factors_into(px, py, pz, qw, qx, qy, qz, believed, k)
    for i in range(4):
        out[i] = w[i] / math.sqrt(k[i])
    return True


@njit(cache=True, inline="always")
def _rotmat(q: FloatArray) -> tuple[float, float, float, float, float, float, float, float,
                                     float]:  # fmt: skip
    """R_WB of a unit quaternion (w, x, y, z), row-major, with the bits of
    :func:`tetherland.rotations.quat_to_rotmat`."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    return (
        1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y),
    )  # fmt: skip


@njit(cache=True)
def _drag_into(R: FloatArray, vx: float, vy: float, vz: float, ax: float, ay: float,
               az: float, drag: FloatArray, out: FloatArray) -> None:  # fmt: skip
    """:func:`drag_acceleration` of the velocity (vx, vy, vz) and acceleration (ax, ay, az)
    at the attitude R (9, row-major), added to ``out`` (3,) [m/s^2]."""
    # v_B = R^T v (x and y)
    bx = R[0] * vx + R[3] * vy + R[6] * vz
    by = R[1] * vx + R[4] * vy + R[7] * vz
    fx, fy = drag[_D_X] * bx, drag[_D_Y] * by
    az = az + GRAVITY
    k = math.sqrt(math.sqrt(ax * ax + ay * ay + az * az) / GRAVITY) / drag[DRAG_MASS]
    for i in range(3):  # R f_B, f_B = (fx, fy, 0)
        out[i] = out[i] + fma(R[3 * i + 2], 0.0, fma(R[3 * i], fx, R[3 * i + 1] * fy)) * k


@njit(cache=True)
def drag_rows_into(q_WB: FloatArray, rows: FloatArray, drag: FloatArray,
                   out: FloatArray) -> None:  # fmt: skip
    """:func:`drag_rows_reference` compiled, at the attitude ``q_WB`` (unit quaternion),
    on the packed ``drag`` (:func:`pack_drag`): the rows into ``out``
    (max(k, 3), 3) [m, m/s, m/s^2, ...]."""
    R = np.empty(9)
    R[0], R[1], R[2], R[3], R[4], R[5], R[6], R[7], R[8] = _rotmat(q_WB)
    n = rows.shape[0]
    for r in range(n):
        for c in range(3):
            out[r, c] = rows[r, c]
    ax = ay = az = 0.0
    if n > 2:
        ax, ay, az = rows[2, 0], rows[2, 1], rows[2, 2]
    else:  # the acceleration row is the feed-forward itself (as numpy's vstack)
        out[2, 0] = out[2, 1] = out[2, 2] = -0.0  # (-0.0 + x is x, bit for bit)
    _drag_into(R, rows[1, 0], rows[1, 1], rows[1, 2], ax, ay, az, drag, out[2])
    if n > 3:  # its rate along the reference (attitude held): D a_ref / m
        _drag_into(R, ax, ay, az, ax, ay, az, drag, out[3])


@njit(cache=True)
def link_drag_into(q_WB: FloatArray, Y: FloatArray, thrust: float,
                   drag: FloatArray) -> tuple[float, float]:  # fmt: skip
    """:func:`link_drag_acceleration` compiled, at the attitude ``q_WB`` (unit quaternion),
    on the packed ``drag`` (:func:`pack_drag`) [rad/s^2]."""
    R = np.empty(9)
    R[0], R[1], R[2], R[3], R[4], R[5], R[6], R[7], R[8] = _rotmat(q_WB)
    A = drag[DRAG_R_WA]
    m, length = drag[DRAG_MASS], drag[DRAG_LENGTH]
    phi, delta = Y[0, 0], Y[0, 1]
    # R_AL = link_frame(phi, delta): columns y_L = (cp sd, cd, sp sd), z_L = (-sp, 0, cp)
    cp, sp, cd, sd = math.cos(phi), math.sin(phi), math.cos(delta), math.sin(delta)
    yx, yy, yz = cp * sd, cd, sp * sd
    zx, zy, zz = -sp, 0.0, cp
    c1, c2 = cd * Y[1, 0], Y[1, 1]
    lx = length * (c1 * zx - c2 * yx)
    ly = length * (c1 * zy - c2 * yy)
    lz = length * (c1 * zz - c2 * yz)
    # v_W = R_WA l (...)
    vx = fma(A[2], lz, fma(A[0], lx, A[1] * ly))
    vy = fma(A[5], lz, fma(A[3], lx, A[4] * ly))
    vz = fma(A[8], lz, fma(A[6], lx, A[7] * ly))
    scale = math.sqrt(thrust / (m * GRAVITY)) if thrust > 0.0 else 1.0
    bx = R[0] * vx + R[3] * vy + R[6] * vz  # v_B = R_WB^T v_W (x and y)
    by = R[1] * vx + R[4] * vy + R[7] * vz
    fx, fy = drag[_D_X] * bx, drag[_D_Y] * by
    # D_W = -(R_WB f_B) scale
    dx = -fma(R[2], 0.0, fma(R[0], fx, R[1] * fy)) * scale
    dy = -fma(R[5], 0.0, fma(R[3], fx, R[4] * fy)) * scale
    dz = -fma(R[8], 0.0, fma(R[6], fx, R[7] * fy)) * scale
    # D_L = R_AL^T R_WA^T D_W (its y and z)
    ux = A[0] * dx + A[3] * dy + A[6] * dz
    uy = A[1] * dx + A[4] * dy + A[7] * dz
    uz = A[2] * dx + A[5] * dy + A[8] * dz
    d_y = yx * ux + yy * uy + yz * uz
    d_z = zx * ux + zy * uy + zz * uz
    return -d_z / (m * length * cd), d_y / (m * length)
