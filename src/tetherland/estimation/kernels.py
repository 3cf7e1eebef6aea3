"""Compiled per-tick outputs of :class:`~tetherland.estimation.UkfEstimator`.

After the UKF has integrated the tick's IMU samples (:mod:`~tetherland.estimation.ukf_kernels`),
one call of :func:`estimate_into` writes everything the estimate record needs into one
flat array: the body state with the bias-corrected rate, the biases, the link state of
the attachment point around the believed anchor (docs/theory.md section 3) and the
instantaneous cable tension (docs/theory.md section 8)

    f_L = d_B . (f_R e3 - m (f_B - b_a))   (projection on the link; the norm when d_B = 0).

:func:`estimate_reference` is the same with the readable pieces
(:func:`tetherland.state.link_state_reference`,
:func:`tetherland.estimation.tension.tension_from_forces`); a property test checks both.

Layout of ``out`` (:data:`WIDTH` floats): p_W, v_W, q_WB, omega_B, accel bias b_a, gyro
bias b_g (the log's estimate columns in order), link [phi, delta, phi', delta'], d_B, the
raw tension and the external force m (f_B - b_a) - f_R e3 in F_B (everything but the
rotors: cable, contact, wind). ``geo`` = [r_att_B (3), p_A (3), R_WA (3x3, row-major)].

The estimator's whole tick (issue 25). :class:`~tetherland.estimation.UkfEstimator` keeps
its mutable state in two arrays, the filter's workspace (``ukf_kernels.WS_*``) and its
own (``E_*`` below: the buffered IMU samples, the geometry, the motor lag, the tension
filter and the believed ground effect), so that each of its steps is one compiled call of
three or four array arguments: :func:`push_imu` (an IMU sample), :func:`estimate_tick`
(the buffered samples integrated, the motor lag advanced, the believed ground effect, the
outputs of :func:`estimate_into` and the filtered tension with the taut rule),
:func:`fuse_pose` (a motion-capture pose) and :func:`command_into` (a command sent). They
call the compiled forms of the laws (:func:`~tetherland.estimation.ukf_kernels.predict_into`,
:func:`~tetherland.estimation.tension.motor_lag_advance`,
:func:`~tetherland.estimation.ground_effect.believed_total_thrust_of`,
:func:`estimate_into`, :func:`~tetherland.estimation.tension.tension_filter_step`) in the
order the plain estimator calls its pieces: the same bits (a test runs both side by side).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.estimation.ground_effect import believed_total_thrust_of
from tetherland.estimation.tension import (
    FILTER_WIDTH,
    M_COMMAND,
    M_THRUST_COEFFICIENT,
    MOTOR_WIDTH,
    motor_lag_advance,
    motor_lag_total_thrust,
    tension_filter_step,
    tension_from_forces,
)
from tetherland.estimation.ukf_kernels import WS_CLOCK, WS_X, predict_ws, update_pose_ws
from tetherland.geometry import FloatArray
from tetherland.state import link_into, link_state_reference

P_W, V_W, Q_WB, OMEGA_B = slice(0, 3), slice(3, 6), slice(6, 10), slice(10, 13)
ACCEL_BIAS, GYRO_BIAS, LINK, D_B = slice(13, 16), slice(16, 19), slice(19, 23), slice(23, 26)
TENSION = 26
EXTERNAL = slice(27, 30)
WIDTH = 30
WS_X0, WS_X1, WS_CLOCK0, WS_CLOCK1 = WS_X.start, WS_X.stop, WS_CLOCK.start, WS_CLOCK.stop


# ------------------------------------------------------------------ the estimator's state
BUFFER = 16
"""IMU samples buffered at most between two integrations."""
E_COUNT = 0
"""Number n of buffered IMU samples."""
E_BUFFER = slice(1, 1 + BUFFER * 7)
"""The buffered IMU rows [t, f_B (3), omega_B (3)] (BUFFER, 7), row-major."""
E_GEOMETRY = slice(E_BUFFER.stop, E_BUFFER.stop + 15)
"""``geo`` of :func:`estimate_into`."""
E_MASS = E_GEOMETRY.stop
"""Believed mass m [kg]."""
E_MOTOR_T = E_MASS + 1
"""Time the motor lag was last advanced to [s]."""
E_MOTOR = slice(E_MOTOR_T + 1, E_MOTOR_T + 1 + MOTOR_WIDTH)
"""The motor lag (:func:`~tetherland.estimation.tension.pack_motor_lag`)."""
E_FILTER = slice(E_MOTOR.stop, E_MOTOR.stop + FILTER_WIDTH)
"""The tension filter (:func:`~tetherland.estimation.tension.pack_tension_filter`)."""
E_RAW = E_FILTER.stop
"""Raw tension of the last estimate [N] (NaN: no estimate yet)."""
E_GROUND_EFFECT = E_RAW + 1
"""1 with the believed ground effect, 0 without."""
E_FACTORS = slice(E_GROUND_EFFECT + 1, E_GROUND_EFFECT + 5)
"""The believed factors of the last estimate (4) [-]."""
E_PACK = E_FACTORS.stop
"""Start of the believed ground effect packed
(:func:`~tetherland.estimation.ground_effect.pack_believed`), to the end."""
_B0, _B1, _G0, _G1 = E_BUFFER.start, E_BUFFER.stop, E_GEOMETRY.start, E_GEOMETRY.stop
_M0, _M1, _F0, _F1 = E_MOTOR.start, E_MOTOR.stop, E_FILTER.start, E_FILTER.stop
_C0, _CF = E_MOTOR.start + M_COMMAND.start, E_MOTOR.start + M_THRUST_COEFFICIENT
_K0, _K1 = E_FACTORS.start, E_FACTORS.stop


def pack_estimator(
    r_att_B: FloatArray,
    p_A: FloatArray,
    R_WA: FloatArray,
    mass: float,
    t0: float,
    motor: FloatArray,
    tension_filter: FloatArray,
    believed: FloatArray | None,
) -> FloatArray:
    """The estimator's state (``E_*``): nothing buffered, the geometry (attachment point
    r_att_B [m], anchor p_A [m], R_WA), the ``mass`` [kg], the motor lag ``motor`` as of
    ``t0`` [s], the tension filter and the packed believed ground effect (None: none)."""
    pack = np.empty(0) if believed is None else np.asarray(believed, dtype=float)
    e = np.zeros(E_PACK + pack.size)
    e[E_GEOMETRY] = pack_geometry(r_att_B, p_A, R_WA)
    e[E_MASS], e[E_MOTOR_T] = mass, t0
    e[E_MOTOR], e[E_FILTER] = motor, tension_filter
    e[E_RAW] = math.nan
    e[E_GROUND_EFFECT] = 0.0 if believed is None else 1.0
    e[E_FACTORS] = 1.0
    e[E_PACK:] = pack
    return e


# ------------------------------------------------------------------ the estimator's steps
@njit(cache=True)
def flush(ws: FloatArray, e: FloatArray) -> None:
    """Integrate the buffered IMU samples (one unscented transform) into the filter's
    workspace ``ws``."""
    n = int(e[E_COUNT])
    if n:
        predict_ws(ws, e[_B0:_B1].reshape((BUFFER, 7)), n)
        e[E_COUNT] = 0.0


@njit(cache=True)
def push_imu(ws: FloatArray, e: FloatArray, t: float, f_B: FloatArray,
             omega_B: FloatArray) -> bool:  # fmt: skip
    """Buffer the IMU sample (t [s], f_B [m/s^2], omega_B [rad/s]), integrating the full
    buffer first; False (nothing done) for a sample at or before the estimate's time."""
    if t <= ws[WS_CLOCK0]:
        return False  # a sample at the estimate's own time spans no interval
    n = int(e[E_COUNT])
    if n == BUFFER:
        flush(ws, e)
        n = 0
    i = _B0 + 7 * n
    e[i] = t
    for k in range(3):
        e[i + 1 + k] = f_B[k]
        e[i + 4 + k] = omega_B[k]
    e[E_COUNT] = n + 1
    return True


