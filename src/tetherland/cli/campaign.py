"""`tetherland campaign`: randomised runs in parallel, durable and resumable (issue 7)."""

from __future__ import annotations

import os
import shlex
import signal
from pathlib import Path
from typing import Annotated

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeRemainingColumn
from rich.table import Table

from tetherland.campaign import (
    CampaignResult,
    CampaignSpec,
    Sweep,
    make_executor,
    open_store,
    run_campaign,
)
from tetherland.campaign.executors import DEFAULT_RETRIES
from tetherland.campaign.faults import DEFAULT_WINDOW, fault_table, parse_faults, parse_window
from tetherland.campaign.plots import plot_errors, plot_success
from tetherland.cli.common import (
    INTERRUPTED,
    ScenarioArg,
    SetOption,
    console,
    default_output,
    resolve_scenario,
)
from tetherland.errors import ConfigError
from tetherland.io import prepare_output_dir
from tetherland.provenance import provenance


def _fault_table(counts: dict[str, dict[str, dict[str, int]]]) -> Table:
    table = Table(title="Faults: phase at the fault time x outcome (runs)")
    for col in ("fault", "phase", "outcomes"):
        table.add_column(col)
    for kind, phases in counts.items():
        for phase, outcomes in phases.items():
            table.add_row(kind, phase, ", ".join(f"{o} {n}" for o, n in sorted(outcomes.items())))
    return table


def _interrupt(signum: int, frame: object) -> None:
    raise KeyboardInterrupt


