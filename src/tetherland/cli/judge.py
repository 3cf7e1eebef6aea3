"""`tetherland judge RUN_DIR`: recompute a saved run's verdict from its files alone."""

from __future__ import annotations

import json as _json
from pathlib import Path
from typing import Annotated, Any

import typer

from tetherland.cli.common import JsonOption, console, outcome_text
from tetherland.io import dumps_json
from tetherland.runs import jsonable_summary, rejudge
from tetherland.runs.directory import SUMMARY_FILE
from tetherland.verdict import RunRecordError


def _stored_summary(path: Path) -> dict[str, Any] | None:
    """``summary.json`` without its file list (None when there is none)."""
    if not path.exists():
        return None
    try:
        stored = _json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, RecursionError) as err:
        raise RunRecordError(f"{path}: unreadable summary ({err or type(err).__name__})") from None
    if not isinstance(stored, dict):
        raise RunRecordError(f"{path}: not a run summary (a JSON object)")
    stored.pop("files", None)
    return stored


def judge(
    run_dir: Annotated[
        Path, typer.Argument(help="A run directory written by `tetherland mission`.")
    ],
    json: JsonOption = False,
) -> None:
    """Judge a saved run again from its log.npz and run.json (any landing method).

    Prints the verdict (with --json: the summary.json document) and whether it equals the
    summary.json written when the run was flown. Exit code 0 when the run succeeded and
    its summary.json (if any) says the same, 1 when it did not succeed or summary.json
    differs from the recomputed verdict (a tampered or stale run), 2 when the directory
    holds no readable run.
    """
    verdict = rejudge(run_dir)
    summary = jsonable_summary(verdict)
    stored = _stored_summary(run_dir / SUMMARY_FILE)
    matches = None if stored is None else stored == summary
    if json:
        typer.echo(dumps_json({**summary, "matches_summary": matches}), nl=False)
    else:
        console.print(
            f"[bold]{summary['scenario']}[/bold] ({summary['method']}, seed {summary['seed']}): "
            f"{outcome_text(summary)} ({verdict.outcome.value})"
        )
        if not verdict.success:
            console.print(f"reason: {verdict.reason}")
        if matches is not None:
            console.print(f"same as {SUMMARY_FILE}: {'yes' if matches else 'NO'}")
    if matches is False:
        assert stored is not None
        keys = sorted(k for k in stored.keys() | summary.keys() if stored.get(k) != summary.get(k))
        typer.echo(
            f"error: {run_dir / SUMMARY_FILE} differs from the verdict recomputed from the log "
            f"and run.json (in {', '.join(keys)}): the run was changed or is stale",
            err=True,
        )
        raise typer.Exit(1)
    if not verdict.success:
        raise typer.Exit(1)
