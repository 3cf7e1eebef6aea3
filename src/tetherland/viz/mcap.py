"""Write a run to an MCAP file with the Foxglove SDK (Foxglove's schemas, see channels).

The file opens in Foxglove (and in Rerun, which reads MCAP); the shipped layout
(:func:`tetherland.viz.layout.layout_path`) arranges the 3D scene and figure 6.5's plots.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import foxglove
import mujoco
import numpy as np
from foxglove.messages import SceneUpdate

from tetherland import __version__
from tetherland.config import Scenario
from tetherland.geometry import LandingGeometry
from tetherland.io import atomic_path
from tetherland.planning.trajectory import Trajectory
from tetherland.sim.mjcf import SceneLayout, build_mjcf
from tetherland.viz.channels import Publisher
from tetherland.viz.run import RunData
from tetherland.viz.scene import planned_path_W, static_scene, tension_scale
from tetherland.viz.series import NominalPlan, tick_series


@dataclass(frozen=True)
class McapResult:
    """A written MCAP file.

    Attributes
    ----------
    path : Path
    ticks : int
        Control ticks written (one message per tick on every per-tick topic).
    events : int
        Log messages of run events (phases, hook, aborts).
    """

    path: Path
    ticks: int
    events: int


def scene_model(scenario: Scenario) -> mujoco.MjModel:
    """The plant's MuJoCo model of ``scenario`` (the scene the physics simulates)."""
    return mujoco.MjModel.from_xml_string(build_mjcf(scenario, SceneLayout.from_scenario(scenario)))


def make_publisher(
    context: foxglove.Context,
    scenario: Scenario,
    plans: Callable[[], Sequence[Trajectory]],
    model: mujoco.MjModel | None = None,
) -> Publisher:
    """The :class:`Publisher` of a run: its channels in ``context`` and its static scene.

    Parameters
    ----------
    plans : callable
        Returns the planned trajectories to draw (asked each time the scene is published:
        a live mission knows them only once it has planned).
    model : mujoco.MjModel, optional
        The plant's model (default: built from ``scenario``).
    """
    model = model if model is not None else scene_model(scenario)
    geo = LandingGeometry.from_scenario(scenario)
    r_att = np.asarray(scenario.vehicle.cable_attachment, dtype=float)

    paths: dict[int, tuple[Trajectory, np.ndarray]] = {}

    def path_W(trajectory: Trajectory) -> np.ndarray:
        """The planned path of ``trajectory``, computed once (the scene is republished every
        SCENE_PERIOD; a live mission's plans appear as it plans them)."""
        known = paths.get(id(trajectory))
        if known is None or known[0] is not trajectory:
            known = paths[id(trajectory)] = (trajectory, planned_path_W(trajectory, r_att))
        return known[1]

    def scene(t: float) -> SceneUpdate:
        named = [(p.meta.maneuver, p) for p in plans()]
        return static_scene(model, geo, named, r_att, t, path_W)

    return Publisher(context, scenario, scene, tension_scale(scenario.vehicle.mass))


def _metadata(run: RunData) -> dict[str, str]:
    prov = run.log.metadata.get("provenance") or {}
    return {
        "tetherland_version": __version__,
        "git_commit": str(prov.get("git_commit")),
        "scenario": run.scenario.name,
        "seed": str(prov.get("seed")),
        "status": str(run.log.metadata.get("status")),
        "success": json.dumps(run.summary.get("success")),
        "time": "simulation time from 0 (ns)",
    }


def write_mcap(run: RunData, path: str | Path, *, by_row: bool = False) -> McapResult:
    """Write ``run`` to ``path`` (atomically: a failed export leaves nothing behind).

    Parameters
    ----------
    run : RunData
        From :func:`tetherland.viz.load_run` or :func:`tetherland.viz.run_data_from_mission`.
    path : str or Path
        Output file (``.mcap``).
    by_row : bool
        Encode the per-tick messages row by row, one dict and ``json.dumps`` each (the
        reference encoding of :meth:`Publisher.publish_tick`, several times slower; the
        same messages).
    """
    path = Path(path)
    log = run.log
    series = tick_series(log, run.scenario, NominalPlan(run.scenario, run.spans).evaluate(log.t))
    events = sorted(run.events, key=lambda e: float(e["t"]))
    context = foxglove.Context()
    with atomic_path(path) as tmp:
        writer = foxglove.open_mcap(tmp, allow_overwrite=True, context=context)
        try:
            writer.write_metadata("tetherland", _metadata(run))
            publisher = make_publisher(context, run.scenario, lambda: run.plans)
            publisher.phase_names = dict(run.phase_names)
            publisher.publish_ticks(series, events, by_row=by_row)
            if run.summary:
                t_end = float(series.t[-1]) if len(series) else 0.0
                publisher.publish_verdict(t_end, run.summary)
        finally:
            writer.close()
    return McapResult(path=path, ticks=len(series), events=len(events))
