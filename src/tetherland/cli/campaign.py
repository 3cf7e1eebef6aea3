"""`tetherland campaign`: randomised runs in parallel, durable and resumable (issue 7), and
`tetherland campaign report DIR`: its tables and figures, read from the directory."""

from __future__ import annotations

import os
import shlex
import signal
from pathlib import Path
from typing import Annotated, Any

import typer
import typer.core
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TimeRemainingColumn
from rich.table import Table

from tetherland.campaign import (
    CampaignSpec,
    Sweep,
    make_executor,
    open_store,
    run_campaign,
)
from tetherland.campaign.executors import DEFAULT_RETRIES
from tetherland.campaign.faults import DEFAULT_WINDOW, parse_faults, parse_window
from tetherland.campaign.report import CampaignReport
from tetherland.campaign.store import KEEP_POLICIES, ResultsStore
from tetherland.cli.common import (
    INTERRUPTED,
    JsonOption,
    ScenarioArg,
    SetOption,
    console,
    default_output,
    resolve_scenario,
)
from tetherland.errors import ConfigError
from tetherland.io import dumps_json, prepare_output_dir
from tetherland.provenance import provenance


class CampaignGroup(typer.core.TyperGroup):
    """``campaign SCENARIO ...`` runs a campaign (``campaign --help`` is its help), and
    ``campaign report DIR`` reports one: arguments that do not start with a subcommand
    are the campaign's."""

    def parse_args(self, ctx: Any, args: list[str]) -> list[str]:
        if args and args[0] not in self.commands:
            args = ["run", *args]
        return super().parse_args(ctx, args)


campaign_app = typer.Typer(
    cls=CampaignGroup,
    name="campaign",
    help="Randomised runs in parallel (campaign SCENARIO), or the report of one (campaign "
    "report DIR).",
    no_args_is_help=True,
    add_completion=False,
    rich_markup_mode=None,
)


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
            "--address",
            help="Dask scheduler or Ray cluster address (docs/howto/cluster_campaigns.md).",
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
    keep: Annotated[
        str,
        typer.Option(
            "--keep",
            help="Which runs keep their run directory in DIR/runs/: failures (every run "
            "that did not succeed), all or none.",
        ),
    ] = "failures",
    overrides: SetOption = None,
) -> None:
    """Run randomised missions for each method (and sweep value) and summarise success rates.

    With --faults, run --runs tethered missions per fault kind instead, with the fault
    times drawn across the mission, and print fault x phase x outcome. Every failure in
    results.jsonl says when, in which phase and why; the failed runs keep their run
    directories (--keep); `tetherland replay DIR RUN_ID` flies any run again exactly and
    `tetherland campaign report DIR` prints the tables again."""
    sc = resolve_scenario(scenario, overrides)
    if keep not in KEEP_POLICIES:
        raise ConfigError(f"--keep must be one of {', '.join(KEEP_POLICIES)} (got {keep!r})")
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
                spec, store, executor, provenance=record, on_result=on_result,
                on_start=on_start, keep=keep,
            )  # fmt: skip
        finally:
            for sig, handler in previous.items():
                signal.signal(sig, handler)

    results, summary = directory / "results.jsonl", directory / "summary.json"
    if result.interrupted:  # stop fast: no plots (the completed campaign draws them)
        if result.done:
            print_report(CampaignReport.load(directory), figures=False)
            console.print(f"results so far: {results} ({result.done} of {result.total} runs)")
        console.print(f"interrupted: {result.done} of {result.total} runs saved; continue with")
        console.print(resume_cmd, soft_wrap=True, markup=False, highlight=False)
        raise typer.Exit(INTERRUPTED)
    print_report(CampaignReport.load(directory), figures=True)
    console.print(f"results: {results} (table), {summary}, plots in {directory}")
    if result.lost:
        console.print(
            f"{result.lost} runs lost their workers more than --retries {retries} times; "
            "run them with", soft_wrap=True,
        )  # fmt: skip
        console.print(resume_cmd, soft_wrap=True, markup=False, highlight=False)


