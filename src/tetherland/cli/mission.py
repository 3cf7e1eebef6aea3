"""`tetherland mission`: the full closed-loop mission (the project's main job)."""

from __future__ import annotations

from pathlib import Path
from collections.abc import Sequence
from typing import Annotated, Any

import typer
from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn
from rich.table import Table

from tetherland.campaign.jobs import draw_run, fly_perturbed
from tetherland.cli.common import (
    JsonOption,
    McapOption,
    OverwriteOption,
    ScenarioArg,
    SetOption,
    VideoOption,
    conditions_text,
    console,
    default_output,
    outcome_text,
    perturbation_text,
    resolve_scenario,
)
from tetherland.errors import ConfigError
from tetherland.io import OutputDir, dumps_json
from tetherland.methods import Flight, get_method, method_names
from tetherland.runs import run_mission, save_run
from tetherland.runs.directory import write_summary
from tetherland.runs.explain import explain
from tetherland.verdict import Outcome

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


def _start_live(sc: Any, speed: float, port: int, rate: float, quiet: bool) -> Any:
    from tetherland.cli.common import err_console
    from tetherland.viz.live import LiveView

    view = LiveView(sc, port=port, speed=speed, rate_hz=rate)
    pace = f"{speed:g}x real time" if speed > 0 else "unpaced"
    (err_console if quiet else console).print(
        f"live view on {view.url} ({pace}): in Foxglove, Open connection > Foxglove WebSocket"
    )
    return view


def add_mcap(result: Any, directory: Path, files: dict[str, Path], listed_as: Path) -> None:
    """Write run.mcap and list it in summary.json."""
    from tetherland.viz import run_data_from_result
    from tetherland.viz.mcap import write_mcap

    files["mcap"] = write_mcap(run_data_from_result(result), directory / "run.mcap").path
    write_summary(result.summary, files, listed_as)


def mission(
    scenario: ScenarioArg,
    overrides: SetOption = None,
    controller: Annotated[
        str | None, typer.Option("--controller", help="Tethered controller: hierarchical or dfl.")
    ] = None,
    method: Annotated[
        str,
        typer.Option("--method", help=f"Landing method: {', '.join(method_names())}."),
    ] = "tethered",
    seed: Annotated[
        int,
        typer.Option(
            "--seed",
            help="Seed of the sensor noise (alone it varies nothing else; add --perturb).",
        ),
    ] = 0,
    perturb: Annotated[
        bool,
        typer.Option(
            "--perturb",
            help="Also draw the campaign's perturbation for --seed (model, surface and "
            "anchor belief errors, noise scale, wind gusts), exactly as a campaign run with "
            "that seed; recorded in run.json.",
        ),
    ] = False,
    out: Annotated[
        Path | None, typer.Option("--out", help="Output directory (default out/<name>/mission).")
    ] = None,
    overwrite: OverwriteOption = False,
    json: JsonOption = False,
    video: VideoOption = False,
    mcap: McapOption = False,
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
    live_rate: Annotated[
        float, typer.Option("--live-rate", help="With --live: messages per second per topic.")
    ] = 100.0,
    firmware: Annotated[
        str | None,
        typer.Option("--firmware", help="Fly through flight firmware in lockstep: betaflight."),
    ] = None,
) -> None:
    """Fly the full mission closed loop (MuJoCo, sensors, UKF, planner, controllers, supervisor).

    Writes the log, summary.json, the figure 6.5 plots and the 3D path (and an mp4 with
    --video, run.mcap for Foxglove or Rerun with --mcap) into --out, all at once when the
    run ends; an existing run there is replaced as a whole only with --overwrite. --live
    streams the run to Foxglove while it flies. --seed alone varies only the sensor noise
    (the robot believes the scenario exactly, no wind): --perturb flies the campaign's
    perturbation of that seed. Exit code 0 when the mission succeeded, 1 when it failed;
    a mission that cannot be planned (a slope the vehicle cannot reach) prints one line with
    the reason, writes no results and exits 1.
    """
    sc = resolve_scenario(scenario, overrides)
    how = get_method(method, "--method")
    if controller is not None and controller not in CONTROLLERS:
        raise ConfigError(
            f"--controller must be one of {', '.join(CONTROLLERS)} (got {controller!r})"
        )
    if seed < 0:
        raise ConfigError(f"--seed must be >= 0 (got {seed})")
    inner_loop = _firmware(firmware)
    if mcap:
        from tetherland.optional import require

        require("foxglove", package="foxglove-sdk", extra="viz", feature="--mcap")
    default = "mission" if how.name == "tethered" else "perching"
    target = OutputDir(out or default_output(sc.name, default), overwrite=overwrite)
    view = _start_live(sc, live_speed, live_port, live_rate, json) if live else None
    with Progress(
        SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(),
        console=console, transient=True, disable=json,
    ) as progress:  # fmt: skip
        task = progress.add_task("planning", total=None)
        holder: dict[str, Any] = {}

        def phase_of() -> str:
            phase = getattr(holder.get("reference"), "phase", None)
            return phase.name.lower() if phase is not None else ""

        def on_flight(flight: Flight) -> None:
            holder.update(reference=flight.reference)

        observers = [_ProgressObserver(progress, task, phase_of), *([view] if view else [])]
        if perturb:  # the campaign's draw for this seed, flown as the campaign flies it
            result = fly_perturbed(
                draw_run(sc, seed), how.name, controller=controller, inner_loop=inner_loop,
                observers=observers, on_flight=on_flight,
            )  # fmt: skip
        else:
            result = run_mission(
                sc, method=how.name, controller=controller, seed=seed, observers=observers,
                on_flight=on_flight, inner_loop=inner_loop,
            )  # fmt: skip
        if view is not None:
            view.finish(result.summary)
            view.close()
        if result.summary["outcome"] == Outcome.NO_RUN.value:
            # a valid request the vehicle cannot fly (no plan): one line, exit 1, no files
            if json:
                typer.echo(dumps_json(result.summary), nl=False)
            typer.echo(f"error: mission not flown: {result.summary['reason']}", err=True)
            raise typer.Exit(1)
        progress.update(task, description="writing results")
        with target.staging() as staging:
            files = save_run(result, staging, video=video, listed_as=target.path)
            if mcap and result.log is not None:
                add_mcap(result, staging, files, target.path)
        files = {k: target.path / v.name for k, v in files.items()}
        summary = result.summary
        failures = [f.to_dict() for f in explain(summary, result.log, result.record)]
    if json:
        files_doc = {k: str(v) for k, v in files.items()}
        typer.echo(dumps_json({**summary, "failures": failures, "files": files_doc}), nl=False)
    else:
        _print_summary(summary, files, failures)
    if not summary["success"]:
        raise typer.Exit(1)


