"""The contact-free tracker (free-flight law with flatness feed-forward, a hover-only
integral and motor-lag compensation), plain and compiled side by side.

:func:`tracker_reference` is the readable law (the equations of
:class:`~tetherland.control.position.PositionController` with its feed-forward rates,
:func:`~tetherland.control.attitude.attitude_torque` and the mixer); :func:`tracker_into`
is the same law compiled, one call per control tick. Both read ``par``
(:func:`pack_tracker`) at the ``PAR_*`` fields, keep their memory in ``state`` (the
``STATE_*`` fields; :func:`tracker_state`) and the position-error integral in
``integral``, and write the ``OUT_*`` fields of ``out``. The controller is
:class:`tetherland.control.tracking.FreeFlightTracker`.

Per tick: the integral runs only while the reference is at rest (speed at most
``PAR_HOLD_SPEED``); with the reference's jerk (and snap) rows, the body rate and angular
acceleration of the flat outputs enter the attitude law; with lag compensation, the speed
commands lead the motor lag along the rate of the reference's nominal rotor thrusts
f_n = Gamma^-1 [m ||p'' + g z_W||, J omega_d' + omega_d x J omega_d] between two ticks at
most 2.5 periods apart.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.control.attitude import attitude_torque
from tetherland.control.feedforward import _feedforward_kernel, attitude_feedforward
from tetherland.control.kernels import free_flight, mixer, so3
from tetherland.control.kernels.packing import Fields
from tetherland.errors import SingularityError
from tetherland.geometry import FloatArray
from tetherland.models.quadrotor import RotorLayout, RotorModel
from tetherland.rotations import quat_to_rotmat, rotation_from_z_and_yaw

LAG_WINDOW = 2.5
"""Longest gap between two ticks whose nominal thrusts give a rate, in control periods."""

# ------------------------------------------------------------------ par: gains and model
_par = Fields()
PAR_LAW = _par.vector(free_flight.PAR_WIDTH)
"""The free-flight law's gains and model (:func:`~.free_flight.pack_free_flight`)."""
PAR_PERIOD = _par.scalar()
"""Control period [s]."""
PAR_LAG = _par.scalar()
"""1: lead the speed commands by the motor lag, 0: not."""
PAR_HOLD_SPEED = _par.scalar()
"""Largest reference speed at which the integral runs [m/s]."""
PAR_WIDTH = _par.width

# ------------------------------------------------------------------ state: between ticks
_state = Fields()
STATE_T_INTEGRAL = _state.scalar()
"""Time of the last tick [s] (NaN: none since the reset)."""
STATE_T_NOMINAL = _state.scalar()
"""Time of the last nominal thrusts [s] (NaN: none)."""
STATE_NOMINAL = _state.vector(4)
"""The last nominal rotor thrusts f_n [N]."""
STATE_WIDTH = _state.width

# ------------------------------------------------------------------ out: after the mixer's
_out = Fields(mixer.OUT_WIDTH)
OUT_SINGULAR = _out.scalar()
"""0 regular; 1 heading of F_d undefined, 2 nominal force zero, 3 heading of the nominal
force undefined: no command."""
OUT_LIMITED = _out.scalar()
"""1 when the tilt or vertical-thrust limit acted."""
OUT_POSITION_ERROR = _out.scalar()
"""||p - p_d|| [m]."""
OUT_WIDTH = _out.width

SINGULAR_MESSAGES = {
    1: "thrust axis is aligned with the desired heading: yaw undefined",
    2: "desired force is zero: its direction is undefined",
    3: "z_d x x_C (thrust axis along the heading) is zero: its direction is undefined",
}
"""The :class:`SingularityError` message of each ``OUT_SINGULAR`` value."""


def pack_tracker(law: FloatArray, period: float, lag: bool, hold_speed: float) -> FloatArray:
    """``par`` of :func:`tracker_into` (:data:`PAR_WIDTH`): the free-flight law's ``par``,
    the control period [s], lag compensation on/off and the largest reference speed of
    the integral [m/s]."""
    par = np.empty(PAR_WIDTH)
    par[PAR_LAW] = law
    par[PAR_PERIOD], par[PAR_LAG], par[PAR_HOLD_SPEED] = period, float(lag), hold_speed
    return par


