"""The full mission in closed loop: MuJoCo plant, sensors, UKF, controllers, supervisor."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from tetherland.config import Scenario, apply_overrides, scenario_from_dict
from tetherland.control import SwitchingController, SwitchRecord
from tetherland.estimation import UkfEstimator
from tetherland.mission.supervisor import MissionSupervisor
from tetherland.planning import Planner
from tetherland.sim import Plant, Runner, SimLog

DIAGNOSTICS = (
    "e_phi", "e_delta", "e_theta_A", "e_psi", "singular", "saturation", "e_x", "e_y", "e_z",
    "ff_tension",
)  # fmt: skip
"""Controller diagnostics recorded as ``diag.<key>`` log columns."""


@dataclass
class MissionResult:
    """Everything a mission run produced.

    Attributes
    ----------
    log : SimLog
        One row per control tick (truth, measurements, estimate, reference, command).
    supervisor : MissionSupervisor
        Phases, events and key times.
    switches : list of SwitchRecord
        Every controller switch with its command jump.
    plant_scenario, belief_scenario : Scenario
        What the plant simulated and what the robot believed.
    controller : str
        Tethered controller used.
    seed : int
    wall_time_s : float
    summary : dict
        The verdict (see :mod:`tetherland.mission.verdict`), filled by :func:`run_mission`.
    """

    log: SimLog
    supervisor: MissionSupervisor
    switches: list[SwitchRecord]
    plant_scenario: Scenario
    belief_scenario: Scenario
    controller: str
    seed: int
    wall_time_s: float
    summary: dict[str, Any] = field(default_factory=dict)


def with_overrides(scenario: Scenario, overrides: Sequence[str]) -> Scenario:
    """A validated copy of ``scenario`` with ``section.key=value`` overrides."""
    if not overrides:
        return scenario
    return scenario_from_dict(
        apply_overrides(scenario.model_dump(mode="python", exclude_none=True), overrides),
        scenario.name,
    )


def run_mission(
    scenario: Scenario,
    belief: Scenario | None = None,
    *,
    controller: str | None = None,
    seed: int = 0,
    planner: Planner | None = None,
    observers: Sequence[Callable[[float, Plant], None]] = (),
    plant_setup: Callable[[Plant], None] | None = None,
) -> MissionResult:
    """Fly the whole mission of chapter 6.6 once.

    Parameters
    ----------
    scenario : Scenario
        The truth the plant simulates.
    belief : Scenario, optional
        What the robot believes (planner, controllers, estimator, supervisor); default:
        the truth.
    controller : str, optional
        Tethered controller, ``"hierarchical"`` or ``"dfl"`` (default from the scenario).
    seed : int
        Seed of the sensor noise and of every random disturbance of the plant.
    planner : Planner, optional
        Reuse a planner (compiled solvers are cached).
    observers : sequence of callables
        Called as ``observer(t, plant)`` after each control tick (progress, video).
    plant_setup : callable, optional
        Called with the plant before the run (e.g. to add wind).
    """
    from tetherland.mission.verdict import evaluate

    belief = belief or scenario
    kind = controller or belief.controller.kind
    plant = Plant(scenario)
    if plant_setup is not None:
        plant_setup(plant)
    start = plant.start_state()
    supervisor = MissionSupervisor(belief, start, planner)
    estimator = UkfEstimator(belief, start, 0.0)
    ctrl = SwitchingController(belief, kind)
    runner = Runner(
        scenario, ctrl, estimator=estimator, reference=supervisor, seed=seed, plant=plant,
        diagnostic_keys=DIAGNOSTICS, observers=observers,
    )  # fmt: skip
    wall0 = time.perf_counter()
    log = runner.run(belief.mission.max_duration, initial_state=start)
    wall = time.perf_counter() - wall0
    supervisor.finish(float(log["t"][-1]) if len(log) else 0.0)
    result = MissionResult(
        log=log, supervisor=supervisor, switches=ctrl.switches, plant_scenario=scenario,
        belief_scenario=belief, controller=kind, seed=seed, wall_time_s=wall,
    )  # fmt: skip
    result.summary = evaluate(result)
    return result
