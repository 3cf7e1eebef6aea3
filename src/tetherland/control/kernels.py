"""Compiled control laws: one call per control tick, over flat arrays (numba).

Each kernel computes a whole controller update, mixer included, and writes it into a
fresh ``out`` array; the controller classes (:class:`FreeFlightController`,
:class:`HierarchicalController`, :class:`DflController`, :class:`Mixer`) keep their
public interfaces and only pack inputs and unpack results. Beside every kernel sits its
plain reference (``*_reference``): the same update written with the readable pieces
(:func:`tetherland.control.attitude.attitude_error`,
:func:`tetherland.rotations.rotation_from_z_and_yaw`, :meth:`RotorLayout.allocate`,
:func:`tetherland.geometry.link_frame`, ...), with the same packed arguments (the mixer's
reference takes the :class:`RotorLayout` and :class:`RotorModel` themselves). A property
test checks each pair to 1e-9 on random inputs. The DFL law is in
:mod:`tetherland.control.dfl_kernels`.

Packed arguments (``pack_*`` build them once per controller):

- ``mix`` (:data:`MIX_WIDTH`): allocation Gamma (4x4) and its inverse (row-major), f_min,
  f_max, c_f, tau_m, w_min, w_max; see :func:`mix_into` (6.19 and docs/theory.md section 4);
- ``par``: gains and model of each controller (``FF_*``, ``HC_*`` offsets below);
- ``state``: the controller's memory (integrals, last regular attitude), updated in place.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from tetherland.control.attitude import attitude_error
from tetherland.control.common import attitude_from_thrust_axis, cable_torque, heading_of
from tetherland.errors import SingularityError
from tetherland.geometry import FloatArray, link_frame, theta_A_from_z_B
from tetherland.models.quadrotor import RotorLayout, RotorModel, Saturation
from tetherland.models.tethered import COS_DELTA_MIN
from tetherland.rotations import cross3, quat_to_rotmat, rotation_from_z_and_yaw

if TYPE_CHECKING:
    from tetherland.control.hierarchical import HierarchicalController
    from tetherland.control.position import PositionController

_BOUND_TOL = 1e-12  # as models.quadrotor
YAW_SINGULAR_NORM = 1e-9
"""|z_B,d x x_C| below which the heading is undefined (as rotation_from_z_and_yaw)."""
U_Z_MIN_FRACTION = 0.02
"""u_z below this fraction of m g counts as singular (the thrust must push across the link)."""
COS_SUM_MIN = 0.02
"""|cos(phi + theta_A,d)| below this is singular (thrust axis along the link)."""
_SATURATION_LEVEL = {s: float(i) for i, s in enumerate(Saturation)}  # 0 none ... 3 thrust

# ------------------------------------------------------------------ packed layouts
MIX_WIDTH = 38
MIX_G, MIX_GI = slice(0, 16), slice(16, 32)
MIX_F_MIN, MIX_F_MAX, MIX_C_F, MIX_TAU, MIX_W_MIN, MIX_W_MAX = 32, 33, 34, 35, 36, 37

# mixer result inside every ``out``: rotor speeds, achieved wrench, saturation level
OUT_SPEEDS, OUT_WRENCH, OUT_SATURATION = slice(0, 4), slice(4, 8), 8

FF_WIDTH = 17
"""mass, g, k_x, k_v, k_i, integral bound, tan(max tilt), min vertical, J, J k_R, J k_w."""
FF_OUT_WIDTH = 14  # mixer (9), limited, singular, e_x (3)
FF_LIMITED, FF_SINGULAR, FF_E_X = 9, 10, slice(11, 14)

HC_WIDTH = 29
"""m, l, g, k_p, k_d, k_i, integral max, compensate, r_att, R_WA (9), J, J k_R, J k_w."""
HC_STATE_WIDTH = 14  # integral (2), t_last (NaN: none), last f_R, has last R_d, last R_d (9)
HC_OUT_WIDTH = 16
"""mixer (9), singular, margin, e_phi, e_delta, e_theta_A, e_psi, theta_A undefined."""
HC_SINGULAR, HC_MARGIN, HC_ERRORS, HC_THETA_UNDEFINED = 9, 10, slice(11, 15), 15


def pack_mixer(layout: RotorLayout, rotors: RotorModel) -> FloatArray:
    """``mix`` for :func:`mix_into`."""
    limits = [layout.f_min, layout.f_max, rotors.thrust_coefficient, rotors.time_constant,
              rotors.w_min, rotors.w_max]  # fmt: skip
    G, Gi = layout.allocation.reshape(16), layout.allocation_inverse.reshape(16)
    return np.concatenate((G, Gi, limits)).astype(float)


# ================================================================== mixer (6.19)


def mix_reference(
    wrench: FloatArray, rates: FloatArray | None, layout: RotorLayout, rotors: RotorModel
) -> FloatArray:
    """Allocation with priority saturation then speed commands (:meth:`RotorLayout.allocate`,
    :meth:`RotorModel.speed_command`): [speeds (4), achieved wrench (4), saturation level]."""
    alloc = layout.allocate(wrench)
    speeds = rotors.speed_command(alloc.thrusts, rates)
    return np.concatenate((speeds, alloc.wrench, [_SATURATION_LEVEL[alloc.saturation]]))


@njit(cache=True)
def _feasible(a: FloatArray, b: FloatArray, lo: float, hi: float) -> tuple[bool, float, float]:
    """(exists, s_min, s_max) of {s: lo <= a + s b <= hi} (as models.quadrotor)."""
    s_min, s_max = -math.inf, math.inf
    for i in range(4):
        ai, bi = a[i], b[i]
        if abs(bi) < 1e-15:
            if ai < lo - _BOUND_TOL or ai > hi + _BOUND_TOL:
                return False, s_min, s_max
            continue
        s1, s2 = (lo - ai) / bi, (hi - ai) / bi
        s_min, s_max = max(s_min, min(s1, s2)), min(s_max, max(s1, s2))
    return not s_min > s_max + _BOUND_TOL, s_min, s_max


@njit(cache=True)
def mix_into(
    f_R: float,
    tx: float,
    ty: float,
    tz: float,
    rates: FloatArray,
    use_rates: bool,
    mix: FloatArray,
    out: FloatArray,
) -> None:
    """Compiled :func:`mix_reference` of the wrench (f_R, tau) into ``out[0:9]``; the thrust
    rates [N/s] enter only when ``use_rates``."""
    Gi = mix[MIX_GI].reshape(4, 4)
    G = mix[MIX_G].reshape(4, 4)
    lo, hi = mix[MIX_F_MIN], mix[MIX_F_MAX]
    w = np.array([f_R, tx, ty, tz])
    f = np.empty(4)
    f_lo, f_hi = math.inf, -math.inf
    for i in range(4):
        f[i] = Gi[i, 0] * w[0] + Gi[i, 1] * w[1] + Gi[i, 2] * w[2] + Gi[i, 3] * w[3]
        f_lo, f_hi = min(f_lo, f[i]), max(f_hi, f[i])
    if f_lo >= lo - _BOUND_TOL and f_hi <= hi + _BOUND_TOL:  # the common case
        level = 0.0
        for i in range(4):
            out[4 + i] = w[i]
    else:
        base = np.empty(4)
        d = np.empty(4)
        for i in range(4):  # 1. keep f_R, tau_x, tau_y; scale tau_z by s in [0, 1]
            base[i] = Gi[i, 0] * w[0] + Gi[i, 1] * w[1] + Gi[i, 2] * w[2]
            d[i] = Gi[i, 3] * w[3]
        ok, s0, s1 = _feasible(base, d, lo, hi)
        if ok and s0 <= 1.0 and s1 >= 0.0:
            level = 1.0
        else:  # 2. keep f_R; scale (tau_x, tau_y) by s in [0, 1], no yaw
            for i in range(4):
                base[i] = Gi[i, 0] * w[0]
                d[i] = Gi[i, 1] * w[1] + Gi[i, 2] * w[2]
            ok, s0, s1 = _feasible(base, d, lo, hi)
            if ok and s0 <= 1.0 and s1 >= 0.0:
                level = 2.0
            else:  # 3. clip the total thrust, no torque
                level = 3.0
                f_c = min(max(w[0], 4.0 * lo), 4.0 * hi)
                for i in range(4):
                    base[i] = Gi[i, 0] * f_c
                    d[i] = 0.0
                s1 = 0.0
        s = min(1.0, s1)
        for i in range(4):
            f[i] = base[i] + s * d[i]
        for i in range(4):
            f[i] = min(max(f[i], lo), hi)
        for r in range(4):
            out[4 + r] = G[r, 0] * f[0] + G[r, 1] * f[1] + G[r, 2] * f[2] + G[r, 3] * f[3]
    out[OUT_SATURATION] = level
    c_f, tau = mix[MIX_C_F], mix[MIX_TAU]
    w_min, w_max = mix[MIX_W_MIN], mix[MIX_W_MAX]
    lead = use_rates and tau > 0.0
    for i in range(4):
        fi = min(max(f[i], lo), hi)
        wi = math.sqrt(fi / c_f)
        if lead:  # w_cmd = w + tau_m f'/(2 c_f w), limited
            wi = min(max(wi + tau * rates[i] / (2.0 * c_f * wi), w_min), w_max)
        out[i] = wi


# ================================================================== shared scalar pieces


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
def _attitude_torque(
    R: FloatArray,
    omega: FloatArray,
    R_d: FloatArray,
    omega_d: FloatArray,
    omega_dot_d: FloatArray,
    feedforward: bool,
    par: FloatArray,
    j0: int,
) -> tuple[float, float, float]:
    """SO(3) attitude law of :class:`AttitudeController` (Lee et al. 2010); J, J k_R, J k_w
    at par[j0 : j0 + 9]."""
    E = tmul3(R_d, R)
    e0, e1, e2 = 0.5 * (E[2, 1] - E[1, 2]), 0.5 * (E[0, 2] - E[2, 0]), 0.5 * (E[1, 0] - E[0, 1])
    J0, J1, J2 = par[j0], par[j0 + 1], par[j0 + 2]
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
        t0 - par[j0 + 3] * e0 - par[j0 + 6] * ew0,
        t1 - par[j0 + 4] * e1 - par[j0 + 7] * ew1,
        t2 - par[j0 + 5] * e2 - par[j0 + 8] * ew2,
    )


# ================================================================== free flight


def pack_free_flight(position: PositionController) -> FloatArray:
    """``par`` of :func:`free_flight_into` from a :class:`PositionController`."""
    att = position.attitude
    bound = position.integral_max / (position.mass * position.k_i) if position.k_i > 0 else 0.0
    gains = [position.mass, position.g, position.k_x, position.k_v, position.k_i, bound,
             position.tan_max_tilt, position.min_vertical]  # fmt: skip
    return np.concatenate((gains, att.J, att.J * att.gains.k_R, att.J * att.gains.k_w))


def free_flight_reference(
    p_W: FloatArray,
    v_W: FloatArray,
    q_WB: FloatArray,
    omega_B: FloatArray,
    ref: FloatArray,
    yaw: float,
    dt: float,
    integral: FloatArray,
    par: FloatArray,
    layout: RotorLayout,
    rotors: RotorModel,
) -> FloatArray:
    """Free-flight position + attitude control and mixer (Lee et al. 2010), plain.

    F_d = m (a_d - k_x e_x - k_v e_v) - m k_i int(e_x) + m g z_W, limited in tilt and
    vertical thrust; f_R = F_d . z_B; R_d from (F_d, psi_d); tau from the SO(3) law.
    ``ref`` rows (p, v, a), the first k given; ``dt`` NaN: no integration. ``integral``
    (int e_x [m s]) is updated in place. Returns ``out`` (:data:`FF_OUT_WIDTH`).
    """
    m, g, k_x, k_v, k_i, bound, tan_max, min_vertical = par[0:8]
    J, JkR, Jkw = par[8:11], par[11:14], par[14:17]
    zero = np.zeros(3)
    p_d, v_d, a_d = (ref[i] if ref.shape[0] > i else zero for i in range(3))
    e_x, e_v = p_W - p_d, v_W - v_d
    F = m * (a_d - k_x * e_x - k_v * e_v) - m * k_i * integral
    F[2] += m * g
    limited = False
    if F[2] < min_vertical:
        F[2] = min_vertical
        limited = True
    horiz, max_horiz = math.hypot(F[0], F[1]), F[2] * tan_max
    if horiz > max_horiz:
        F[0:2] *= max_horiz / horiz
        limited = True
    if not math.isnan(dt) and k_i > 0.0 and not limited:
        np.clip(integral + e_x * dt, -bound, bound, out=integral)
    out = np.zeros(FF_OUT_WIDTH)
    out[FF_LIMITED], out[FF_E_X] = float(limited), e_x
    R = quat_to_rotmat(q_WB)
    try:
        R_d = rotation_from_z_and_yaw(F, yaw)
    except SingularityError:
        out[FF_SINGULAR] = 1.0
        return out
    e_R = attitude_error(R, R_d)
    tau = cross3(omega_B, J * omega_B) - JkR * e_R - Jkw * omega_B
    out[0:9] = mix_reference(np.concatenate(([F @ R[:, 2]], tau)), None, layout, rotors)
    return out


@njit(cache=True)
def free_flight_into(
    p_W: FloatArray,
    v_W: FloatArray,
    q_WB: FloatArray,
    omega_B: FloatArray,
    ref: FloatArray,
    yaw: float,
    dt: float,
    integral: FloatArray,
    par: FloatArray,
    mix: FloatArray,
    out: FloatArray,
) -> None:
    """Compiled :func:`free_flight_reference` (``integral`` in place, result in ``out``)."""
    m, g, k_x, k_v, k_i = par[0], par[1], par[2], par[3], par[4]
    k = ref.shape[0]
    F = np.empty(3)
    for i in range(3):
        e = p_W[i] - ref[0, i]
        out[11 + i] = e
        ev = v_W[i] - (ref[1, i] if k > 1 else 0.0)
        a = ref[2, i] if k > 2 else 0.0
        F[i] = m * (a - k_x * e - k_v * ev) - m * k_i * integral[i]
    F[2] += m * g
    limited = False
    if F[2] < par[7]:
        F[2] = par[7]
        limited = True
    horiz, max_horiz = math.hypot(F[0], F[1]), F[2] * par[6]
    if horiz > max_horiz:
        F[0] *= max_horiz / horiz
        F[1] *= max_horiz / horiz
        limited = True
    if dt == dt and k_i > 0.0 and not limited:
        bound = par[5]
        for i in range(3):
            integral[i] = min(max(integral[i] + out[11 + i] * dt, -bound), bound)
    out[FF_LIMITED] = 1.0 if limited else 0.0
    # R_d from (z_B,d, psi): y = z x x_C / ||.||, x = y x z (rotation_from_z_and_yaw)
    n = math.sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2])
    zx, zy, zz = F[0] / n, F[1] / n, F[2] / n
    cx, cy = math.cos(yaw), math.sin(yaw)
    yx, yy, yz = -zz * cy, zz * cx, zx * cy - zy * cx
    n = math.sqrt(yx * yx + yy * yy + yz * yz)
    if n < YAW_SINGULAR_NORM:
        out[FF_SINGULAR] = 1.0
        return
    out[FF_SINGULAR] = 0.0
    yx, yy, yz = yx / n, yy / n, yz / n
    R_d = np.empty((3, 3))
    R_d[0, 0], R_d[1, 0], R_d[2, 0] = yy * zz - yz * zy, yz * zx - yx * zz, yx * zy - yy * zx
    R_d[0, 1], R_d[1, 1], R_d[2, 1] = yx, yy, yz
    R_d[0, 2], R_d[1, 2], R_d[2, 2] = zx, zy, zz
    R = quat_rotmat3(q_WB)
    thrust = F[0] * R[0, 2] + F[1] * R[1, 2] + F[2] * R[2, 2]
    t0, t1, t2 = _attitude_torque(R, omega_B, R_d, omega_B, omega_B, False, par, 8)
    mix_into(thrust, t0, t1, t2, F, False, mix, out)


@njit(cache=True)
def cancel_cable_torque(
    t0: float, t1: float, t2: float, R: FloatArray, R_WA: FloatArray,
    xa0: float, xa1: float, xa2: float, tension: float, r0: float, r1: float, r2: float,
) -> tuple[float, float, float]:  # fmt: skip
    """tau - r_att x (-f_L d_B), d_B = R^T R_WA x_L (the link direction x_L in F_A given as
    (xa0, xa1, xa2), in F_B): the torque that cancels the cable's at the attachment offset
    (docs/theory.md section 7.7; :func:`tetherland.control.common.cable_torque`)."""
    dw = np.empty(3)
    for i in range(3):
        dw[i] = R_WA[i, 0] * xa0 + R_WA[i, 1] * xa1 + R_WA[i, 2] * xa2
    db0 = R[0, 0] * dw[0] + R[1, 0] * dw[1] + R[2, 0] * dw[2]
    db1 = R[0, 1] * dw[0] + R[1, 1] * dw[1] + R[2, 1] * dw[2]
    db2 = R[0, 2] * dw[0] + R[1, 2] * dw[1] + R[2, 2] * dw[2]
    f0, f1, f2 = -tension * db0, -tension * db1, -tension * db2
    return t0 - (r1 * f2 - r2 * f1), t1 - (r2 * f0 - r0 * f2), t2 - (r0 * f1 - r1 * f0)


# ================================================================== hierarchical


def pack_hierarchical(ctrl: HierarchicalController) -> FloatArray:
    """``par`` of :func:`hierarchical_into` from a :class:`HierarchicalController`."""
    att = ctrl.attitude
    gains = [ctrl.mass, ctrl.length, ctrl.g, ctrl.k_p, ctrl.k_d, ctrl.k_i, ctrl.integral_max,
             float(ctrl.compensate_offset)]  # fmt: skip
    R_WA = np.asarray(ctrl.R_WA, dtype=float).reshape(9)
    return np.concatenate(
        (gains, ctrl.r_att_B, R_WA, att.J, att.J * att.gains.k_R, att.J * att.gains.k_w)
    )


def hierarchical_state(mass: float, g: float) -> FloatArray:
    """A reset ``state`` of :func:`hierarchical_into`: no integral, no last attitude."""
    s = np.zeros(HC_STATE_WIDTH)
    s[2], s[3] = math.nan, mass * g
    return s


def hierarchical_reference(
    t: float,
    link: FloatArray,
    q_WB: FloatArray,
    omega_B: FloatArray,
    Y: FloatArray,
    ff_omega: FloatArray,
    ff_omega_dot: FloatArray,
    feedforward: bool,
    tension: float,
    state: FloatArray,
    par: FloatArray,
    layout: RotorLayout,
    rotors: RotorModel,
) -> FloatArray:
    """Gamma_HC^b (docs/theory.md section 7, chapter 4.5.2), plain; see
    :mod:`tetherland.control.hierarchical` for the equations. ``link`` = [phi, delta,
    phi', delta'], ``Y`` rows y_d, y_d', y_d'' (the first k given), ``state`` updated in
    place. Returns ``out`` (:data:`HC_OUT_WIDTH`)."""
    m, l, g, k_p, k_d, k_i, integral_max, compensate = par[0:8]
    r_att, R_WA = par[8:11], par[11:20].reshape(3, 3)
    J, JkR, Jkw = par[20:23], par[23:26], par[26:29]
    phi, delta, dphi, ddelta = link
    yd = Y[0]
    yd1 = Y[1] if Y.shape[0] > 1 else np.zeros(4)
    yd2 = Y[2] if Y.shape[0] > 2 else np.zeros(4)
    if not math.isnan(state[2]) and k_i > 0.0:
        bound, dt = integral_max / k_i, t - state[2]
        state[0] = min(max(state[0] + (yd[0] - phi) * dt, -bound), bound)
        state[1] = min(max(state[1] + (yd[1] - delta) * dt, -bound), bound)
    state[2] = t
    v_phi = yd2[0] + k_d * (yd1[0] - dphi) + k_p * (yd[0] - phi) + k_i * state[0]
    v_delta = yd2[1] + k_d * (yd1[1] - ddelta) + k_p * (yd[1] - delta) + k_i * state[1]
    cp, sp, cd, sd = math.cos(phi), math.sin(phi), math.cos(delta), math.sin(delta)
    u_z = m * l * (cd * v_phi - 2.0 * sd * dphi * ddelta) + m * g * cp
    u_y = m * g * sp * sd - m * l * (v_delta + 0.5 * math.sin(2.0 * delta) * dphi * dphi)
    cos_sum = math.cos(phi + yd[2])
    margin = min(abs(cd) / 0.1, u_z / (U_Z_MIN_FRACTION * m * g), abs(cos_sum) / COS_SUM_MIN)
    R = quat_to_rotmat(q_WB)
    singular = abs(cd) < COS_DELTA_MIN or u_z < U_Z_MIN_FRACTION * m * g or abs(
        cos_sum) < COS_SUM_MIN  # fmt: skip
    if not singular:
        u_x = u_z * math.tan(phi + yd[2]) / cd
        F_A = link_frame(phi, delta) @ np.array([u_x, u_y, u_z])
        F_norm = float(np.linalg.norm(F_A))
        singular = F_norm < 1e-6 * m * g
    if singular:
        R_d = state[5:14].reshape(3, 3) if state[4] else R
        f_R = state[3]
    else:
        R_d = R_WA @ attitude_from_thrust_axis(F_A / F_norm, yd[3])
        f_R = float((R_WA @ F_A) @ R[:, 2])
        state[3], state[4], state[5:14] = f_R, 1.0, R_d.reshape(9)
    e_R = attitude_error(R, R_d)
    tau = cross3(omega_B, J * omega_B)
    e_w = omega_B
    if feedforward:
        w_d_B = R.T @ R_d @ ff_omega
        e_w = omega_B - w_d_B
        tau = tau - J * (cross3(omega_B, w_d_B) - R.T @ R_d @ ff_omega_dot)
    tau = tau - JkR * e_R - Jkw * e_w
    if compensate and tension > 0.0:
        d_B = R.T @ (R_WA @ link_frame(phi, delta)[:, 0])
        tau = tau - cable_torque(r_att, tension, d_B)
    out = np.zeros(HC_OUT_WIDTH)
    out[0:9] = mix_reference(np.concatenate(([max(f_R, 0.0)], tau)), None, layout, rotors)
    try:
        theta_A = theta_A_from_z_B(R_WA.T @ R[:, 2], phi, delta)
    except SingularityError:
        theta_A, out[HC_THETA_UNDEFINED] = math.nan, 1.0
    psi = heading_of(R_WA.T @ R)
    out[HC_SINGULAR], out[HC_MARGIN] = float(singular), margin
    out[HC_ERRORS] = [yd[0] - phi, yd[1] - delta, yd[2] - theta_A,
                      math.remainder(yd[3] - psi, 2.0 * math.pi)]  # fmt: skip
    return out


@njit(cache=True)
def _rot_y_x_z(theta_e: float, roll: float, psi: float) -> FloatArray:
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
def hierarchical_into(
    t: float,
    link: FloatArray,
    q_WB: FloatArray,
    omega_B: FloatArray,
    Y: FloatArray,
    ff_omega: FloatArray,
    ff_omega_dot: FloatArray,
    feedforward: bool,
    tension: float,
    state: FloatArray,
    par: FloatArray,
    mix: FloatArray,
    out: FloatArray,
) -> None:
    """Compiled :func:`hierarchical_reference` (``state`` in place, result in ``out``)."""
    m, l, g, k_p, k_d, k_i = par[0], par[1], par[2], par[3], par[4], par[5]
    R_WA = par[11:20].reshape(3, 3)
    phi, delta, dphi, ddelta = link[0], link[1], link[2], link[3]
    k = Y.shape[0]
    y0, y1, y2, y3 = Y[0, 0], Y[0, 1], Y[0, 2], Y[0, 3]
    yd1_0, yd1_1 = (Y[1, 0], Y[1, 1]) if k > 1 else (0.0, 0.0)
    yd2_0, yd2_1 = (Y[2, 0], Y[2, 1]) if k > 2 else (0.0, 0.0)
    if state[2] == state[2] and k_i > 0.0:
        bound, dt = par[6] / k_i, t - state[2]
        state[0] = min(max(state[0] + (y0 - phi) * dt, -bound), bound)
        state[1] = min(max(state[1] + (y1 - delta) * dt, -bound), bound)
    state[2] = t
    v_phi = yd2_0 + k_d * (yd1_0 - dphi) + k_p * (y0 - phi) + k_i * state[0]
    v_delta = yd2_1 + k_d * (yd1_1 - ddelta) + k_p * (y1 - delta) + k_i * state[1]
    cp, sp, cd, sd = math.cos(phi), math.sin(phi), math.cos(delta), math.sin(delta)
    u_z = m * l * (cd * v_phi - 2.0 * sd * dphi * ddelta) + m * g * cp
    u_y = m * g * sp * sd - m * l * (v_delta + 0.5 * math.sin(2.0 * delta) * dphi * dphi)
    cos_sum = math.cos(phi + y2)
    margin = min(abs(cd) / 0.1, u_z / (U_Z_MIN_FRACTION * m * g), abs(cos_sum) / COS_SUM_MIN)
    R = quat_rotmat3(q_WB)
    singular = abs(cd) < COS_DELTA_MIN or u_z < U_Z_MIN_FRACTION * m * g or abs(
        cos_sum) < COS_SUM_MIN  # fmt: skip
    F0 = F1 = F2 = F_norm = 0.0
    if not singular:
        u_x = u_z * math.tan(phi + y2) / cd
        # F_A = R_AL [u_x, u_y, u_z], R_AL = link_frame(phi, delta)
        F0 = cd * cp * u_x + cp * sd * u_y - sp * u_z
        F1 = -sd * u_x + cd * u_y
        F2 = cd * sp * u_x + sp * sd * u_y + cp * u_z
        F_norm = math.sqrt(F0 * F0 + F1 * F1 + F2 * F2)
        singular = F_norm < 1e-6 * m * g
    R_d = np.empty((3, 3))
    if singular:
        if state[4] != 0.0:
            for i in range(9):
                R_d[i // 3, i % 3] = state[5 + i]
        else:
            for i in range(9):
                R_d[i // 3, i % 3] = R[i // 3, i % 3]
        f_R = state[3]
    else:
        zx, zy, zz = F0 / F_norm, F1 / F_norm, F2 / F_norm  # attitude_from_thrust_axis
        R_AB = _rot_y_x_z(math.atan2(zx, zz), math.atan2(-zy, math.hypot(zx, zz)), y3)
        mul3_into(R_WA, R_AB, R_d)
        f_R = 0.0
        for i in range(3):
            f_R += (R_WA[i, 0] * F0 + R_WA[i, 1] * F1 + R_WA[i, 2] * F2) * R[i, 2]
        state[3], state[4] = f_R, 1.0
        for i in range(9):
            state[5 + i] = R_d[i // 3, i % 3]
    t0, t1, t2 = _attitude_torque(R, omega_B, R_d, ff_omega, ff_omega_dot, feedforward, par, 20)
    if par[7] != 0.0 and tension > 0.0:
        t0, t1, t2 = cancel_cable_torque(
            t0, t1, t2, R, R_WA, cd * cp, -sd, cd * sp, tension, par[8], par[9], par[10]
        )
    mix_into(max(f_R, 0.0), t0, t1, t2, omega_B, False, mix, out)
    # diagnostics: theta_A of the actual z_B (geometry.theta_A_from_z_B) and heading psi
    R_AB = tmul3(R_WA, R)
    zx, zy, zz = R_AB[0, 2], R_AB[1, 2], R_AB[2, 2]
    yl0, yl1, yl2 = cp * sd, cd, sp * sd  # y_L in F_A
    c = yl0 * zx + yl1 * zy + yl2 * zz
    al0, al2 = zx - c * yl0, zz - c * yl2
    out[HC_THETA_UNDEFINED] = 0.0
    if math.hypot(al0, al2) < 1e-12:
        theta_A = math.nan
        out[HC_THETA_UNDEFINED] = 1.0
    else:
        theta_A = math.atan2(al0, al2)
    M = _rot_y_x_z(math.atan2(zx, zz), math.atan2(-zy, math.hypot(zx, zz)), 0.0)
    Rz = tmul3(M, R_AB)  # heading_of
    psi = math.atan2(Rz[1, 0], Rz[0, 0])
    out[HC_SINGULAR] = 1.0 if singular else 0.0
    out[HC_MARGIN] = margin
    out[11], out[12], out[13] = y0 - phi, y1 - delta, y2 - theta_A
    out[14] = remainder(y3 - psi, 2.0 * math.pi)


@njit(cache=True)
def remainder(x: float, y: float) -> float:
    """IEEE remainder x - n y, n the integer nearest x/y (ties to even), as math.remainder."""
    n = round(x / y)  # rounds half to even, like math.remainder
    r = x - n * y
    if abs(r) > 0.5 * y:  # x / y rounded across a tie
        r -= math.copysign(y, r)
    return r
