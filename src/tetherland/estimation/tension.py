"""Cable tension from thrust and the accelerometer (docs/theory.md section 8).

Newton in F_B with the IMU at the centre of mass and no contact:
    m a_m = f_R e3 - f_L d_B,     d_B = R_BW d  (d: unit link direction, anchor -> robot)
so  f_L = d_B . (f_R e3 - m a_m)  (projection on the link), or, when d is unknown,
f_L = ||f_R e3 - m a_m||. The thrust f_R is the rotors' actual thrust, predicted from the
commanded speeds through the motor lag; the estimate is low-pass filtered.

Each law is here twice: the plain classes (:class:`MotorLagThrust`,
:class:`TensionEstimator`, :class:`ThresholdDwell`) and compiled steps of the same
operations in the same order on a packed state (:func:`motor_lag_advance`,
:func:`tension_filter_step`), which the estimator's per-tick kernels
(:mod:`tetherland.estimation.kernels`) call; a test compares them bit for bit.

Elastic cables (docs/tether.md): the force balance holds whatever the cable's stretch, so
the estimate needs no cable model; the link direction d is that of the stretched cable
(anchor to attachment point, at distance l + s). The stretch gives a second, geometric
reading of the tension, f_L = k (|p_att - p_A| - l) while taut (:func:`elastic_tension`),
with an error of k times the position error: useful for soft lines (k = 1.2e3 N/m for
1 m of nylon: 1.2 N per mm), not for stiff ones (Dyneema: 15 N per mm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from tetherland.geometry import FloatArray

_E3 = np.array([0.0, 0.0, 1.0])


def tension_from_forces(
    thrust: float, specific_force_B: ArrayLike, mass: float, d_B: ArrayLike | None = None
) -> float:
    """Instantaneous tension estimate [N] from thrust [N] and specific force [m/s^2] in F_B.

    With ``d_B`` (unit link direction in F_B) the residual force is projected on the link;
    without it its norm is used (which also counts unmodelled forces).
    """
    residual = thrust * _E3 - mass * np.asarray(specific_force_B, dtype=float)
    if d_B is None:
        return float(np.linalg.norm(residual))
    return float(np.asarray(d_B, dtype=float) @ residual)


TENSION_FILTER_SLOW = 0.02
"""Low-pass time constant of the tension estimate with an inextensible cable [s]."""
TENSION_FILTER_FAST = 0.005
"""Shortest time constant: below it the accelerometer noise dominates the estimate [s]."""


def tension_filter_time_constant(stiffness: float | None, mass: float) -> float:
    """Low-pass time constant of the tension estimate for a cable of spring constant k
    (None: inextensible) holding ``mass`` [kg] [s].

    A taut elastic cable oscillates axially at w = sqrt(k/m) (5.5 Hz for 1 m of 1 mm
    nylon, 19 Hz for Dyneema), which a 20 ms filter lags by 35-68 deg: the time constant
    is 0.2/w (11 deg of lag), between :data:`TENSION_FILTER_FAST` and
    :data:`TENSION_FILTER_SLOW`.
    """
    if stiffness is None:
        return TENSION_FILTER_SLOW
    tau = 0.2 / math.sqrt(stiffness / mass)
    return min(TENSION_FILTER_SLOW, max(TENSION_FILTER_FAST, tau))


def elastic_tension(distance: float, length: float, stiffness: float) -> float:
    """Tension k (D - l) of an elastic cable of unstretched length l [m] and spring constant
    k [N/m] whose ends are D [m] apart; 0 when slack (D <= l) [N]."""
    x = distance - length
    return stiffness * x if x > 0.0 else 0.0


@dataclass(frozen=True)
class CableEstimate:
    """The cable as the estimated pose sees it.

    Attributes
    ----------
    distance : float
        Distance anchor -> attachment point D [m].
    stretch : float
        D - l (negative when slack) [m].
    elastic_tension : float or None
        k max(D - l, 0) for an elastic cable, None for an inextensible one [N].
    """

    distance: float
    stretch: float
    elastic_tension: float | None


@dataclass(frozen=True)
class TensionEstimate:
    """Output of :class:`TensionEstimator` at one instant.

    Attributes
    ----------
    raw : float
        Unfiltered estimate [N].
    filtered : float
        Low-pass filtered estimate [N].
    taut : bool
        The filtered tension has stayed above the threshold for the dwell time.
    """

    raw: float
    filtered: float
    taut: bool


class ThresholdDwell:
    """A value counts as "on" once it has stayed above ``threshold`` for ``dwell`` seconds.

    The supervisor's rule for a taut cable (docs/theory.md section 8); any drop below the
    threshold restarts the timer.
    """

    def __init__(self, threshold: float, dwell: float):
        self.threshold = threshold
        self.dwell = dwell
        self._above_since: float | None = None

    def reset(self) -> None:
        self._above_since = None

    def update(self, t: float, value: float) -> bool:
        """Feed ``value`` at time ``t`` [s]; return whether the rule holds now."""
        if value > self.threshold:
            if self._above_since is None:
                self._above_since = t
        else:
            self._above_since = None
        return self._above_since is not None and t - self._above_since >= self.dwell - 1e-12


class TensionEstimator:
    """Filtered cable-tension estimate and the "taut" rule of the supervisor.

    Parameters
    ----------
    mass : float
        Vehicle mass [kg].
    threshold : float
        Tension above which the cable counts as taut [N].
    dwell : float
        Time the filtered tension must stay above ``threshold`` [s].
    time_constant : float
        First-order low-pass time constant [s].
    """

    def __init__(self, mass: float, threshold: float, dwell: float, time_constant: float = 0.05):
        if mass <= 0 or threshold < 0 or dwell < 0 or time_constant < 0:
            raise ValueError("mass > 0, threshold >= 0, dwell >= 0, time_constant >= 0 required")
        self.mass = mass
        self.time_constant = time_constant
        self.rule = ThresholdDwell(threshold, dwell)
        self.reset()

    def reset(self) -> None:
        """Forget the filter state and the dwell timer."""
        self._t: float | None = None
        self._filtered = 0.0
        self._dt, self._a = math.nan, 0.0
        self.rule.reset()
        self.taut = False
        """The taut rule's result at the last sample."""

    def update(
        self,
        t: float,
        thrust: float,
        specific_force_B: ArrayLike,
        d_B: ArrayLike | None = None,
    ) -> TensionEstimate:
        """Add one sample at time ``t`` [s]; see :func:`tension_from_forces` for the inputs."""
        return self.filter(t, tension_from_forces(thrust, specific_force_B, self.mass, d_B))

    def filter(self, t: float, raw: float) -> TensionEstimate:
        """Add one instantaneous estimate ``raw`` [N] at time ``t`` [s] (first-order
        low-pass, exact for a sample held over the interval) and apply the taut rule."""
        filtered = self.filter_value(t, raw)
        return TensionEstimate(raw, filtered, self.taut)

    def filter_value(self, t: float, raw: float) -> float:
        """:meth:`filter` without its record (the estimator's control-rate path): returns
        the filtered estimate [N]; the taut rule's result is :attr:`taut`."""
        if self._t is None or self.time_constant == 0.0:
            self._filtered = raw
        else:
            dt = t - self._t
            if dt != self._dt:  # the (usually constant) interval: its factor once
                self._dt = dt
                self._a = 1.0 - math.exp(-max(dt, 0.0) / self.time_constant)
            self._filtered += self._a * (raw - self._filtered)
        self._t = t
        self.taut = self.rule.update(t, self._filtered)
        return self._filtered

    @property
    def value(self) -> float:
        """Current filtered estimate [N]."""
        return self._filtered