@njit(cache=True)
def push_imu_rows(ws: FloatArray, e: FloatArray, rows: FloatArray) -> bool:
    """:func:`push_imu` for each row [t, f_B (3), omega_B (3)] of ``rows``, in order; True
    if any was buffered."""
    pushed = False
    for j in range(rows.shape[0]):
        pushed |= push_imu(ws, e, rows[j, 0], rows[j, 1:4], rows[j, 4:7])
    return pushed


@njit(cache=True)
def fuse_pose(ws: FloatArray, e: FloatArray, t_meas: float, p_W: FloatArray,
              q_WB: FloatArray) -> float:  # fmt: skip
    """The buffered samples integrated, then the pose (p_W [m], q_WB) measured at
    ``t_meas`` [s] fused (:func:`~tetherland.estimation.ukf_kernels.update_pose_into`):
    the NIS, or ``REJECTED``."""
    flush(ws, e)
    return update_pose_ws(ws, t_meas, p_W, q_WB)


@njit(cache=True)
def thrust_at(e: FloatArray, t: float) -> float:
    """Total actual thrust at ``t`` [s]: the motor lag advanced to ``t`` [N]."""
    dt = t - e[E_MOTOR_T]
    m = e[_M0:_M1]
    if dt > 0.0:
        e[E_MOTOR_T] = t
        return motor_lag_advance(m, dt)
    return motor_lag_total_thrust(m)


@njit(cache=True)
def command_into(e: FloatArray, t: float, rotor_speeds: FloatArray) -> None:
    """The rotors are commanded ``rotor_speeds`` (4) [rad/s] from ``t`` [s] on: the motor
    lag advanced to ``t``, the command held from there."""
    thrust_at(e, t)
    for i in range(4):
        e[_C0 + i] = rotor_speeds[i]


