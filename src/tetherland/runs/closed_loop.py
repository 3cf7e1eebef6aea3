"""One closed-loop run of a landing method in MuJoCo: plant, sensors, UKF, method, judge.

The plant simulates the *truth* scenario; the method plans and the estimator, controller
and supervisor run on the *belief* (what the robot knows). After the run the method
reports its record and the one judge (:func:`tetherland.verdict.judge`) measures the
landing on the plant's truth. Every method runs through :func:`run_mission`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any, Protocol

from tetherland.config import Scenario
from tetherland.control.stack import with_aero_belief
from tetherland.errors import InfeasibleError
from tetherland.estimation import UkfEstimator
from tetherland.geometry import FloatArray
from tetherland.interfaces import Estimator, InnerLoop
from tetherland.methods import ControllerChoice, Flight, Planners, get_method
from tetherland.provenance import provenance
from tetherland.sim import Plant, Runner, SimLog
from tetherland.sim.faults import faulty_belief
from tetherland.state import RigidBodyState
from tetherland.verdict import RunRecord, Verdict, judge, not_flown

EstimatorFactory = Callable[[Scenario, RigidBodyState, float, FloatArray | None], Estimator | None]
"""``factory(belief, initial_state, t0, rotor_speeds0) -> Estimator`` (None: the truth)."""


class InnerLoopFactory(Protocol):
    """Makes the flight controller under the method's controller (e.g. the firmware)."""

    def __call__(self, truth: Scenario, belief: Scenario) -> InnerLoop:
        """The inner loop for a run: hardware from ``truth``, knowledge from ``belief``."""
        ...

    def describe(self) -> dict[str, Any]:
        """What flies the inner loop, for the run's provenance (name, versions, settings)."""
        ...


def ukf_estimator(
    belief: Scenario, initial: RigidBodyState, t0: float, rotor_speeds0: FloatArray | None
) -> Estimator:
    """The default estimator: the UKF with the cable-tension estimator (section 8)."""
    return UkfEstimator(belief, initial, t0, rotor_speeds0=rotor_speeds0)


def truth_estimator(
    belief: Scenario, initial: RigidBodyState, t0: float, rotor_speeds0: FloatArray | None
) -> None:
    """No estimator: the controllers and the supervisor see the plant's truth."""
    return None


@dataclass(frozen=True)
class RunResult:
    """Everything one run produced.

    Attributes
    ----------
    method : str
        The landing method's registered name.
    record : RunRecord
        What the method reported (``run.json``).
    verdict : Verdict
        The judge's verdict (``summary.json``).
    log : SimLog or None
        One row per control tick (None when the run could not start: no plan).
    plan : object or None
        The method's plan (:class:`~tetherland.mission.MissionPlan`, or the perching
        :class:`~tetherland.planning.perching.PerchResult`).
    flight : Flight or None
        The roles that flew (the supervisor is ``flight.reference``).
    plant_scenario, belief_scenario : Scenario
        What the plant simulated and what the robot believed.
    """

    method: str
    record: RunRecord
    verdict: Verdict
    log: SimLog | None
    plan: Any
    flight: Flight | None
    plant_scenario: Scenario
    belief_scenario: Scenario

    @property
    def summary(self) -> dict[str, Any]:
        """The verdict as the ``summary.json`` document."""
        return self.verdict.to_dict()

    @property
    def success(self) -> bool:
        return self.verdict.success

    @property
    def reference(self) -> Any:
        """The method's reference source (the mission supervisor for the tethered method)."""
        return None if self.flight is None else self.flight.reference