class TensionTare:
    """The tension estimate's bias, measured on a line hanging free and taken off later
    readings (docs/mechanism.md, *Tension, truth and belief*).

    The estimate f_L = d_B . (f_R e3 - m f_B) (module docstring) is built on the believed
    thrust coefficient c_f and mass m. With c_f believed (1 + e_c) times the true one
    and m (1 + e_m) times, a hover that carries the weight reads about (e_c - e_m) m g
    more along the thrust axis e3: 0.85 N in the pilot campaign's draw 50-00007 (+4.6 %,
    -3.9 %), of the order of the tension threshold (1 N) and four times the hanging
    line's weight. A line hanging free pulls the attachment point straight down with its
    believed weight W (the line and the hook), which the estimate reads as W (d . z_W),
    d the unit link direction from the believed anchor. The tare fits the bias as a force
    beta along the thrust axis, r_i = W (d_i . z_W) + beta (d_i . z_B,i) over samples
    r_i of the estimate, in least squares:

        beta = sum c_i (r_i - W a_i) / sum c_i^2,   a_i = d_i . z_W,  c_i = d_i . z_B,i

    and takes it off later readings along the current direction: f_L - beta (d . z_B).
    At another thrust f_R the c_f part leaves e_c (f_R - f_R,tare) (d . z_B) (a few
    hundredths of a newton for the pull of a taut take-up); the readings stay what the
    robot measures, corrected by what it measured and believes.

    Parameters
    ----------
    weight : float
        Believed weight of what hangs on the line while it hangs free, W [N] (0 for a
        cable with nothing hanging on it).
    """

    def __init__(self, weight: float) -> None:
        if not weight >= 0.0:
            raise ValueError("weight >= 0 required")
        self.weight = weight
        self.bias: float | None = None
        """Fitted bias beta along the thrust axis [N] (None before the first tare)."""
        self.samples = 0
        """Samples of the tare under way."""
        self._sum_cr = self._sum_cc = 0.0

    def add(self, reading: float, d_z_W: float, d_z_B: float) -> None:
        """Add one reading ``reading`` [N] of the line hanging free, with the unit link
        direction's vertical part d . z_W and its part along the thrust axis d . z_B [-]."""
        self._sum_cr += d_z_B * (reading - self.weight * d_z_W)
        self._sum_cc += d_z_B * d_z_B
        self.samples += 1

    def close(self) -> float | None:
        """End the tare: :attr:`bias` from the samples added since the last close (kept as
        it was if there were none, or the thrust axis was across the link) [N]."""
        if self.samples and self._sum_cc > 0.0:
            self.bias = self._sum_cr / self._sum_cc
        self.samples = 0
        self._sum_cr = self._sum_cc = 0.0
        return self.bias

    def correct(self, reading: float, d_z_B: float) -> float:
        """``reading`` [N] less the bias along the link direction, beta (d . z_B) [N]
        (unchanged before the first tare)."""
        return reading if self.bias is None else reading - self.bias * d_z_B


