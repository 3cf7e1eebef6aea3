"""Body-rate step responses on the plant: tetherland's own inner loop against the firmware's.

The vehicle hovers clear of every surface under the free-flight controller; at ``start``
the controller's torque becomes the rate part of tetherland's attitude law,

    tau = J k_w (w_step - w) + w x J w        (k_w of ``controller.free_flight``),

for ``duration`` seconds. Without an inner loop the rotors realise that torque (tetherland's
own inner loop: a rate loop of bandwidth k_w behind the motors' lag). Through the firmware
the hand-over turns it into the rate setpoint w + k_w (w_step - w) / K, which is w_step
when the firmware's gain K equals k_w, and Betaflight's rate loop does the rest: the radio
frame, its filters, its mixer and the same motors. The response is the plant's true body
rate along the stepped axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tetherland import GRAVITY
from tetherland.config import Scenario
from tetherland.control.attitude import AttitudeGains
from tetherland.control.free_flight import FreeFlightController
from tetherland.control.mixer import Mixer
from tetherland.errors import SimulationError
from tetherland.geometry import FloatArray
from tetherland.interfaces import Command, InnerLoop, Reference, StateEstimate
from tetherland.rotations import cross3
from tetherland.sim import Plant, Runner, RunStatus
from tetherland.sim.baselines import ConstantReference
from tetherland.state import RigidBodyState


@dataclass(frozen=True)
class RateStep:
    """A body-rate step.

    Attributes
    ----------
    axis : int
        0 roll, 1 pitch, 2 yaw (F_B).
    amplitude : float
        Step size [rad/s].
    start : float
        Time of the step, a control tick [s].
    duration : float
        How long the step is held [s].
    """

    axis: int = 0
    amplitude: float = 1.0
    start: float = 1.0
    duration: float = 0.3


@dataclass(frozen=True)
class StepResponse:
    """The body rate after a step, normalised by its amplitude.

    Attributes
    ----------
    t : (n,) array
        Time since the step, at the control ticks of the step [s].
    y : (n,) array
        (w - w_before) / amplitude along the axis [-].
    """

    t: FloatArray
    y: FloatArray

    def time_to(self, fraction: float) -> float:
        """First time the response reaches ``fraction`` of the step, interpolated linearly
        between the samples [s] (NaN: never)."""
        hit = np.flatnonzero(self.y >= fraction)
        if not hit.size:
            return math.nan
        i = int(hit[0])
        if i == 0:
            return float(self.t[0])
        t0, t1, y0, y1 = self.t[i - 1], self.t[i], self.y[i - 1], self.y[i]
        return float(t0 + (fraction - y0) * (t1 - t0) / (y1 - y0))

    @property
    def overshoot(self) -> float:
        """Peak above the step [-]."""
        return float(self.y.max() - 1.0)

    @property
    def final(self) -> float:
        """Mean of the last 20 ms [-]."""
        return float(self.y[self.t >= self.t[-1] - 0.02].mean())


class _RateStepController:
    """Free-flight hold, and the rate law of the step while it lasts (a Controller)."""

    def __init__(self, scenario: Scenario, step: RateStep):
        self.hold = FreeFlightController(scenario)
        self.mixer = Mixer(scenario.vehicle)
        self.J = np.asarray(scenario.vehicle.inertia, dtype=float)
        self.k_w = AttitudeGains.from_config(scenario.controller.free_flight).k_w
        self.step = step
        self.w_step = np.zeros(3)
        self.w_step[step.axis] = step.amplitude

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        command = self.hold.update(t, estimate, reference)
        s = self.step
        if s.start - 1e-9 <= t < s.start + s.duration - 1e-9:
            w = estimate.body.omega_B
            tau = self.J * self.k_w * (self.w_step - w) + cross3(w, self.J * w)
            command = self.mixer.command(command.thrust, tau)
        return command


def rate_step_response(
    scenario: Scenario,
    step: RateStep,
    *,
    inner_loop: InnerLoop | None = None,
    p_W: FloatArray | None = None,
    seed: int = 0,
) -> StepResponse:
    """Fly ``step`` from hover at ``p_W`` and return the plant's response.

    Parameters
    ----------
    scenario : Scenario
        Vehicle, sensors and gains (the robot's belief is the truth here).
    step : RateStep
    inner_loop : InnerLoop, optional
        The firmware (None: tetherland's own inner loop).
    p_W : (3,) array, optional
        Hover point [m] (default: 2 m above the start pad, clear of the surface).
    seed : int
        Sensor-noise seed.
    """
    v = scenario.vehicle
    plant = Plant(scenario)
    p_W = plant.start_state().p_W + np.array([0.0, 0.0, 2.0]) if p_W is None else np.asarray(p_W)
    runner = Runner(
        scenario, _RateStepController(scenario, step), plant=plant,
        reference=ConstantReference(p_W=p_W), seed=seed, inner_loop=inner_loop,
    )  # fmt: skip
    hover = math.sqrt(v.mass * GRAVITY / 4.0 / v.thrust_coefficient)
    level = RigidBodyState(p_W, np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3))
    log = runner.run(step.start + step.duration + 0.01, initial_state=level,
                     rotor_speeds=np.full(4, hover))  # fmt: skip
    if log.status != RunStatus.COMPLETED:
        raise SimulationError(f"the step-response flight ended early ({log.status}): "
                              f"{log.metadata.get('message')}")
    t = log["t"]
    w = log["omega_B"][:, step.axis]
    during = (t >= step.start - 1e-9) & (t < step.start + step.duration - 1e-9)
    before = w[np.searchsorted(t, step.start - 1e-9) - 1]
    return StepResponse(t[during] - step.start, (w[during] - before) / step.amplitude)


__all__ = ["RateStep", "StepResponse", "rate_step_response"]