def tracker_state() -> FloatArray:
    """A reset ``state`` (no earlier tick)."""
    state = np.zeros(STATE_WIDTH)
    state[STATE_T_INTEGRAL] = state[STATE_T_NOMINAL] = math.nan
    return state


def tracker_reference(
    t: float,
    p_W: FloatArray,
    v_W: FloatArray,
    q_WB: FloatArray,
    omega_B: FloatArray,
    ref: FloatArray,
    yaw: float,
    integral: FloatArray,
    state: FloatArray,
    par: FloatArray,
    layout: RotorLayout,
    rotors: RotorModel,
) -> FloatArray:
    """The contact-free tracker at time ``t`` [s], plain.

    ``ref`` rows (p, v, a, jerk, snap), the first k given [F_W]; ``integral`` (int e_x
    [m s]) and ``state`` are updated in place. Returns ``out`` (:data:`OUT_WIDTH`).
    """
    law = par[PAR_LAW]
    m, g = law[free_flight.PAR_MASS], law[free_flight.PAR_G]
    att = law[free_flight.PAR_ATTITUDE]
    J = att[so3.ATT_J]
    out = np.zeros(OUT_WIDTH)
    rows = np.zeros((5, 3))
    rows[: len(ref)] = ref
    p_d, v_d, a_d, j_d, s_d = rows
    last = state[STATE_T_INTEGRAL]
    state[STATE_T_INTEGRAL] = t
    dt = t - last if np.linalg.norm(v_d) <= par[PAR_HOLD_SPEED] else math.nan
    F_n = m * a_d + np.array([0.0, 0.0, m * g])
    feedforward = len(ref) > 3
    w_d, w_dot_d = np.zeros(3), np.zeros(3)
    if feedforward:
        try:
            _, w_d, w_dot_d = attitude_feedforward(F_n, m * j_d, m * s_d, yaw)
        except SingularityError as err:
            out[OUT_SINGULAR] = 2.0 if str(err).startswith("desired force") else 3.0
            return out
    # F_d: PD on the position error, integral, tilt and vertical-thrust limits
    e_x = p_W - p_d
    F = m * (a_d - law[free_flight.PAR_K_X] * e_x - law[free_flight.PAR_K_V] * (v_W - v_d))
    F -= m * law[free_flight.PAR_K_I] * integral
    F[2] += m * g
    limited = False
    if F[2] < law[free_flight.PAR_MIN_VERTICAL]:
        F[2], limited = law[free_flight.PAR_MIN_VERTICAL], True
    horiz, max_horiz = math.hypot(F[0], F[1]), F[2] * law[free_flight.PAR_TAN_MAX_TILT]
    if horiz > max_horiz:
        F[0:2] *= max_horiz / horiz
        limited = True
    bound = law[free_flight.PAR_INTEGRAL_BOUND]
    if not math.isnan(dt) and law[free_flight.PAR_K_I] > 0.0 and not limited:
        np.clip(integral + e_x * dt, -bound, bound, out=integral)
    out[OUT_LIMITED], out[OUT_POSITION_ERROR] = float(limited), np.linalg.norm(e_x)
    try:
        R_d = rotation_from_z_and_yaw(F, yaw)
    except SingularityError:
        out[OUT_SINGULAR] = 1.0
        return out
    R = quat_to_rotmat(q_WB)
    ff = (w_d, w_dot_d) if feedforward else (None, None)
    tau = attitude_torque(J, att[so3.ATT_J_K_R], att[so3.ATT_J_K_W], R, omega_B, R_d, *ff)
    wrench = np.concatenate(([F @ R[:, 2]], tau))
    rates = None
    if par[PAR_LAG]:
        tau_n = J * w_dot_d + np.cross(w_d, J * w_d)
        f_n = layout.allocation_inverse @ np.concatenate(([np.linalg.norm(F_n)], tau_n))
        gap = t - state[STATE_T_NOMINAL]
        if 0.0 < gap <= LAG_WINDOW * par[PAR_PERIOD]:  # False for NaN
            rates = (f_n - state[STATE_NOMINAL]) / gap
        state[STATE_T_NOMINAL], state[STATE_NOMINAL] = t, f_n
    out[: mixer.OUT_WIDTH] = mixer.mix_reference(wrench, rates, layout, rotors)
    return out


