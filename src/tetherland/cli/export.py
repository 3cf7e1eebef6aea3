"""`tetherland export`: convert a saved run for the robotics viewers (MCAP)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from tetherland.cli.common import JsonOption, console
from tetherland.errors import ConfigError
from tetherland.io import dumps_json


def export(
    run_dir: Annotated[
        Path, typer.Argument(help="A run directory written by `tetherland mission --out`.")
    ],
    mcap: Annotated[
        bool, typer.Option("--mcap", help="Write an MCAP file (Foxglove schemas).")
    ] = False,
    out: Annotated[
        Path | None, typer.Option("--out", help="Output file (default: RUN_DIR/run.mcap).")
    ] = None,
    json: JsonOption = False,
) -> None:
    """Convert a saved run: --mcap writes run.mcap for Foxglove or Rerun.

    Open it in Foxglove with the layout shipped as tetherland/viz/foxglove_layout.json
    (its path: python -c "import tetherland.viz.layout as l; print(l.layout_path())").
    """
    if not mcap:
        raise ConfigError("choose an output format: --mcap (the only one so far)")
    from tetherland.viz import load_run
    from tetherland.viz.layout import layout_path
    from tetherland.viz.mcap import write_mcap

    target = out or run_dir / "run.mcap"
    if target.suffix != ".mcap":
        raise ConfigError(f"--out must end in .mcap (got '{target.name}')")
    if target.is_dir():
        raise ConfigError(f"--out '{target}' is a directory; give a file name ending in .mcap")
    run = load_run(run_dir)
    try:
        result = write_mcap(run, target)
    except OSError as err:  # a folder we may not write, a path through a file, a full disk
        why = f"{err.strerror}: '{err.filename}'" if err.strerror and err.filename else err
        raise ConfigError(f"--out: cannot write '{target}' ({why})") from None
    doc = {"mcap": str(result.path), "ticks": result.ticks, "events": result.events,
           "layout": str(layout_path())}  # fmt: skip
    if json:
        typer.echo(dumps_json(doc), nl=False)
    else:
        console.print(
            f"wrote {result.path} ({result.ticks} control ticks, {result.events} events); "
            f"Foxglove layout: {doc['layout']}"
        )
