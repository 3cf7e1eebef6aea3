"""The hierarchical tethered law Gamma_HC^b (docs/theory.md section 7, chapter 4.5.2),
plain and compiled side by side.

:func:`hierarchical_reference` is the readable law (the equations of
:mod:`tetherland.control.hierarchical`, written with
:func:`~tetherland.control.attitude.attitude_torque`, :func:`~tetherland.geometry.link_frame`,
:func:`~tetherland.control.common.attitude_from_thrust_axis` and the mixer);
:func:`hierarchical_into` is the same law compiled, one call per control tick. Both read the
gains and model packed by :func:`pack_hierarchical` at the ``PAR_*`` fields, keep their
memory at the ``STATE_*`` fields (:func:`hierarchical_state`) and write the ``OUT_*``
fields of ``out``. The controller is :class:`tetherland.control.HierarchicalController`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.control.attitude import attitude_torque
from tetherland.control.common import attitude_from_thrust_axis, heading_of
from tetherland.control.kernels import mixer, so3
from tetherland.control.kernels.packing import Fields
from tetherland.errors import SingularityError
from tetherland.geometry import FloatArray, link_frame, theta_A_from_z_B
from tetherland.models.quadrotor import RotorLayout, RotorModel
from tetherland.models.tethered import COS_DELTA_MIN
from tetherland.rotations import quat_to_rotmat

U_Z_MIN_FRACTION = 0.02
"""u_z below this fraction of m g counts as singular (the thrust must push across the link)."""
COS_SUM_MIN = 0.02
"""|cos(phi + theta_A,d)| below this is singular (thrust axis along the link)."""

# ------------------------------------------------------------------ par: gains and model
_par = Fields()
PAR_MASS = _par.scalar()
"""m [kg]."""
PAR_LENGTH = _par.scalar()
"""Link length l [m]."""
PAR_G = _par.scalar()
"""g [m/s^2]."""
PAR_K_P = _par.scalar()
"""Link-angle gain k_p [1/s^2]."""
PAR_K_D = _par.scalar()
"""Link-rate gain k_d [1/s]."""
PAR_K_I = _par.scalar()
"""Link-angle integral gain k_i [1/s^3]."""
PAR_INTEGRAL_MAX = _par.scalar()
"""Largest k_i int(e) per angle [rad/s^2]."""
PAR_CABLE = _par.vector(so3.CABLE_WIDTH)
"""The cable's geometry (:func:`tetherland.control.kernels.so3.pack_cable`)."""
PAR_ATTITUDE = _par.vector(so3.ATT_WIDTH)
"""The attitude law's gains (:func:`tetherland.control.kernels.so3.pack_attitude`)."""
PAR_WIDTH = _par.width

# ------------------------------------------------------------------ state: the memory
_state = Fields()
STATE_INTEGRAL = _state.vector(2)
"""Integrals of the phi and delta errors [rad s]."""
STATE_T_LAST = _state.scalar()
"""Time of the last update [s] (NaN: none)."""
STATE_THRUST = _state.scalar()
"""Last regular thrust f_R [N] (held through singularities)."""
STATE_HAS_R_D = _state.scalar()
"""1 once a regular desired attitude was computed."""
STATE_R_D = _state.vector(9)
"""Last regular desired attitude R_WB,d, row-major (held through singularities)."""
STATE_LEAN_TAN = _state.scalar()
"""tan of the lean limit of this update (``Reference.lean_limit``; 0: none) [-]: set by the
controller before each call."""
STATE_WIDTH = _state.width

# ------------------------------------------------------------------ out: after the mixer's
_out = Fields(mixer.OUT_WIDTH)
OUT_SINGULAR = _out.scalar()
"""1 when the law is singular (the last regular attitude and thrust are held)."""
OUT_MARGIN = _out.scalar()
"""Distance from the singularities, 1 at the thresholds [-]."""
OUT_ERRORS = _out.vector(4)
"""Errors e_phi, e_delta, e_theta_A, e_psi (desired - actual) [rad]."""
OUT_THETA_UNDEFINED = _out.scalar()
"""1 when theta_A of the actual attitude is undefined (thrust axis across the link plane)."""
OUT_WIDTH = _out.width