def _firmware(name: str | None) -> Any:
    """The inner-loop factory of ``--firmware`` (ConfigError for an unknown name)."""
    if name is None:
        return None
    from tetherland.firmware import FIRMWARES, BetaflightSitl

    if name not in FIRMWARES:
        raise ConfigError(f"--firmware must be one of {', '.join(FIRMWARES)} (got {name!r})")
    return BetaflightSitl()


def _print_summary(
    summary: dict, files: dict[str, Path], failures: Sequence[dict] = ()
) -> None:
    import math

    landing = summary.get("landing", {})
    rtf = summary.get("real_time_factor") or 0.0
    console.print(
        f"[bold]{summary['scenario']}[/bold] ({summary['method']}): {outcome_text(summary)}, "
        f"{summary['sim_time_s']:.1f} s simulated, {rtf:.1f}x real time"
    )
    perturbation = summary.get("provenance", {}).get("perturbation")
    if perturbation is not None:
        console.print(perturbation_text(perturbation), markup=False, highlight=False)
    if not summary["success"]:
        console.print(f"reason: {summary['reason']}", markup=False, highlight=False)
        for failure in failures:
            console.print(f"  {failure['message']}", markup=False, highlight=False)
    table = Table(title="Landing (plant truth at touchdown)")
    table.add_column("measure")
    table.add_column("value")
    rows = [
        ("position error", "position_error_m", 100, "cm"),
        ("attitude error", "attitude_error_rad", 180 / math.pi, "deg"),
        ("touchdown speed", "touchdown_speed_mps", 1, "m/s"),
        ("touchdown angular rate", "touchdown_angular_rate_rps", 1, "rad/s"),
        ("touchdown acceleration", "touchdown_accel_mps2", 1, "m/s^2"),
        ("slip, touchdown to spin-up", "slip_m", 1000, "mm"),
        ("min cable tension", "min_tension_N", 1, "N"),
    ]
    for label, key, scale, unit in rows:
        value = landing.get(key)
        if value is not None:
            table.add_row(label, f"{value * scale:.3g} {unit}")
    rest = landing.get("rest_interval_s")
    if rest is not None:
        table.add_row("rest (true thrust off)", f"{rest[0]:.2f}-{rest[1]:.2f} s")
    if landing.get("conditions"):
        table.add_row("conditions (required)", conditions_text(landing))
    console.print(table)
    if "phases" in summary:
        console.print(
            "phases: " + ", ".join(f"{p['name']} {p['start']:.1f}s" for p in summary["phases"])
        )
    console.print(
        f"results in {files['summary'].parent}/: " + ", ".join(p.name for p in files.values())
    )
