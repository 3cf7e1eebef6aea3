"""Do-nothing implementations of the roles in :mod:`tetherland.interfaces`.

For wiring, tests and benchmarks (like rotorpy's ``NullEstimator``): an estimator that
passes the ground truth, an open-loop controller holding constant rotor speeds, and a
reference source that never changes.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from tetherland import GRAVITY
from tetherland.config import VehicleConfig
from tetherland.interfaces import (
    Command,
    ControlMode,
    ImuSample,
    MocapSample,
    Reference,
    StateEstimate,
)


class TruthEstimator:
    """Returns the ground truth as the estimate; ignores measurements.

    Parameters
    ----------
    source : callable
        Returns the true :class:`StateEstimate` at the current control tick (the runner
        passes its own; outside a runner use ``Plant.truth_estimate``).
    """

    def __init__(self, source: Callable[[], StateEstimate]) -> None:
        self._source = source

    def predict(self, imu: ImuSample) -> None:
        """Ignored."""

    def update(self, mocap: MocapSample) -> None:
        """Ignored."""

    def estimate(self) -> StateEstimate:
        return self._source()


class ConstantSpeedController:
    """Open loop: the same rotor speeds at every tick (hover for m g by default).

    Parameters
    ----------
    rotor_speeds : (4,) array
        Commanded speeds [rad/s].
    thrust : float, optional
        Total thrust these speeds mean, for the log [N].
    """

    def __init__(self, rotor_speeds: ArrayLike, thrust: float | None = None) -> None:
        speeds = np.array(rotor_speeds, dtype=float)
        if speeds.shape != (4,) or not np.all(np.isfinite(speeds)) or np.any(speeds < 0):
            raise ValueError(f"rotor_speeds must be 4 finite non-negative values, got {speeds}")
        speeds.setflags(write=False)
        self._command = Command(rotor_speeds=speeds, thrust=thrust)

    @classmethod
    def hover(cls, vehicle: VehicleConfig, thrust: float | None = None) -> ConstantSpeedController:
        """Equal rotor speeds giving total thrust ``thrust`` (default m g) [N]."""
        f_R = vehicle.mass * GRAVITY if thrust is None else float(thrust)
        if f_R < 0:
            raise ValueError(f"thrust must be >= 0, got {f_R}")
        return cls(np.full(4, math.sqrt(f_R / 4.0 / vehicle.thrust_coefficient)), thrust=f_R)

    @classmethod
    def motors_off(cls) -> ConstantSpeedController:
        return cls(np.zeros(4), thrust=0.0)

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        return self._command


class ConstantReference:
    """The same reference at every tick (its ``t`` updated).

    Parameters
    ----------
    mode : ControlMode
    p_W : (3,) array, optional
        Position to hold [m].
    yaw : float
        Heading [rad].
    phase : int
        Phase code to log.
    """

    def __init__(
        self,
        mode: ControlMode = ControlMode.FREE_FLIGHT,
        p_W: ArrayLike | None = None,
        yaw: float = 0.0,
        phase: int = 0,
    ) -> None:
        self._mode = mode
        self._p = None if p_W is None else np.asarray(p_W, dtype=float).reshape(1, 3)
        self._yaw = float(yaw)
        self._phase = int(phase)

    def reference(self, t: float, estimate: StateEstimate) -> Reference:
        return Reference(t=t, mode=self._mode, phase=self._phase, p_W=self._p, yaw=self._yaw)