def run_mission(
    scenario: Scenario,
    belief: Scenario | None = None,
    *,
    method: str = "tethered",
    controller: ControllerChoice = None,
    seed: int = 0,
    estimator: EstimatorFactory = ukf_estimator,
    planners: Planners | None = None,
    plant: Plant | None = None,
    observers: Sequence[Callable[[float, Plant], None]] = (),
    plant_setup: Callable[[Plant], None] | None = None,
    on_flight: Callable[[Flight], None] | None = None,
    inner_loop: InnerLoopFactory | None = None,
) -> RunResult:
    """Fly one run of a landing method closed loop and judge it.

    Parameters
    ----------
    scenario : Scenario
        The truth the plant simulates (and the verdict's geometry).
    belief : Scenario, optional
        What the robot believes (planner, controllers, estimator, supervisor); default:
        the truth.
    method : str
        Registered landing method (:func:`tetherland.methods.method_names`).
    controller : str or Controller, optional
        Tethered method: ``"hierarchical"`` or ``"dfl"`` (default from the belief) or your
        own tethered :class:`~tetherland.interfaces.Controller`; contact-free method: your
        own controller instead of the feed-forward tracker.
    seed : int
        Seed of the sensor noise and of every random disturbance of the plant.
    estimator : callable
        Builds the estimator from the belief (:data:`EstimatorFactory`); default the UKF,
        :func:`truth_estimator` for the plant's truth.
    planners : Planners, optional
        Reuse compiled planners between runs.
    plant : Plant, optional
        Reuse a plant built for ``scenario``.
    observers : sequence of callables
        Called as ``observer(t, plant)`` after each control tick (progress, wind, video).
    plant_setup : callable, optional
        Called with the plant before the run (e.g. to add wind).
    on_flight : callable, optional
        Called with the method's :class:`~tetherland.methods.Flight` before it flies (to
        watch the supervisor's phase, for example).
    inner_loop : InnerLoopFactory, optional
        A flight controller under the method's controller (``tetherland.firmware``): the
        controllers become its outer loop.
    """
    belief = belief or scenario
    if scenario.faults.active or belief.faults.active:  # the robot never knows the faults
        belief = faulty_belief(belief, scenario.faults)
    how = get_method(method)
    if how.name == "tethered":
        controller = controller or belief.controller.kind
    name = controller if controller is None or isinstance(controller, str) else (
        type(controller).__name__
    )
    base = RunRecord(
        method=how.name, seed=int(seed), controller=name,
        truth=scenario.model_dump(mode="json"), belief=belief.model_dump(mode="json"),
        expects=how.expects,
        provenance=provenance(scenario, seed=seed, extra={
            "method": how.name, "controller": name,
            **({} if inner_loop is None else {"inner_loop": inner_loop.describe()})}),
    )  # fmt: skip
    plant = Plant(scenario) if plant is None else plant
    if plant_setup is not None:
        plant_setup(plant)
    planners = planners or Planners()
    try:
        plan = how.plan(belief, plant.start_state(), planners)
    except InfeasibleError as err:
        return RunResult(how.name, base, not_flown(base, str(err)), None, None, None, scenario,
                         belief)  # fmt: skip
    flight = how.fly(plan, belief, controller)
    if on_flight is not None:
        on_flight(flight)
    controller_ = with_aero_belief(flight.controller, belief)
    runner = Runner(
        scenario, controller_,
        estimator=estimator(belief, flight.initial_state, 0.0, flight.rotor_speeds),
        reference=flight.reference, seed=seed, plant=plant,
        diagnostic_keys=flight.diagnostic_keys, observers=observers,
        inner_loop=None if inner_loop is None else inner_loop(scenario, belief),
    )  # fmt: skip
    wall0 = time.perf_counter()
    log = runner.run(flight.duration, initial_state=flight.initial_state,
                     rotor_speeds=flight.rotor_speeds)  # fmt: skip
    wall = time.perf_counter() - wall0
    # judged (and drawn, exported) as the log file holds it: `judge` on the saved run
    # gives this verdict exactly (rounded in place: the runner's log is this run's alone)
    log = log.round_to_storage()
    t_end = float(log["t"][-1]) if len(log) else 0.0
    record = how.record(plan, flight, t_end, replace(base, wall_time_s=wall))
    return RunResult(how.name, record, judge(log, record), log, plan, flight, scenario, belief)