def campaign(
    scenario: ScenarioArg,
    runs: Annotated[int, typer.Option("--runs", help="Runs per method and sweep value.")] = 10,
    methods: Annotated[
        str, typer.Option("--methods", help="Comma-separated: tethered, free-flight.")
    ] = "tethered,free-flight",
    sweep: Annotated[
        str | None,
        typer.Option("--sweep", help="Swept key, e.g. surface.slope_deg=30:80:10 or =30,50,70."),
    ] = None,
    workers: Annotated[
        int | None, typer.Option("--workers", help="Parallel workers (default: all cores).")
    ] = None,
    engine: Annotated[str, typer.Option("--engine", help="local, dask or ray.")] = "local",
    retries: Annotated[
        int,
        typer.Option(
            "--retries", help="Times a run whose worker was lost (killed, crashed) is run again."
        ),
    ] = DEFAULT_RETRIES,
    address: Annotated[
        str | None,
        typer.Option(
            "--address", help="Dask scheduler or Ray cluster address (docs/campaigns.md)."
        ),
    ] = None,
    out: Annotated[Path | None, typer.Option("--out", help="Output directory.")] = None,
    resume: Annotated[
        bool, typer.Option("--resume", help="Run only what is missing in --out.")
    ] = False,
    seed: Annotated[int, typer.Option("--seed", help="Base seed of the campaign.")] = 0,
    controller: Annotated[
        str, typer.Option("--controller", help="Tethered controller: hierarchical or dfl.")
    ] = "hierarchical",
    job: Annotated[
        str,
        typer.Option(
            "--job", help="mission (closed-loop simulation) or analysis (static feasibility, fast)."
        ),
    ] = "mission",
    faults: Annotated[
        str | None,
        typer.Option(
            "--faults",
            help="Fault campaign: --runs tethered runs per fault kind, comma-separated: "
            "rotor, snap, mocap, anchor, jam (docs/faults.md).",
        ),
    ] = None,
    fault_window: Annotated[
        str,
        typer.Option("--fault-window", help="START:END of the fault times [s] (stratified)."),
    ] = f"{DEFAULT_WINDOW[0]:g}:{DEFAULT_WINDOW[1]:g}",
    firmware: Annotated[
        str | None,
        typer.Option("--firmware", help="Fly every run through flight firmware: betaflight."),
    ] = None,
    overrides: SetOption = None,
) -> None:
    """Run randomised missions for each method (and sweep value) and summarise success rates.

    With --faults, run --runs tethered missions per fault kind instead, with the fault
    times drawn across the mission, and print fault x phase x outcome."""
    sc = resolve_scenario(scenario, overrides)
    if seed < 0:
        raise ConfigError(f"--seed must be >= 0 (got {seed})")
    if controller not in ("hierarchical", "dfl"):
        raise ConfigError(f"--controller must be hierarchical or dfl (got {controller!r})")
    spec = CampaignSpec(
        scenario=sc.model_dump(mode="json"),
        runs=runs,
        methods=tuple(m.strip() for m in methods.split(",") if m.strip()),
        sweep=Sweep.parse(sweep) if sweep else None,
        seed=seed,
        job=job,
        controller=controller,
        faults=parse_faults(faults) if faults is not None else (),
        fault_window=parse_window(fault_window),
        firmware=firmware,
    )
    if spec.sweep is not None:  # validate every swept value up front: fail fast, one line
        for value in spec.sweep.values:
            resolve_scenario(scenario, [*(overrides or []), Sweep.override(spec.sweep.key, value)])
    directory = prepare_output_dir(out or default_output(sc.name, "campaign"))
    record = provenance(sc, seed=seed, extra={"engine": engine, "workers": workers})
    # connect first: an address that fails leaves no campaign directory behind
    executor = make_executor(engine, workers or os.cpu_count() or 1, address, retries)
    try:
        store = open_store(spec, directory, resume=resume, provenance=record)
    except BaseException:
        executor.close()
        raise
    resume_cmd = shlex.join(
        [
            "tetherland", "campaign", scenario, *(a for o in overrides or [] for a in ("--set", o)),
            "--runs", str(runs), "--methods", methods, *(["--sweep", sweep] if sweep else []),
            "--seed", str(seed), "--job", job, "--controller", controller,
            *(["--faults", faults, "--fault-window", fault_window] if faults is not None else []),
            "--engine", engine, *(["--workers", str(workers)] if workers else []),
            *(["--address", address] if address else []), "--retries", str(retries),
            "--out", str(directory), "--resume",
        ]
    )  # fmt: skip

    with (
        store,
        Progress(
            "[progress.description]{task.description}",
            BarColumn(),
            MofNCompleteColumn(),
            TimeRemainingColumn(),
            console=console,
            transient=False,
        ) as progress,
    ):
        task = progress.add_task("runs", total=None)

        def on_start(total: int, done: int) -> None:
            progress.update(task, total=total, completed=done)

        def on_result(rec: dict) -> None:
            ok = rec.get("status") == "ok" and rec.get("verdict", {}).get("success")
            status = "ok" if ok else "fail"
            progress.update(task, advance=1, description=f"runs (last: {rec['method']} {status})")

        # a polite stop (SIGTERM, e.g. from a batch scheduler) ends like Ctrl-C: the pool's
        # workers are stopped with it instead of being orphaned. SIGINT gets the same
        # handler explicitly: a shell starts background jobs with SIGINT ignored, and
        # Python then keeps ignoring it
        previous = {sig: signal.signal(sig, _interrupt) for sig in (signal.SIGTERM, signal.SIGINT)}
        try:
            result = run_campaign(
                spec, store, executor, provenance=record, on_result=on_result, on_start=on_start
            )
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)

    results, summary = directory / "results.jsonl", directory / "summary.json"
    if result.interrupted:  # stop fast: no plots (the completed campaign draws them)
        if result.done:
            console.print(_rates_table(result, spec))
            console.print(f"results so far: {results} ({result.done} of {result.total} runs)")
        console.print(f"interrupted: {result.done} of {result.total} runs saved; continue with")
        console.print(resume_cmd, soft_wrap=True, markup=False, highlight=False)
        raise typer.Exit(INTERRUPTED)
    plot_success(
        result.summary, directory / "success_rate.png", spec.sweep.key if spec.sweep else None
    )
    plot_errors(store.load(), directory / "errors.png")
    console.print(_rates_table(result, spec))
    if spec.faults:
        console.print(_fault_table(fault_table(store.load())))
    console.print(f"results: {results} (table), {summary}, plots in {directory}")
    if result.lost:
        console.print(
            f"{result.lost} runs lost their workers more than --retries {retries} times; "
            "run them with", soft_wrap=True,
        )  # fmt: skip
        console.print(resume_cmd, soft_wrap=True, markup=False, highlight=False)


def _rates_table(result: CampaignResult, spec: CampaignSpec) -> Table:
    table = Table(title=f"Success rates ({result.done}/{result.total} runs)")
    for col in (
        "method",
        spec.sweep.key if spec.sweep else "point",
        "n",
        "success",
        "rate",
        "95 % CI",
    ):
        table.add_column(col)
    for s in result.summary:
        table.add_row(
            s.method,
            "-" if s.sweep_value is None else f"{s.sweep_value:g}",
            str(s.n),
            str(s.successes),
            f"{100 * s.rate:.1f} %",
            f"[{100 * s.ci_low:.1f}, {100 * s.ci_high:.1f}] %",
        )
    return table