def _rates_table(report: CampaignReport) -> Table:
    spec = report.spec
    table = Table(title=f"Success rates ({len(report.records)}/{report.total} runs)")
    for col in (
        "method",
        spec.sweep.key if spec.sweep else "point",
        "n",
        "success",
        "rate",
        "95 % CI",
    ):
        table.add_column(col)
    for s in report.rates:
        table.add_row(
            s.method,
            "-" if s.sweep_value is None else f"{s.sweep_value:g}",
            str(s.n),
            str(s.successes),
            f"{100 * s.rate:.1f} %",
            f"[{100 * s.ci_low:.1f}, {100 * s.ci_high:.1f}] %",
        )
    return table


def _failure_table(report: CampaignReport) -> Table:
    table = Table(title="Failures by kind and phase (runs)")
    for col in ("method", "failure", "phase", "runs", "run ids (replay one)"):
        table.add_column(col)
    for g in report.failures:
        ids = ", ".join(g.run_ids[:3]) + (", ..." if len(g.run_ids) > 3 else "")
        table.add_row(g.method, g.kind, g.phase, str(g.runs), ids)
    return table


HOOKING_KINDS = ("caught", "bounced", "wrong_side", "tangled", "missed")


def _hooking_table(report: CampaignReport) -> Table:
    table = Table(title="Hooking attempts on the plant's truth (runs: lost = came off under "
                        "load, held = not released)")  # fmt: skip
    spec = report.spec
    cols = ("method", spec.sweep.key if spec.sweep else "point", "runs", *HOOKING_KINDS,
            "lost", "held")  # fmt: skip
    for col in cols:
        table.add_column(col.replace("_", " "))
    for h in report.hooking:
        table.add_row(
            h.method, "-" if h.sweep_value is None else f"{h.sweep_value:g}", str(h.runs),
            *(str(h.attempts.get(k, 0)) for k in HOOKING_KINDS), str(h.lost),
            str(h.not_released),
        )  # fmt: skip
    return table


def _fault_table(counts: dict[str, dict[str, dict[str, int]]]) -> Table:
    table = Table(title="Faults: phase at the fault time x outcome (runs)")
    for col in ("fault", "phase", "outcomes"):
        table.add_column(col)
    for kind, phases in counts.items():
        for phase, outcomes in phases.items():
            table.add_row(kind, phase, ", ".join(f"{o} {n}" for o, n in sorted(outcomes.items())))
    return table


def print_report(report: CampaignReport, *, figures: bool) -> dict[str, Path]:
    """Print a campaign's tables (success by point with 95 % intervals, failures by kind
    and phase, faults by phase) and, with ``figures``, draw its figures; returns them."""
    console.print(_rates_table(report))
    if report.failures:
        console.print(_failure_table(report))
    if report.hooking:
        console.print(_hooking_table(report))
    if report.faults is not None:
        console.print(_fault_table(report.faults))
    return report.draw() if figures and report.records else {}


def report(
    directory: Annotated[Path, typer.Argument(help="A campaign directory (its --out).")],
    json: JsonOption = False,
) -> None:
    """Print the tables of a campaign directory (finished, interrupted or running): success
    by method and point with 95 % intervals, failures by kind and phase with the runs to
    replay, faults by phase; and redraw success_rate.png and errors.png there (not while
    another process runs the campaign)."""
    doc = CampaignReport.load(directory)
    files: dict[str, Path] = {}
    store = ResultsStore(directory)
    try:
        store.lock()  # the figures are the campaign's files: not while it runs
    except ConfigError:
        busy: str | None = "another process is running this campaign"
    else:
        busy = None
    try:
        if json:
            files = doc.draw() if busy is None and doc.records else {}
            out = {**doc.to_dict(), "files": {k: str(v) for k, v in files.items()}}
            typer.echo(dumps_json(out), nl=False)
            return
        files = print_report(doc, figures=busy is None)
    finally:
        store.close()
    kept = sum(1 for r in doc.records if r.get("run_dir"))
    console.print(
        f"{len(doc.records)} of {doc.total} runs finished"
        + (f", {len(doc.lost)} lost (--resume runs them)" if doc.lost else "")
        + (f"; {kept} run directories kept in {directory / 'runs'}" if kept else ""),
        markup=False, highlight=False,
    )  # fmt: skip
    if busy is not None:
        console.print(f"figures not redrawn: {busy}", markup=False, highlight=False)
    for name, path in files.items():
        console.print(f"{name}: {path}", markup=False, highlight=False)


campaign_app.command("run")(campaign)
campaign_app.command("report")(report)
