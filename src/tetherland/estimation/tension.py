"""Cable tension from thrust and the accelerometer (docs/theory.md section 8).

Newton in F_B with the IMU at the centre of mass and no contact:
    m a_m = f_R e3 - f_L d_B,     d_B = R_BW d  (d: unit link direction, anchor -> robot)
so  f_L = d_B . (f_R e3 - m a_m)  (projection on the link), or, when d is unknown,
f_L = ||f_R e3 - m a_m||. The thrust f_R is the rotors' actual thrust, predicted from the
commanded speeds through the motor lag; the estimate is low-pass filtered.
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