def pack_hierarchical(
    mass: float,
    length: float,
    g: float,
    k_p: float,
    k_d: float,
    k_i: float,
    integral_max: float,
    compensate: bool,
    r_att_B: FloatArray,
    R_WA: FloatArray,
    inertia: FloatArray,
    k_R: FloatArray,
    k_w: FloatArray,
) -> FloatArray:
    """``par`` of :func:`hierarchical_into` (:data:`PAR_WIDTH`): mass [kg], link length [m],
    g [m/s^2], gains k_p [1/s^2], k_d [1/s], k_i [1/s^3], the integral bound [rad/s^2],
    whether to cancel the cable torque, r_att in F_B [m], R_WA, inertia [kg m^2] and
    attitude gains k_R [1/s^2], k_w [1/s] per axis."""
    par = np.empty(PAR_WIDTH)
    par[PAR_MASS], par[PAR_LENGTH], par[PAR_G] = mass, length, g
    par[PAR_K_P], par[PAR_K_D], par[PAR_K_I] = k_p, k_d, k_i
    par[PAR_INTEGRAL_MAX] = integral_max
    par[PAR_CABLE] = so3.pack_cable(compensate, r_att_B, R_WA)
    par[PAR_ATTITUDE] = so3.pack_attitude(inertia, k_R, k_w)
    return par


def hierarchical_state(mass: float, g: float) -> FloatArray:
    """A reset ``state`` of :func:`hierarchical_into`: no integral, no last attitude, the
    hover thrust m g [N] held."""
    s = np.zeros(STATE_WIDTH)
    s[STATE_T_LAST], s[STATE_THRUST] = math.nan, mass * g
    return s


def link_force_components(
    m: float, l: float, g: float, phi: float, delta: float, dphi: float, ddelta: float,
    v_phi: float, v_delta: float,
) -> tuple[float, float]:
    """(u_y, u_z) of the hierarchical law for the link accelerations (v_phi, v_delta), in
    F_L [N] (docs/theory.md 7.5, the inversion of the taut-link dynamics of section 4.2);
    plain, shared by :func:`hierarchical_reference` and the hand-over from free flight."""
    cp, sp, cd, sd = math.cos(phi), math.sin(phi), math.cos(delta), math.sin(delta)
    u_z = m * l * (cd * v_phi - 2.0 * sd * dphi * ddelta) + m * g * cp
    u_y = m * g * sp * sd - m * l * (v_delta + 0.5 * math.sin(2.0 * delta) * dphi * dphi)
    return u_y, u_z