@njit(cache=True)
def estimate_tick(ws: FloatArray, e: FloatArray, out: FloatArray):
    """One estimate: the buffered samples integrated, the thrust (motor lag, believed
    ground effect), :func:`estimate_into` into ``out`` and the tension filtered (taut
    rule in ``e[E_FILTER]``). Returns (t [s], filtered tension [N], phi, delta [rad],
    phi', delta' [rad/s])."""
    flush(ws, e)
    x = ws[WS_X0:WS_X1]
    imu = ws[WS_CLOCK0:WS_CLOCK1]
    t = imu[0]
    thrust = thrust_at(e, t)
    if e[E_GROUND_EFFECT] != 0.0:
        c_f = e[_CF]
        w0, w1, w2, w3 = e[_M0], e[_M0 + 1], e[_M0 + 2], e[_M0 + 3]
        thrust = believed_total_thrust_of(x, c_f * (w0 * w0), c_f * (w1 * w1), c_f * (w2 * w2),
                                          c_f * (w3 * w3), e[E_PACK:], e[_K0:_K1])  # fmt: skip
    estimate_into(x, imu, thrust, e[E_MASS], e[_G0:_G1], out)
    raw = out[TENSION]
    e[E_RAW] = raw
    filtered = tension_filter_step(e[_F0:_F1], t, raw)
    return t, filtered, out[19], out[20], out[21], out[22]


def pack_geometry(r_att_B: FloatArray, p_A: FloatArray, R_WA: FloatArray) -> FloatArray:
    """``geo`` of :func:`estimate_into`."""
    return np.concatenate((r_att_B, p_A, np.asarray(R_WA, dtype=float).reshape(9))).astype(float)


def estimate_reference(
    x: FloatArray,
    imu: FloatArray,
    thrust: float,
    mass: float,
    geo: FloatArray,
) -> FloatArray:
    """Plain version of :func:`estimate_into` (returns ``out``).

    Parameters
    ----------
    x : (16,) array
        UKF state [p_W, v_W, q_WB, b_g, b_a].
    imu : (10,) array
        The UKF's IMU record [t, f_B, omega_B of the last sample, mean f_B of the last
        prediction] (measured) [s, m/s^2, rad/s, m/s^2].
    thrust : float
        Actual total rotor thrust (motor lag) [N].
    mass : float
        [kg]
    geo : (15,) array
        See the module docstring.
    """
    p_W, v_W, q_WB, b_g, b_a = x[0:3], x[3:6], x[6:10], x[10:13], x[13:16]
    omega_B, f_mean_B = imu[4:7] - b_g, imu[7:10]
    r_att, p_A, R_WA = geo[0:3], geo[3:6], geo[6:15].reshape(3, 3)
    link, d_B = link_state_reference(np.concatenate((p_W, q_WB, v_W, omega_B)), r_att, p_A, R_WA)
    tension = tension_from_forces(thrust, f_mean_B - b_a, mass, d_B if d_B.any() else None)
    external_B = mass * (f_mean_B - b_a) - thrust * np.array([0.0, 0.0, 1.0])
    return np.concatenate((p_W, v_W, q_WB, omega_B, b_a, b_g, link, d_B, [tension], external_B))


@njit(cache=True)
def estimate_into(
    x: FloatArray,
    imu: FloatArray,
    thrust: float,
    mass: float,
    geo: FloatArray,
    out: FloatArray,
) -> None:
    """Compiled :func:`estimate_reference`, written into ``out`` (:data:`WIDTH`,)."""
    for i in range(6):
        out[i] = x[i]  # p_W, v_W
    for i in range(4):
        out[6 + i] = x[6 + i]  # q_WB
    for i in range(3):
        out[10 + i] = imu[4 + i] - x[10 + i]  # omega_B = omega_m - b_g
        out[13 + i] = x[13 + i]  # b_a
        out[16 + i] = x[10 + i]  # b_g
    R_WA = geo[6:15].reshape(3, 3)
    link_into(out[0:3], out[6:10], out[3:6], out[10:13], geo[0:3], geo[3:6], R_WA,
              out[19:23], out[23:26])  # fmt: skip
    # residual force f_R e3 - m (f_B - b_a) in F_B, projected on d_B (or its norm)
    rx = -mass * (imu[7] - x[13])
    ry = -mass * (imu[8] - x[14])
    rz = thrust - mass * (imu[9] - x[15])
    dx, dy, dz = out[23], out[24], out[25]
    if dx != 0.0 or dy != 0.0 or dz != 0.0:
        out[TENSION] = dx * rx + dy * ry + dz * rz
    else:
        out[TENSION] = math.sqrt(rx * rx + ry * ry + rz * rz)
    out[27] = -rx  # the external force, m (f_B - b_a) - f_R e3
    out[28] = -ry
    out[29] = -rz
