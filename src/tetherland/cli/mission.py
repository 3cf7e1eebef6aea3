"""`tetherland mission`: the full closed-loop mission (the project's main job)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn
from rich.table import Table

from tetherland.cli.common import JsonOption, ScenarioArg, SetOption, console, resolve_scenario
from tetherland.errors import ConfigError
from tetherland.io import atomic_write_json, dumps_json

METHODS = ("tethered", "free-flight")
CONTROLLERS = ("hierarchical", "dfl")


class _ProgressObserver:
    """Updates a progress line every 0.25 s of simulated time (cheap in the 500 Hz loop)."""

    def __init__(self, progress: Progress, task: Any, phase_of=None):
        self.progress, self.task, self.phase_of = progress, task, phase_of
        self._next = 0.0

    def __call__(self, t: float, plant: Any) -> None:
        if t >= self._next:
            self._next = t + 0.25
            phase = self.phase_of() if self.phase_of else ""
            self.progress.update(self.task, description=f"t = {t:6.2f} s  {phase}")


def _write_mcap(run: Any, out: Path) -> Path:
    from tetherland.viz.mcap import write_mcap

    return write_mcap(run, out / "run.mcap").path


def _start_live(sc: Any, speed: float, port: int, quiet: bool) -> Any:
    from tetherland.cli.common import err_console
    from tetherland.viz.live import LiveView

    view = LiveView(sc, port=port, speed=speed)
    pace = f"{speed:g}x real time" if speed > 0 else "unpaced"
    (err_console if quiet else console).print(
        f"live view on {view.url} ({pace}): in Foxglove, Open connection > Foxglove WebSocket"
    )
    return view


def _write_tethered(result: Any, out: Path, video: bool, mcap: bool = False) -> dict[str, Path]:
    from tetherland.report import save_figures

    files = {"log": out / "log.npz", "summary": out / "summary.json"}
    result.log.save(files["log"])
    sup = result.supervisor
    files["landing_trajectory"] = sup.landing_traj.save_csv(out / "landing_trajectory.csv")
    files["takeoff_trajectory"] = sup.takeoff_traj.save_csv(out / "takeoff_trajectory.csv")
    figure_65, path_3d = save_figures(result, out)
    files["figure_6_5"], files["path_3d"] = figure_65, path_3d
    if video:
        from tetherland.sim.render import render_log

        files["video"] = render_log(
            result.log, out / "mission.mp4", scenario=result.plant_scenario
        ).path
    if mcap:
        from tetherland.viz import run_data_from_mission

        files["mcap"] = _write_mcap(run_data_from_mission(result), out)
    atomic_write_json(
        files["summary"], {**result.summary, "files": {k: str(v) for k, v in files.items()}}
    )
    return files


def _run_free_flight(
    sc: Any, seed: int, out: Path, video: bool, observers: list, mcap: bool = False
) -> tuple[dict, dict]:
    from tetherland.estimation import UkfEstimator
    from tetherland.perching import run_perching
    from tetherland.provenance import provenance

    t0 = time.perf_counter()
    log, verdict = run_perching(
        sc, sc, seed, lambda b, x0, t, w0: UkfEstimator(b, x0, t, rotor_speeds0=w0),
        observers=observers,
    )  # fmt: skip
    wall = time.perf_counter() - t0
    v = verdict.to_dict()
    sim_time = float(log["t"][-1]) if log is not None and len(log) else 0.0
    summary = {
        "success": v["success"],
        "method": "free-flight",
        "scenario": sc.name,
        "seed": seed,
        "reason": v["reason"],
        "landing": {k: v[k] for k in v if k not in ("success", "reason")},
        "sim_time_s": sim_time,
        "wall_time_s": wall,
        "real_time_factor": sim_time / wall if wall > 0 else None,
        "provenance": provenance(sc, seed=seed, extra={"method": "free-flight"}),
    }
    files: dict[str, Path] = {"summary": out / "summary.json"}
    if log is not None:
        files["log"] = log.save(out / "log.npz") or out / "log.npz"
        if video:
            from tetherland.sim.render import render_log

            files["video"] = render_log(log, out / "mission.mp4", scenario=sc).path
        if mcap:
            from tetherland.viz import RunData

            files["mcap"] = _write_mcap(RunData(log=log, scenario=sc, summary=summary), out)
    atomic_write_json(files["summary"], {**summary, "files": {k: str(p) for k, p in files.items()}})
    return summary, files


def mission(
    scenario: ScenarioArg,
    overrides: SetOption = None,
    controller: Annotated[
        str | None, typer.Option("--controller", help="Tethered controller: hierarchical or dfl.")
    ] = None,
    method: Annotated[
        str, typer.Option("--method", help="tethered (the chapter's) or free-flight (perching).")
    ] = "tethered",
    seed: Annotated[int, typer.Option("--seed", help="Seed of sensor noise and disturbances.")] = 0,
    out: Annotated[Path | None, typer.Option("--out", help="Output directory.")] = None,
    json: JsonOption = False,
    video: Annotated[
        bool, typer.Option("--video", help="Also render mission.mp4 (offscreen).")
    ] = False,
    mcap: Annotated[
        bool, typer.Option("--mcap", help="Also write run.mcap (Foxglove, Rerun).")
    ] = False,
    live: Annotated[
        bool, typer.Option("--live", help="Stream the mission to Foxglove while it runs.")
    ] = False,
    live_speed: Annotated[
        float,
        typer.Option("--live-speed", help="With --live: sim seconds per second (0: unpaced)."),
    ] = 1.0,
    live_port: Annotated[
        int, typer.Option("--live-port", help="With --live: WebSocket port (0: any free one).")
    ] = 8765,
) -> None:
    """Fly the full mission closed loop (MuJoCo, sensors, UKF, planner, controllers, supervisor).

    Writes the log, summary.json, the figure 6.5 plots and the 3D path (and an mp4 with
    --video) into --out. Exit code 0 when the mission succeeded, 1 when it failed.
    """
    sc = resolve_scenario(scenario, overrides)
    if method not in METHODS:
        raise ConfigError(f"--method must be one of {', '.join(METHODS)} (got {method!r})")
    if controller is not None and controller not in CONTROLLERS:
        raise ConfigError(
            f"--controller must be one of {', '.join(CONTROLLERS)} (got {controller!r})"
        )
    if seed < 0:
        raise ConfigError(f"--seed must be >= 0 (got {seed})")
    directory = out or Path("out") / sc.name / ("mission" if method == "tethered" else "perching")
    if mcap:
        from tetherland.optional import require

        require("foxglove", package="foxglove-sdk", extra="viz", feature="--mcap")
    view = _start_live(sc, live_speed, live_port, json) if live else None
    directory.mkdir(parents=True, exist_ok=True)
    with Progress(
        SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(),
        console=console, transient=True, disable=json,
    ) as progress:  # fmt: skip
        task = progress.add_task("planning", total=None)
        if method == "tethered":
            from tetherland.mission import run_mission

            holder: dict[str, Any] = {}

            def phase_of() -> str:
                sup = holder.get("sup")
                return sup.phase.name.lower() if sup is not None else ""

            obs = _ProgressObserver(progress, task, phase_of)
            result = run_mission(
                sc, controller=controller, seed=seed, observers=[obs, *([view] if view else [])],
                plant_setup=lambda p: None,
            )  # fmt: skip
            holder["sup"] = result.supervisor
            if view is not None:
                view.finish(result.summary)
            progress.update(task, description="writing results")
            files = _write_tethered(result, directory, video, mcap)
            summary = result.summary
        else:
            observers = [_ProgressObserver(progress, task), *([view] if view else [])]
            summary, files = _run_free_flight(sc, seed, directory, video, observers, mcap)
            if view is not None:
                view.finish(summary)
    if view is not None:
        view.close()
    if json:
        typer.echo(
            dumps_json({**summary, "files": {k: str(v) for k, v in files.items()}}), nl=False
        )
    else:
        _print_summary(summary, files)
    if not summary["success"]:
        raise typer.Exit(1)


def _print_summary(summary: dict, files: dict[str, Path]) -> None:
    import math

    landing = summary.get("landing", {})
    ok = "[green]success[/green]" if summary["success"] else "[red]failure[/red]"
    rtf = summary.get("real_time_factor") or 0.0
    console.print(
        f"[bold]{summary['scenario']}[/bold] ({summary['method']}): {ok}, "
        f"{summary['sim_time_s']:.1f} s simulated, {rtf:.1f}x real time"
    )
    if summary.get("abort_reason") or summary.get("reason") not in (None, "ok"):
        console.print(f"reason: {summary.get('abort_reason') or summary.get('reason')}")
    table = Table(title="Landing (plant truth at touchdown)")
    table.add_column("measure")
    table.add_column("value")
    rows = [
        ("position error", "position_error_m", 100, "cm"),
        ("attitude error", "attitude_error_rad", 180 / math.pi, "deg"),
        ("touchdown speed", "touchdown_speed_mps", 1, "m/s"),
        ("touchdown angular rate", "touchdown_angular_rate_rps", 1, "rad/s"),
        ("touchdown acceleration", "touchdown_accel_mps2", 1, "m/s^2"),
        ("slip while motors off", "slip_m", 1000, "mm"),
        ("min cable tension", "min_tension_N", 1, "N"),
    ]
    for label, key, scale, unit in rows:
        value = landing.get(key)
        if value is not None:
            table.add_row(label, f"{value * scale:.3g} {unit}")
    conditions = landing.get("conditions") or {}
    table.add_row(
        "conditions (1)-(5)", " ".join(f"{k}:{'ok' if v else 'NO'}" for k, v in conditions.items())
    )
    console.print(table)
    if "phases" in summary:
        console.print(
            "phases: " + ", ".join(f"{p['name']} {p['start']:.1f}s" for p in summary["phases"])
        )
    console.print(
        f"results in {files['summary'].parent}/: " + ", ".join(p.name for p in files.values())
    )