class MotorLagThrust:
    """Predicts the rotors' actual thrust from commanded speeds through the first-order lag.

    w' = (w_cmd - w)/tau_m, f_i = c_f w_i^2; the same model the plant uses. Unlike
    :class:`tetherland.models.RotorModel` (the controllers' model, which limits commands
    to [w_min, w_max]) a zero command here means motors off, as on the real ESCs.
    Four rotors, kept as plain floats (it runs twice per control tick).
    """

    def __init__(self, thrust_coefficient: float, time_constant: float, w0: ArrayLike):
        self.c_f = thrust_coefficient
        self.tau = time_constant
        self._w = [float(v) for v in np.asarray(w0, dtype=float).reshape(4)]
        self._dt = -1.0
        self._decay = 0.0

    @property
    def w(self) -> FloatArray:
        """Current rotor speeds [rad/s] (copy)."""
        return np.array(self._w)

    @property
    def speeds(self) -> list[float]:
        """Current rotor speeds as four floats [rad/s] (the live list: read, never keep or
        write)."""
        return self._w

    @property
    def total_thrust(self) -> float:
        """f_R = sum c_f w_i^2 at the current speeds [N]."""
        w0, w1, w2, w3 = self._w
        return self.c_f * (w0 * w0 + w1 * w1 + w2 * w2 + w3 * w3)

    def step(self, w_cmd: ArrayLike, dt: float) -> FloatArray:
        """Advance by ``dt`` [s] with the commands held; return rotor thrusts [N]."""
        self.advance([float(v) for v in np.asarray(w_cmd, dtype=float).reshape(4)], dt)
        return self.c_f * np.square(self._w)

    def advance(self, w_cmd: list[float], dt: float) -> float:
        """:meth:`step` on four floats; returns the total thrust [N] (the hot path).

        w(t + dt) = w_cmd + (w - w_cmd) exp(-dt/tau_m) (exact for a held command).
        """
        if self.tau <= 0.0:
            self._w = list(w_cmd)
        else:
            if dt != self._dt:  # the decay for the (usually constant) step, computed once
                self._dt, self._decay = dt, math.exp(-dt / self.tau)
            a = self._decay
            w = self._w
            c0, c1, c2, c3 = w_cmd
            w0, w1, w2, w3 = w
            self._w = [c0 + (w0 - c0) * a, c1 + (w1 - c1) * a, c2 + (w2 - c2) * a,
                       c3 + (w3 - c3) * a]  # fmt: skip
        w0, w1, w2, w3 = self._w  # total_thrust, inlined
        return self.c_f * (w0 * w0 + w1 * w1 + w2 * w2 + w3 * w3)


# ------------------------------------------------------------------ compiled forms
# The packed state of the compiled motor lag (:func:`pack_motor_lag`), in order:
M_SPEEDS = slice(0, 4)
"""Rotor speeds w [rad/s] (:attr:`MotorLagThrust.speeds`)."""
M_COMMAND = slice(4, 8)
"""Commanded speeds w_cmd held [rad/s]."""
M_DT = 8
"""Step of the cached decay [s] (-1: none yet)."""
M_DECAY = 9
"""exp(-dt/tau_m) of that step [-]."""
M_THRUST_COEFFICIENT = 10
"""c_f [N/(rad/s)^2]."""
M_TIME_CONSTANT = 11
"""tau_m [s]."""
MOTOR_WIDTH = 12


