"""The ``tetherland`` command line: a thin layer over the library.

Bad input (unknown key, out-of-range value, missing file, ...) is reported on one line
on stderr with exit code 2 and no traceback.
"""

from __future__ import annotations

import functools
import os
import sys

# Offscreen rendering (``--video``) on a machine without a display: MuJoCo picks its GL
# backend at import, so choose EGL before anything imports it.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")

import typer
import typer.core
import typer.main
from typer.exceptions import TyperException

from tetherland import __version__
from tetherland.cli.analyze import analyze
from tetherland.cli.campaign import campaign_app
from tetherland.cli.common import INTERRUPTED
from tetherland.cli.design import design
from tetherland.cli.export import export
from tetherland.cli.judge import judge
from tetherland.cli.mission import mission
from tetherland.cli.plan import plan
from tetherland.cli.replay import replay
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
app.add_typer(campaign_app)
app.command()(design)
app.command()(mission)
app.command()(judge)
app.command()(export)
app.command()(plan)
app.command()(replay)


MESSAGE_CHARS = 300
"""Longest error line printed [characters] (a value may be a 50 MB array)."""


def one_line(text: object, limit: int = MESSAGE_CHARS) -> str:
    """``text`` on one printable line of at most ``limit`` characters."""
    line = " ".join("".join(c if c.isprintable() else " " for c in str(text)).split())
    return line if len(line) <= limit else line[: limit - 3] + "..."


def _error(err: BaseException | str) -> None:
    """Print ``error: ...``: one line per problem (a file with three bad fields: three)."""
    for message in getattr(err, "messages", None) or (err,):
        typer.echo(f"error: {one_line(message)}", err=True)


@functools.cache
def _command() -> typer.core.TyperGroup:
    """The click command of :data:`app`, built once (building it takes 0.1 s: calling
    :func:`main` many times in one process, as the tests do, stays fast)."""
    command = typer.main.get_command(app)
    assert isinstance(command, typer.core.TyperGroup)
    return command


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``tetherland`` script; returns the exit code."""
    try:
        result = _command().main(args=argv, prog_name="tetherland", standalone_mode=False)
    except InfeasibleError as err:
        _error(err)
        return 1
    except TetherlandError as err:
        _error(err)
        return 2
    except typer.Exit as err:
        return err.exit_code
    except (typer.Abort, KeyboardInterrupt) as err:
        if isinstance(err.__cause__ or err.__context__, EOFError):
            # click turns any EOFError into Abort: a truncated file, not a Ctrl-C
            _error(f"unexpected end of input ({err.__cause__ or err.__context__})")
            return 2
        typer.echo("aborted", err=True)
        return INTERRUPTED
    except TyperException as err:  # usage errors: unknown option, missing argument, ...
        if type(err).__name__ == "NoArgsIsHelpError":  # `tetherland` alone: the help, whole
            typer.echo(err.format_message(), err=True)
        else:
            _error(err.format_message())
        return err.exit_code
    return int(result) if isinstance(result, int) else 0


def run() -> None:  # pragma: no cover - the console script; tests call main()
    """The ``tetherland`` console script: :func:`main`, then exit with its code.

    After an interrupt everything worth keeping is on disk (written atomically and
    fsync'ed) and printed, so the process ends at once: tearing down the interpreter
    with its compiled solvers and kernels loaded takes seconds, and a stop should not.
    """
    code = main()
    if code == INTERRUPTED:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    sys.exit(code)


if __name__ == "__main__":  # pragma: no cover
    run()
