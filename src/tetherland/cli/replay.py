"""`tetherland replay CAMPAIGN_DIR RUN_ID`: fly one campaign run again, exactly, and explain it."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.progress import Progress, SpinnerColumn, TextColumn, TimeElapsedColumn

from tetherland.campaign.replay import Replay
from tetherland.campaign.replay import replay as replay_run
from tetherland.campaign.report import CampaignReport
from tetherland.cli.common import (
    JsonOption,
    McapOption,
    OverwriteOption,
    VideoOption,
    console,
    default_output,
    outcome_text,
    perturbation_text,
)
from tetherland.cli.mission import add_mcap
from tetherland.io import OutputDir, dumps_json
from tetherland.runs import save_run


def replay(
    directory: Annotated[Path, typer.Argument(help="A campaign directory (its --out).")],
    run_id: Annotated[
        str, typer.Argument(help="The run's id (run_id in results.jsonl, e.g. tethered-70-00003).")
    ],
    out: Annotated[
        Path | None,
        typer.Option("--out", help="Output directory (default out/<name>/replay-<RUN_ID>)."),
    ] = None,
    overwrite: OverwriteOption = False,
    json: JsonOption = False,
    video: VideoOption = False,
    mcap: McapOption = False,
) -> None:
    """Fly run RUN_ID of a campaign again, exactly as the campaign did (its scenario and
    sweep value, seed, perturbation, wind and fault), write its run directory, and explain
    it: when, in which phase and why it failed.

    Exit code 0 when the replay gives the run's record in results.jsonl bit for bit
    (wall times aside) or the run is not recorded yet, 1 when it differs (a changed
    tetherland), 2 on bad input.
    """
    campaign = CampaignReport.load(directory)  # one line if it holds no campaign
    campaign.spec.run(run_id)  # ... or no such run, before anything is written
    if mcap:
        from tetherland.optional import require

        require("foxglove", package="foxglove-sdk", extra="viz", feature="--mcap")
    name = str(campaign.spec.scenario.get("name", "custom"))
    target = None
    if campaign.spec.job == "mission":
        target = OutputDir(out or default_output(name, f"replay-{run_id}"), overwrite=overwrite)
    with Progress(
        SpinnerColumn(), TextColumn("{task.description}"), TimeElapsedColumn(),
        console=console, transient=True, disable=json,
    ) as progress:  # fmt: skip
        progress.add_task(f"replaying {run_id}", total=None)
        result = replay_run(directory, run_id)
    files: dict[str, Path] = {}
    if target is not None and result.result is not None:
        with target.staging() as staging:
            files = save_run(result.result, staging, video=video, listed_as=target.path)
            if mcap and result.result.log is not None:
                add_mcap(result.result, staging, files, target.path)
        files = {k: target.path / v.name for k, v in files.items()}
    if json:
        doc = {
            "run_id": run_id, "identical": result.identical,
            "differences": list(result.differences), "record": result.record,
            "recorded": result.recorded, "files": {k: str(v) for k, v in files.items()},
        }  # fmt: skip
        typer.echo(dumps_json(doc), nl=False)
    else:
        _print(result, files)
    if result.identical is False:
        raise typer.Exit(1)


def _print(result: Replay, files: dict[str, Path]) -> None:
    record, run = result.record, result.run
    point = "" if run.sweep_key is None else f", {run.sweep_key} = {run.sweep_value:g}"
    fault = f", fault {run.fault}" if run.fault else ""
    verdict = record.get("verdict", {})
    head = f"[bold]{run.run_id}[/bold] ({run.method}, seed {run.seed}{point}{fault}): "
    if record.get("status") != "ok":
        console.print(head + f"[red]error[/red]: {record.get('error')}", soft_wrap=True)
    elif "outcome" in verdict:
        console.print(head + outcome_text(verdict) + f", {verdict['sim_time_s']:.1f} s simulated")
    else:
        console.print(head + ("feasible" if verdict.get("success") else "infeasible"))
    if result.result is not None:
        p = result.result.summary.get("provenance", {}).get("perturbation")
        if p is not None:
            console.print(perturbation_text(p), markup=False, highlight=False)
    if not verdict.get("success") and "reason" in verdict:
        console.print(f"reason: {verdict['reason']}", markup=False, highlight=False)
    for failure in verdict.get("failures", []):
        console.print(f"  {failure['message']}", markup=False, highlight=False)
    if result.identical is None:
        console.print("not in results.jsonl yet: nothing to compare")
    elif result.identical:
        console.print("the same record as in results.jsonl, bit for bit (wall times aside)")
    else:
        console.print(f"[red]differs from results.jsonl[/red] in {len(result.differences)} "
                      "field(s):")  # fmt: skip
        for line in result.differences[:10]:
            console.print(f"  {line}", markup=False, highlight=False)
    if files:
        console.print(f"results in {files['summary'].parent}/: "
                      + ", ".join(p.name for p in files.values()), markup=False)  # fmt: skip