def _lean_limited(u_x: float, u_y: float, u_z: float, state: FloatArray, integral: FloatArray,
                  delta_integral: float) -> float:  # fmt: skip
    """u_y cut to the lean limit tan(lean) sqrt(u_x^2 + u_z^2) of ``state`` [N] (plain);
    where it cuts, the delta integral is put back to ``delta_integral``, its value before
    this update."""
    lean_tan = state[STATE_LEAN_TAN]
    if lean_tan > 0.0:
        limit = lean_tan * math.hypot(u_x, u_z)
        if abs(u_y) > limit:
            integral[1] = delta_integral
            return math.copysign(limit, u_y)
    return u_y


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
    place. Returns ``out`` (:data:`OUT_WIDTH`)."""
    m, l, g = par[PAR_MASS], par[PAR_LENGTH], par[PAR_G]
    k_p, k_d, k_i = par[PAR_K_P], par[PAR_K_D], par[PAR_K_I]
    cable, att = par[PAR_CABLE], par[PAR_ATTITUDE]
    R_WA = cable[so3.CABLE_R_WA].reshape(3, 3)
    integral = state[STATE_INTEGRAL]
    phi, delta, dphi, ddelta = link
    yd = Y[0]
    yd1 = Y[1] if Y.shape[0] > 1 else np.zeros(4)
    yd2 = Y[2] if Y.shape[0] > 2 else np.zeros(4)
    delta_integral = integral[1]  # (kept while the lean limit cuts u_y: no wind-up)
    if not math.isnan(state[STATE_T_LAST]) and k_i > 0.0:
        bound, dt = par[PAR_INTEGRAL_MAX] / k_i, t - state[STATE_T_LAST]
        integral[0] = min(max(integral[0] + (yd[0] - phi) * dt, -bound), bound)
        integral[1] = min(max(integral[1] + (yd[1] - delta) * dt, -bound), bound)
    state[STATE_T_LAST] = t
    v_phi = yd2[0] + k_d * (yd1[0] - dphi) + k_p * (yd[0] - phi) + k_i * integral[0]
    v_delta = yd2[1] + k_d * (yd1[1] - ddelta) + k_p * (yd[1] - delta) + k_i * integral[1]
    cd = math.cos(delta)
    u_y, u_z = link_force_components(m, l, g, phi, delta, dphi, ddelta, v_phi, v_delta)
    cos_sum = math.cos(phi + yd[2])
    margin = min(abs(cd) / 0.1, u_z / (U_Z_MIN_FRACTION * m * g), abs(cos_sum) / COS_SUM_MIN)
    R = quat_to_rotmat(q_WB)
    singular = abs(cd) < COS_DELTA_MIN or u_z < U_Z_MIN_FRACTION * m * g or abs(
        cos_sum) < COS_SUM_MIN  # fmt: skip
    if not singular:
        u_x = u_z * math.tan(phi + yd[2]) / cd
        u_y = _lean_limited(u_x, u_y, u_z, state, integral, delta_integral)
        F_A = link_frame(phi, delta) @ np.array([u_x, u_y, u_z])
        F_norm = float(np.linalg.norm(F_A))
        singular = F_norm < 1e-6 * m * g
    if singular:
        R_d = state[STATE_R_D].reshape(3, 3) if state[STATE_HAS_R_D] else R
        f_R = state[STATE_THRUST]
    else:
        R_d = R_WA @ attitude_from_thrust_axis(F_A / F_norm, yd[3])
        f_R = float((R_WA @ F_A) @ R[:, 2])
        state[STATE_THRUST], state[STATE_HAS_R_D], state[STATE_R_D] = f_R, 1.0, R_d.reshape(9)
    w_d, w_dot_d = (ff_omega, ff_omega_dot) if feedforward else (None, None)
    tau = attitude_torque(att[so3.ATT_J], att[so3.ATT_J_K_R], att[so3.ATT_J_K_W], R, omega_B,
                          R_d, w_d, w_dot_d)  # fmt: skip
    tau = so3.cancel_cable_torque_reference(tau, R, link_frame(phi, delta)[:, 0], tension, cable)
    out = np.zeros(OUT_WIDTH)
    wrench = np.concatenate(([max(f_R, 0.0)], tau))
    out[: mixer.OUT_WIDTH] = mixer.mix_reference(wrench, None, layout, rotors)
    try:
        theta_A = theta_A_from_z_B(R_WA.T @ R[:, 2], phi, delta)
    except SingularityError:
        theta_A, out[OUT_THETA_UNDEFINED] = math.nan, 1.0
    psi = heading_of(R_WA.T @ R)
    out[OUT_SINGULAR], out[OUT_MARGIN] = float(singular), margin
    out[OUT_ERRORS] = [yd[0] - phi, yd[1] - delta, yd[2] - theta_A,
                       math.remainder(yd[3] - psi, 2.0 * math.pi)]  # fmt: skip
    return out


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
    m, l, g = par[PAR_MASS], par[PAR_LENGTH], par[PAR_G]
    k_p, k_d, k_i = par[PAR_K_P], par[PAR_K_D], par[PAR_K_I]
    cable = par[PAR_CABLE]
    R_WA = cable[so3.CABLE_R_WA].reshape(3, 3)
    integral = state[STATE_INTEGRAL]
    phi, delta, dphi, ddelta = link[0], link[1], link[2], link[3]
    k = Y.shape[0]
    y0, y1, y2, y3 = Y[0, 0], Y[0, 1], Y[0, 2], Y[0, 3]
    yd1_0, yd1_1 = (Y[1, 0], Y[1, 1]) if k > 1 else (0.0, 0.0)
    yd2_0, yd2_1 = (Y[2, 0], Y[2, 1]) if k > 2 else (0.0, 0.0)
    t_last = state[STATE_T_LAST]
    delta_integral = integral[1]  # (kept while the lean limit cuts u_y: no wind-up)
    if t_last == t_last and k_i > 0.0:
        bound, dt = par[PAR_INTEGRAL_MAX] / k_i, t - t_last
        integral[0] = min(max(integral[0] + (y0 - phi) * dt, -bound), bound)
        integral[1] = min(max(integral[1] + (y1 - delta) * dt, -bound), bound)
    state[STATE_T_LAST] = t
    v_phi = yd2_0 + k_d * (yd1_0 - dphi) + k_p * (y0 - phi) + k_i * integral[0]
    v_delta = yd2_1 + k_d * (yd1_1 - ddelta) + k_p * (y1 - delta) + k_i * integral[1]
    cp, sp, cd, sd = math.cos(phi), math.sin(phi), math.cos(delta), math.sin(delta)
    u_z = m * l * (cd * v_phi - 2.0 * sd * dphi * ddelta) + m * g * cp
    u_y = m * g * sp * sd - m * l * (v_delta + 0.5 * math.sin(2.0 * delta) * dphi * dphi)
    cos_sum = math.cos(phi + y2)
    margin = min(abs(cd) / 0.1, u_z / (U_Z_MIN_FRACTION * m * g), abs(cos_sum) / COS_SUM_MIN)
    R = so3.quat_rotmat3(q_WB)
    singular = abs(cd) < COS_DELTA_MIN or u_z < U_Z_MIN_FRACTION * m * g or abs(
        cos_sum) < COS_SUM_MIN  # fmt: skip
    F0 = F1 = F2 = F_norm = 0.0
    if not singular:
        u_x = u_z * math.tan(phi + y2) / cd
        lean_tan = state[STATE_LEAN_TAN]
        if lean_tan > 0.0:  # the lean limit (_lean_limited); no work without one
            lean = lean_tan * math.hypot(u_x, u_z)
            if abs(u_y) > lean:
                integral[1] = delta_integral
                u_y = math.copysign(lean, u_y)
        # F_A = R_AL [u_x, u_y, u_z], R_AL = link_frame(phi, delta)
        F0 = cd * cp * u_x + cp * sd * u_y - sp * u_z
        F1 = -sd * u_x + cd * u_y
        F2 = cd * sp * u_x + sp * sd * u_y + cp * u_z
        F_norm = math.sqrt(F0 * F0 + F1 * F1 + F2 * F2)
        singular = F_norm < 1e-6 * m * g
    R_d = np.empty((3, 3))
    last_R_d = state[STATE_R_D]
    if singular:
        held = last_R_d if state[STATE_HAS_R_D] != 0.0 else R.reshape(9)
        for i in range(9):
            R_d[i // 3, i % 3] = held[i]
        f_R = state[STATE_THRUST]
    else:
        zx, zy, zz = F0 / F_norm, F1 / F_norm, F2 / F_norm  # attitude_from_thrust_axis
        R_AB = so3.rot_y_x_z(math.atan2(zx, zz), math.atan2(-zy, math.hypot(zx, zz)), y3)
        so3.mul3_into(R_WA, R_AB, R_d)
        f_R = 0.0
        for i in range(3):
            f_R += (R_WA[i, 0] * F0 + R_WA[i, 1] * F1 + R_WA[i, 2] * F2) * R[i, 2]
        state[STATE_THRUST], state[STATE_HAS_R_D] = f_R, 1.0
        for i in range(9):
            last_R_d[i] = R_d[i // 3, i % 3]
    t0, t1, t2 = so3.attitude_torque(R, omega_B, R_d, ff_omega, ff_omega_dot, feedforward,
                                     par[PAR_ATTITUDE])  # fmt: skip
    t0, t1, t2 = so3.cancel_cable_torque(t0, t1, t2, R, cd * cp, -sd, cd * sp, tension, cable)
    mixer.mix_into(max(f_R, 0.0), t0, t1, t2, omega_B, False, mix, out)
    # diagnostics: theta_A of the actual z_B (geometry.theta_A_from_z_B) and heading psi
    R_AB = so3.tmul3(R_WA, R)
    zx, zy, zz = R_AB[0, 2], R_AB[1, 2], R_AB[2, 2]
    yl0, yl1, yl2 = cp * sd, cd, sp * sd  # y_L in F_A
    c = yl0 * zx + yl1 * zy + yl2 * zz
    al0, al2 = zx - c * yl0, zz - c * yl2
    out[OUT_THETA_UNDEFINED] = 0.0
    if math.hypot(al0, al2) < 1e-12:
        theta_A = math.nan
        out[OUT_THETA_UNDEFINED] = 1.0
    else:
        theta_A = math.atan2(al0, al2)
    M = so3.rot_y_x_z(math.atan2(zx, zz), math.atan2(-zy, math.hypot(zx, zz)), 0.0)
    Rz = so3.tmul3(M, R_AB)  # heading_of
    psi = math.atan2(Rz[1, 0], Rz[0, 0])
    out[OUT_SINGULAR] = 1.0 if singular else 0.0
    out[OUT_MARGIN] = margin
    errors = out[OUT_ERRORS]
    errors[0], errors[1], errors[2] = y0 - phi, y1 - delta, y2 - theta_A
    errors[3] = so3.remainder(y3 - psi, 2.0 * math.pi)
