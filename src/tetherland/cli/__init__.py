"""The ``tetherland`` command line: a thin layer over the library.

Bad input (unknown key, out-of-range value, missing file, ...) is reported on one line
on stderr with exit code 2 and no traceback.
"""

from __future__ import annotations

import os
import sys

# Offscreen rendering (``--video``) on a machine without a display: MuJoCo picks its GL
# backend at import, so choose EGL before anything imports it.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")

import typer
from typer.exceptions import TyperException

from tetherland import __version__
from tetherland.cli.analyze import analyze
from tetherland.cli.campaign import campaign
from tetherland.cli.design import design
from tetherland.cli.export import export
from tetherland.cli.judge import judge
from tetherland.cli.mission import mission
from tetherland.cli.plan import plan
from tetherland.cli.scenarios import scenarios, show
from tetherland.errors import InfeasibleError, TetherlandError

app = typer.Typer(
    name="tetherland",
    help="Tethered landing and takeoff of aerial robots on steep slopes and pipes.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
)


def _version(value: bool) -> None:
    if value:
        typer.echo(f"tetherland {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """Tethered landing and takeoff of aerial robots on steep slopes and pipes."""


app.command()(scenarios)
app.command()(show)
app.command()(analyze)
app.command()(campaign)
app.command()(design)
app.command()(mission)
app.command()(judge)
app.command()(export)
app.command()(plan)


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``tetherland`` script; returns the exit code."""
    try:
        result = app(args=argv, prog_name="tetherland", standalone_mode=False)
    except InfeasibleError as err:
        typer.echo(f"error: {err}", err=True)
        return 1
    except TetherlandError as err:
        typer.echo(f"error: {err}", err=True)
        return 2
    except typer.Exit as err:
        return err.exit_code
    except (typer.Abort, KeyboardInterrupt):
        typer.echo("aborted", err=True)
        return 130
    except TyperException as err:  # usage errors: unknown option, missing argument, ...
        typer.echo(f"error: {err.format_message()}", err=True)
        return err.exit_code
    return int(result) if isinstance(result, int) else 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
