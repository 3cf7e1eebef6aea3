"""`tetherland judge RUN_DIR`: recompute a saved run's verdict from its files alone."""

from __future__ import annotations

import json as _json
from pathlib import Path
from typing import Annotated

import typer

from tetherland.cli.common import JsonOption, console
from tetherland.io import dumps_json
from tetherland.runs import jsonable_summary, rejudge
from tetherland.runs.directory import SUMMARY_FILE


def judge(
    run_dir: Annotated[
        Path, typer.Argument(help="A run directory written by `tetherland mission`.")
    ],
    json: JsonOption = False,
) -> None:
    """Judge a saved run again from its log.npz and run.json (any landing method).

    Prints the verdict (with --json: the summary.json document) and whether it equals the
    summary.json written when the run was flown. Exit code 0 when the run succeeded, 1
    when it did not, 2 when the directory holds no readable run.
    """
    verdict = rejudge(run_dir)
    summary = jsonable_summary(verdict)
    stored_path = run_dir / SUMMARY_FILE
    matches = None
    if stored_path.is_file():
        stored = _json.loads(stored_path.read_text())
        stored.pop("files", None)
        matches = stored == summary
    if json:
        typer.echo(dumps_json({**summary, "matches_summary": matches}), nl=False)
    else:
        ok = "[green]success[/green]" if verdict.success else "[red]failure[/red]"
        console.print(
            f"[bold]{summary['scenario']}[/bold] ({summary['method']}, seed {summary['seed']}): "
            f"{ok} ({verdict.outcome.value})"
        )
        if not verdict.success:
            console.print(f"reason: {verdict.reason}")
        if matches is not None:
            console.print(f"same as {SUMMARY_FILE}: {'yes' if matches else 'NO'}")
    if not verdict.success:
        raise typer.Exit(1)
