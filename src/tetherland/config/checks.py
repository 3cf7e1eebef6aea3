"""Checks across sections that every command applies before anything is planned or flown.

Each check is a plain function of a validated scenario's sections (:class:`Sections`) or
of the few values it needs, raising :class:`ValueError` with one line that names the
field first; :class:`~tetherland.config.Scenario` runs them all, so ``show``, ``plan``,
``analyze``, ``mission`` and ``campaign`` accept and reject the same files. The physics
simulation's rate schedule (:class:`tetherland.sim.runner.Schedule`) uses the same rate
rules (:func:`ticks_per_sample`, :func:`mocap_rate`).
"""

from __future__ import annotations

import math
from fractions import Fraction
from typing import Protocol

from tetherland import GRAVITY
from tetherland.config.control import ControllerConfig
from tetherland.config.mission import MissionConfig
from tetherland.config.physical import TetherConfig, VehicleConfig
from tetherland.config.planning import PlannerConfig
from tetherland.config.sensors import SensorsConfig
from tetherland.config.simulation import RATE_TOL, SimConfig


class Sections(Protocol):
    """The sections the checks read: a :class:`~tetherland.config.Scenario` has them (a
    protocol, so that this module does not import the scenario that runs it)."""

    @property
    def vehicle(self) -> VehicleConfig: ...
    @property
    def tether(self) -> TetherConfig: ...
    @property
    def sensors(self) -> SensorsConfig: ...
    @property
    def planner(self) -> PlannerConfig: ...
    @property
    def controller(self) -> ControllerConfig: ...
    @property
    def mission(self) -> MissionConfig: ...
    @property
    def sim(self) -> SimConfig: ...


MOCAP_TOL = 1e-6
"""Relative tolerance of the motion-capture rate's exact fraction [-]."""
MOCAP_DENOMINATOR = 10_000
"""Largest denominator of the motion-capture rate as an exact fraction of 1 Hz [-]."""


def check_name(name: str) -> str:
    """A scenario name is a label: it may not name a path (``/``, ``\\``, ``.``, ``..``) nor
    hold control characters (NUL, newline, ...), since output folders are named after it."""
    bad = [c for c in name if ord(c) < 32 or ord(c) == 127]
    if bad:
        raise ValueError(f"must be a label without control characters (got {name[:40]!r})")
    if "/" in name or "\\" in name or name in (".", ".."):
        raise ValueError(
            f"must be a label, not a path: no '/', '\\', '.' or '..' (got {name[:40]!r})"
        )
    return name


def ticks_per_sample(rate_hz: float, steps_per_second: int, what: str) -> int:
    """Physics steps per sample of a sensor or loop running at ``rate_hz``.

    Raises
    ------
    ValueError
        Naming ``what`` when ``rate_hz`` is not the physics rate divided by an integer.
    """
    n = steps_per_second / rate_hz
    if not math.isfinite(n) or abs(n - round(n)) > RATE_TOL * n or round(n) < 1:
        raise ValueError(
            f"{what} = {rate_hz:g} Hz must divide the physics rate {steps_per_second} Hz "
            "(an integer number of physics steps per sample)"
        )
    return round(n)


def mocap_rate(rate_hz: float, steps_per_second: int) -> Fraction:
    """The motion-capture rate as an exact fraction [Hz] (samples fall on physics steps).

    Raises
    ------
    ValueError
        When it exceeds the physics rate, or is no fraction with a denominator up to
        :data:`MOCAP_DENOMINATOR` (e.g. 1e-300 Hz).
    """
    if rate_hz > steps_per_second:
        raise ValueError(
            f"sensors.mocap.rate_hz = {rate_hz:g} Hz exceeds the physics rate {steps_per_second} Hz"
        )
    exact = Fraction(rate_hz).limit_denominator(MOCAP_DENOMINATOR)
    if exact <= 0 or abs(float(exact) - rate_hz) > MOCAP_TOL * rate_hz:
        raise ValueError(
            f"sensors.mocap.rate_hz = {rate_hz:g} Hz must be a fraction p/q Hz with "
            f"q <= {MOCAP_DENOMINATOR} (e.g. 120 or 0.5)"
        )
    return exact


def check_rates(scenario: Sections) -> None:
    """IMU and control rates divide the physics rate; the mocap rate is an exact fraction."""
    n = scenario.sim.steps_per_second
    ticks_per_sample(scenario.sensors.imu.rate_hz, n, "sensors.imu.rate_hz")
    ticks_per_sample(scenario.controller.rate_hz, n, "controller.rate_hz")
    mocap_rate(scenario.sensors.mocap.rate_hz, n)


def check_timing(scenario: Sections) -> None:
    """The fixed holds of a tethered mission fit in ``mission.time_limit``.

    Deploying, spinning up and the final hold on the pad alone take ``deploy_time +
    spinup_time + done_hold_time``; a mission that cannot end before ``time_limit``
    would be cut off (the plan adds the flight legs: :func:`tetherland.mission.plan_mission`).
    """
    m = scenario.mission
    holds = m.deploy_time + m.spinup_time + m.done_hold_time
    if holds >= m.time_limit:
        raise ValueError(
            f"mission.deploy_time = {m.deploy_time:g} s: with spinup_time {m.spinup_time:g} s "
            f"and done_hold_time {m.done_hold_time:g} s the mission holds {holds:g} s, not less "
            f"than mission.time_limit = {m.time_limit:g} s; shorten deploy_time or raise "
            "time_limit"
        )


def stretch_tension_limit(scenario: Sections) -> float:
    """Largest cable tension the stretching pull can hold, whatever the direction [N].

    The free-flight position loop (stiffness k_p = m w_n^2) pulls towards a point
    ``pull = planner.start_tension / k_p + mission.stretch.pull_margin`` beyond the cable length;
    an elastic cable (k = EA/l) gives way by T/k, so the spring part holds
    k_p pull / (1 + k_p/k); the position integral adds at most its clamp
    (``integral_force_max`` m g per axis, sqrt(3) times that along any direction). The
    rotors' total thrust 4 f_max less the weight, pulling straight down, bounds it too.
    """
    v, ff = scenario.vehicle, scenario.controller.free_flight
    k_p = v.mass * ff.position_frequency**2
    pull = scenario.planner.start_tension / k_p + scenario.mission.stretch.pull_margin
    k = scenario.tether.stiffness
    spring = k_p * pull if k is None else k_p * pull / (1.0 + k_p / k)
    integral = math.sqrt(3.0) * ff.integral_force_max * v.mass * GRAVITY
    rotors = 4.0 * v.f_max + v.mass * GRAVITY
    return min(spring + integral, rotors)


def check_tension_threshold(scenario: Sections) -> None:
    """``mission.stretch.tension_threshold`` is a tension the stretching pull can reach."""
    threshold = scenario.mission.stretch.tension_threshold
    limit = stretch_tension_limit(scenario)
    if threshold >= limit:
        raise ValueError(
            f"mission.stretch.tension_threshold = {threshold:g} N is not below {limit:.3g} N, the "
            "largest tension the stretching pull can hold (planner.start_tension, "
            "mission.stretch.pull_margin, the free-flight gains and the rotors): the hook would "
            f"count as missed; use a threshold below planner.start_tension = "
            f"{scenario.planner.start_tension:g} N"
        )