def pack_motor_lag(thrust_coefficient: float, time_constant: float, w0: ArrayLike) -> FloatArray:
    """The state of :func:`motor_lag_advance`: :class:`MotorLagThrust` (``thrust_coefficient``
    [N/(rad/s)^2], ``time_constant`` [s], speeds ``w0`` [rad/s]) packed, ``w0`` commanded
    (held until the first command)."""
    m = np.zeros(MOTOR_WIDTH)
    m[M_SPEEDS] = m[M_COMMAND] = np.asarray(w0, dtype=float).reshape(4)
    m[M_DT] = -1.0
    m[M_THRUST_COEFFICIENT], m[M_TIME_CONSTANT] = thrust_coefficient, time_constant
    return m


@njit(cache=True)
def motor_lag_total_thrust(m: FloatArray) -> float:
    """:attr:`MotorLagThrust.total_thrust` of the packed state ``m`` [N]."""
    w0, w1, w2, w3 = m[0], m[1], m[2], m[3]
    return m[M_THRUST_COEFFICIENT] * (w0 * w0 + w1 * w1 + w2 * w2 + w3 * w3)


@njit(cache=True)
def motor_lag_advance(m: FloatArray, dt: float) -> float:
    """:meth:`MotorLagThrust.advance` by ``dt`` [s] with the command ``m[M_COMMAND]`` held,
    on the packed state ``m`` (in place); returns the total thrust [N]."""
    tau = m[M_TIME_CONSTANT]
    if tau <= 0.0:
        for i in range(4):
            m[i] = m[4 + i]
    else:
        if dt != m[M_DT]:  # the decay for the (usually constant) step, computed once
            m[M_DT] = dt
            m[M_DECAY] = math.exp(-dt / tau)
        a = m[M_DECAY]
        for i in range(4):
            c = m[4 + i]
            m[i] = c + (m[i] - c) * a
    return motor_lag_total_thrust(m)


# The packed state of the compiled tension filter and taut rule (:func:`pack_tension_filter`):
F_T = 0
"""Time of the last sample [s] (NaN: none yet)."""
F_VALUE = 1
"""Filtered estimate [N]."""
F_DT = 2
"""Interval of the cached factor [s] (NaN: none yet)."""
F_FACTOR = 3
"""1 - exp(-dt/tau) of that interval [-]."""
F_TIME_CONSTANT = 4
"""Low-pass time constant tau [s]."""
F_THRESHOLD = 5
"""Taut threshold [N]."""
F_DWELL = 6
"""Taut dwell [s]."""
F_ABOVE_SINCE = 7
"""Time since which the filtered value is above the threshold [s] (NaN: it is not)."""
F_TAUT = 8
"""The taut rule's result at the last sample (1 or 0)."""
FILTER_WIDTH = 9


def pack_tension_filter(threshold: float, dwell: float, time_constant: float) -> FloatArray:
    """The state of :func:`tension_filter_step`: a reset :class:`TensionEstimator`
    (``threshold`` [N], ``dwell`` [s], ``time_constant`` [s]) packed."""
    f = np.zeros(FILTER_WIDTH)
    f[F_T] = f[F_DT] = f[F_ABOVE_SINCE] = math.nan
    f[F_TIME_CONSTANT], f[F_THRESHOLD], f[F_DWELL] = time_constant, threshold, dwell
    return f


@njit(cache=True)
def tension_filter_step(f: FloatArray, t: float, raw: float) -> float:
    """:meth:`TensionEstimator.filter_value` (the low-pass and the
    :class:`ThresholdDwell` rule) on the packed state ``f`` (in place): the raw estimate
    ``raw`` [N] at ``t`` [s]; returns the filtered estimate [N]."""
    tc = f[F_TIME_CONSTANT]
    if math.isnan(f[F_T]) or tc == 0.0:
        f[F_VALUE] = raw
    else:
        dt = t - f[F_T]
        if dt != f[F_DT]:  # the (usually constant) interval: its factor once
            f[F_DT] = dt
            f[F_FACTOR] = 1.0 - math.exp(-max(dt, 0.0) / tc)
        f[F_VALUE] += f[F_FACTOR] * (raw - f[F_VALUE])
    f[F_T] = t
    value = f[F_VALUE]
    if value > f[F_THRESHOLD]:
        if math.isnan(f[F_ABOVE_SINCE]):
            f[F_ABOVE_SINCE] = t
    else:
        f[F_ABOVE_SINCE] = math.nan
    since = f[F_ABOVE_SINCE]
    taut = not math.isnan(since) and t - since >= f[F_DWELL] - 1e-12
    f[F_TAUT] = 1.0 if taut else 0.0
    return value