@njit(cache=True)
def tracker_into(
    t: float,
    p_W: FloatArray,
    v_W: FloatArray,
    q_WB: FloatArray,
    omega_B: FloatArray,
    ref: FloatArray,
    yaw: float,
    integral: FloatArray,
    state: FloatArray,
    par: FloatArray,
    mix: FloatArray,
    out: FloatArray,
) -> None:
    """Compiled :func:`tracker_reference` (``integral`` and ``state`` in place, result in
    ``out``)."""
    law = par[PAR_LAW]
    m, g = law[free_flight.PAR_MASS], law[free_flight.PAR_G]
    J = law[free_flight.PAR_ATTITUDE][so3.ATT_J]
    k = ref.shape[0]
    last = state[STATE_T_INTEGRAL]
    state[STATE_T_INTEGRAL] = t
    speed = 0.0
    if k > 1:
        speed = math.sqrt(ref[1, 0] ** 2 + ref[1, 1] ** 2 + ref[1, 2] ** 2)
    dt = t - last if speed <= par[PAR_HOLD_SPEED] else math.nan
    F_n = np.zeros(3)
    for i in range(3):
        F_n[i] = m * ref[2, i] if k > 2 else 0.0
    F_n[2] += m * g
    feedforward = k > 3
    w_d, w_dot_d = np.zeros(3), np.zeros(3)
    if feedforward:
        dF, ddF = np.empty(3), np.zeros(3)
        for i in range(3):
            dF[i] = m * ref[3, i]
            if k > 4:
                ddF[i] = m * ref[4, i]
        buf = np.empty(15)
        status = _feedforward_kernel(F_n, dF, ddF, yaw, buf)
        if status != 0:
            out[OUT_SINGULAR] = 1.0 + status
            return
        w_d[:], w_dot_d[:] = buf[9:12], buf[12:15]
    F, e_x = np.empty(3), np.empty(3)
    limited = free_flight.desired_force(p_W, v_W, ref, dt, integral, law, e_x, F)
    out[OUT_LIMITED] = 1.0 if limited else 0.0
    out[OUT_POSITION_ERROR] = math.sqrt(e_x[0] ** 2 + e_x[1] ** 2 + e_x[2] ** 2)
    R_d = np.empty((3, 3))
    if not free_flight.desired_rotation(F, yaw, R_d):
        out[OUT_SINGULAR] = 1.0
        return
    out[OUT_SINGULAR] = 0.0
    R = so3.quat_rotmat3(q_WB)
    thrust = F[0] * R[0, 2] + F[1] * R[1, 2] + F[2] * R[2, 2]
    att = law[free_flight.PAR_ATTITUDE]
    t0, t1, t2 = so3.attitude_torque(R, omega_B, R_d, w_d, w_dot_d, feedforward, att)
    rates = np.zeros(4)
    lead = False
    if par[PAR_LAG] != 0.0:
        a0, a1, a2 = J[0] * w_d[0], J[1] * w_d[1], J[2] * w_d[2]
        w = np.array([
            math.sqrt(F_n[0] ** 2 + F_n[1] ** 2 + F_n[2] ** 2),
            J[0] * w_dot_d[0] + w_d[1] * a2 - w_d[2] * a1,
            J[1] * w_dot_d[1] + w_d[2] * a0 - w_d[0] * a2,
            J[2] * w_dot_d[2] + w_d[0] * a1 - w_d[1] * a0,
        ])  # fmt: skip
        Gi = mix[mixer.MIX_GI].reshape(4, 4)
        gap = t - state[STATE_T_NOMINAL]
        lead = 0.0 < gap <= LAG_WINDOW * par[PAR_PERIOD]
        nominal = state[STATE_NOMINAL]
        for i in range(4):
            f_i = Gi[i, 0] * w[0] + Gi[i, 1] * w[1] + Gi[i, 2] * w[2] + Gi[i, 3] * w[3]
            if lead:
                rates[i] = (f_i - nominal[i]) / gap
            nominal[i] = f_i
        state[STATE_T_NOMINAL] = t
    mixer.mix_into(thrust, t0, t1, t2, rates, lead, mix, out)
