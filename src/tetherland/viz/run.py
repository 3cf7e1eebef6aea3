"""A finished run as the viewers need it, from a run directory or a mission result.

:func:`load_run` is the one place that reads a run directory (``tetherland mission
--out``): ``log.npz``, ``summary.json`` and the planned ``*_trajectory.csv``; the scene is
rebuilt from the scenario stored in the run's provenance.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tetherland.config import Scenario, scenario_from_dict
from tetherland.errors import ConfigError
from tetherland.planning.trajectory import Trajectory, load_trajectory
from tetherland.sim.log import SimLog

if TYPE_CHECKING:
    from tetherland.mission.run import MissionResult


@dataclass(frozen=True)
class PlanSpan:
    """A planned tethered maneuver as flown: the trajectory and the mission times it spans.

    Attributes
    ----------
    name : str
        ``"landing"`` or ``"takeoff"``.
    trajectory : Trajectory
    t0 : float
        Mission time of the trajectory's t = 0 [s].
    t1 : float
        Mission time after which the plan no longer applies (touchdown, release) [s];
        ``inf`` while the maneuver is still being flown.
    """

    name: str
    trajectory: Trajectory
    t0: float
    t1: float = math.inf


@dataclass(frozen=True)
class RunData:
    """Everything the MCAP export shows of one run.

    Attributes
    ----------
    log : SimLog
        One row per control tick.
    scenario : Scenario
        The scenario the plant simulated (scene, geometry) and the robot believed.
    spans : tuple of PlanSpan
        The planned maneuvers that were flown (empty for a free-flight run).
    plans : tuple of Trajectory
        Every planned trajectory (drawn as the planned path), flown or not.
    summary : dict
        The verdict document (``summary.json``); empty while a run is live.
    """

    log: SimLog
    scenario: Scenario
    spans: tuple[PlanSpan, ...] = ()
    plans: tuple[Trajectory, ...] = ()
    summary: dict[str, Any] = field(default_factory=dict)

    @property
    def events(self) -> list[dict[str, Any]]:
        """Hook, mission and runner events in time order."""
        return self.log.events


def plan_spans(
    times: dict[str, float],
    landing: Trajectory | None,
    takeoff: Trajectory | None,
    spinup_time: float,
) -> tuple[PlanSpan, ...]:
    """Where each plan was flown, from the supervisor's key times (t_tethered, t_L, t_T, ...).

    The landing plan starts at ``t_tethered`` and applies until touchdown ``t_L``; the
    takeoff plan starts ``spinup_time`` after ``t_T`` and applies until ``t_released``.
    """
    spans = []
    if landing is not None and "t_tethered" in times:
        spans.append(PlanSpan("landing", landing, times["t_tethered"], times.get("t_L", math.inf)))
    if takeoff is not None and "t_T" in times:
        t0 = times["t_T"] + spinup_time
        spans.append(PlanSpan("takeoff", takeoff, t0, times.get("t_released", math.inf)))
    return tuple(spans)


def run_data_from_mission(result: MissionResult) -> RunData:
    """The :class:`RunData` of a mission that has just been flown."""
    sup = result.supervisor
    spans = plan_spans(
        sup.times, sup.landing_traj, sup.takeoff_traj, result.belief_scenario.mission.spinup_time
    )
    return RunData(
        log=result.log,
        scenario=result.plant_scenario,
        spans=spans,
        plans=(sup.landing_traj, sup.takeoff_traj),
        summary=dict(result.summary),
    )


def load_run(run_dir: str | Path) -> RunData:
    """Read a run directory written by ``tetherland mission --out``.

    Raises
    ------
    ConfigError
        When the directory, its log or its summary is missing or unreadable.
    """
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise ConfigError(f"RUN_DIR '{run_dir}' is not a directory")
    log_path, summary_path = run_dir / "log.npz", run_dir / "summary.json"
    for path in (log_path, summary_path):
        if not path.is_file():
            raise ConfigError(
                f"RUN_DIR '{run_dir}' has no {path.name} (write one with tetherland mission --out)"
            )
    try:
        log = SimLog.load(log_path)
        summary = json.loads(summary_path.read_text())
    except (OSError, ValueError, KeyError) as err:
        raise ConfigError(f"cannot read the run in '{run_dir}': {err}") from err
    stored = (summary.get("provenance") or {}).get("scenario")
    stored = stored or (log.metadata.get("provenance") or {}).get("scenario")
    if stored is None:
        raise ConfigError(f"'{summary_path}' records no scenario (provenance.scenario)")
    scenario = scenario_from_dict(stored, summary.get("scenario", "run"))
    plans: dict[str, Trajectory] = {}
    for name in ("landing", "takeoff"):
        path = run_dir / f"{name}_trajectory.csv"
        if path.is_file():
            plans[name] = load_trajectory(path)
    spans = plan_spans(
        {k: float(v) for k, v in (summary.get("times") or {}).items() if v is not None},
        plans.get("landing"),
        plans.get("takeoff"),
        scenario.mission.spinup_time,
    )
    return RunData(
        log=log, scenario=scenario, spans=spans, plans=tuple(plans.values()), summary=summary
    )
