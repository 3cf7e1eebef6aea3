"""A finished run as the viewers need it, from a run directory or a mission result.

:func:`load_run` is the one place that reads a run directory (``tetherland mission
--out``): the run record ``run.json`` (the scenario the plant simulated, the key times),
``log.npz``, ``summary.json`` (the verdict) and the planned trajectories' CSV files.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tetherland.config import Scenario
from tetherland.errors import ConfigError
from tetherland.planning.trajectory import Trajectory, load_trajectory
from tetherland.sim.log import SimLog

if TYPE_CHECKING:
    from tetherland.runs import RunResult


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
    phase_names : dict of int to str
        The method's phase names by the codes of the log's ``phase`` column (default: the
        tethered mission's :class:`~tetherland.mission.Phase`).
    """

    log: SimLog
    scenario: Scenario
    spans: tuple[PlanSpan, ...] = ()
    plans: tuple[Trajectory, ...] = ()
    summary: dict[str, Any] = field(default_factory=dict)
    phase_names: dict[int, str] = field(default_factory=dict)

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


def _tethered_plans(trajectories: dict[str, Any]) -> dict[str, Trajectory]:
    """The tethered (planar) trajectories by maneuver, of a method's trajectory files."""
    return {t.meta.maneuver: t for t in trajectories.values() if isinstance(t, Trajectory)}


def run_data(
    log: SimLog,
    scenario: Scenario,
    times: dict[str, float],
    plans: dict[str, Trajectory],
    summary: dict[str, Any],
    phase_codes: dict[str, int] | None = None,
) -> RunData:
    """A :class:`RunData` from its parts (the plans by maneuver name, the phase codes by
    name as the run record holds them)."""
    clean = {k: float(v) for k, v in times.items() if v is not None}
    spans = plan_spans(
        clean, plans.get("landing"), plans.get("takeoff"), scenario.mission.spinup_time
    )
    names = {int(code): name for name, code in (phase_codes or {}).items()}
    return RunData(log=log, scenario=scenario, spans=spans, plans=tuple(plans.values()),
                   summary=dict(summary), phase_names=names)  # fmt: skip


def run_data_from_result(result: RunResult) -> RunData:
    """The :class:`RunData` of a run just flown (:func:`tetherland.runs.run_mission`)."""
    from tetherland.methods import get_method

    if result.log is None:
        raise ConfigError("the run was not flown (no plan): there is nothing to export")
    trajectories = get_method(result.method).trajectories(result.plan) if result.plan else {}
    return run_data(result.log, result.plant_scenario, dict(result.record.times),
                    _tethered_plans(trajectories), result.summary,
                    dict(result.record.phase_codes))  # fmt: skip


def load_run(run_dir: str | Path) -> RunData:
    """Read a run directory written by ``tetherland mission --out`` (``run.json``, ``log.npz``,
    ``summary.json`` and the plans' CSV files).

    Raises
    ------
    TetherlandError
        One line when the directory holds no readable run.
    """
    from tetherland.runs import load_run as load_log_and_record

    run_dir = Path(run_dir)
    log, record = load_log_and_record(run_dir)
    summary_path = run_dir / "summary.json"
    summary: dict[str, Any] = {}
    if summary_path.is_file():
        try:
            summary = json.loads(summary_path.read_text())
        except (OSError, ValueError) as err:
            raise ConfigError(f"'{summary_path}' is unreadable: {err}") from None
    plans: dict[str, Trajectory] = {}
    for path in sorted(run_dir.glob("*.csv")):
        try:
            trajectory = load_trajectory(path)
        except (ConfigError, ValueError, KeyError):
            continue  # not a tethered trajectory (e.g. a perching maneuver)
        plans[trajectory.meta.maneuver] = trajectory
    return run_data(log, record.truth_scenario(), dict(record.times), plans, summary,
                    dict(record.phase_codes))  # fmt: skip
