"""Cable tension from thrust and the accelerometer (docs/theory.md section 8).

Newton in F_B with the IMU at the centre of mass and no contact:
    m a_m = f_R e3 - f_L d_B,     d_B = R_BW d  (d: unit link direction, anchor -> robot)
so  f_L = d_B . (f_R e3 - m a_m)  (projection on the link), or, when d is unknown,
f_L = ||f_R e3 - m a_m||. The thrust f_R is the rotors' actual thrust, predicted from the
commanded speeds through the motor lag; the estimate is low-pass filtered.

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
        self.rule.reset()

    def update(
        self,
        t: float,
        thrust: float,
        specific_force_B: ArrayLike,
        d_B: ArrayLike | None = None,
    ) -> TensionEstimate:
        """Add one sample at time ``t`` [s]; see :func:`tension_from_forces` for the inputs."""
        raw = tension_from_forces(thrust, specific_force_B, self.mass, d_B)
        if self._t is None or self.time_constant == 0.0:
            self._filtered = raw
        else:
            dt = max(t - self._t, 0.0)
            a = 1.0 - math.exp(-dt / self.time_constant)
            self._filtered += a * (raw - self._filtered)
        self._t = t
        return TensionEstimate(raw, self._filtered, self.rule.update(t, self._filtered))

    @property
    def value(self) -> float:
        """Current filtered estimate [N]."""
        return self._filtered


class MotorLagThrust:
    """Predicts the rotors' actual thrust from commanded speeds through the first-order lag.

    w' = (w_cmd - w)/tau_m, f_i = c_f w_i^2; the same model the plant uses. Unlike
    :class:`tetherland.models.RotorModel` (the controllers' model, which limits commands
    to [w_min, w_max]) a zero command here means motors off, as on the real ESCs.
    """

    def __init__(self, thrust_coefficient: float, time_constant: float, w0: ArrayLike):
        self.c_f = thrust_coefficient
        self.tau = time_constant
        self.w: FloatArray = np.asarray(w0, dtype=float).copy()
        self._dt = -1.0
        self._decay = 0.0

    def step(self, w_cmd: ArrayLike, dt: float) -> FloatArray:
        """Advance by ``dt`` [s] with the commands held; return rotor thrusts [N]."""
        w_cmd = np.asarray(w_cmd, dtype=float)
        if self.tau <= 0.0:
            self.w = w_cmd.copy()
        else:
            if dt != self._dt:  # the decay for the (usually constant) step, computed once
                self._dt, self._decay = dt, math.exp(-dt / self.tau)
            self.w = w_cmd + (self.w - w_cmd) * self._decay
        return self.c_f * self.w * self.w
