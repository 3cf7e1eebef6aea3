"""The ``tetherland`` command line: a thin layer over the library.

Bad input (unknown key, out-of-range value, missing file, ...) is reported on one line
on stderr with exit code 2 and no traceback.
"""

from __future__ import annotations

import functools
import importlib
import os
import sys
from collections.abc import Iterator, MutableMapping
from typing import Any

# Offscreen rendering (``--video``) on a machine without a display: MuJoCo picks its GL
# backend at import, so choose EGL before anything imports it.
if not os.environ.get("DISPLAY"):
    os.environ.setdefault("MUJOCO_GL", "egl")

import typer
import typer.core
import typer.main
from typer.exceptions import TyperException

from tetherland import __version__
from tetherland.errors import InfeasibleError, TetherlandError

INTERRUPTED = 130
"""Exit code after Ctrl-C or SIGTERM (128 + SIGINT)."""

COMMANDS: dict[str, tuple[str, str]] = {
    "scenarios": ("tetherland.cli.scenarios", "scenarios"),
    "show": ("tetherland.cli.scenarios", "show"),
    "analyze": ("tetherland.cli.analyze", "analyze"),
    "design": ("tetherland.cli.design", "design"),
    "mission": ("tetherland.cli.mission", "mission"),
    "judge": ("tetherland.cli.judge", "judge"),
    "export": ("tetherland.cli.export", "export"),
    "plan": ("tetherland.cli.plan", "plan"),
    "replay": ("tetherland.cli.replay", "replay"),
    "campaign": ("tetherland.cli.campaign", "campaign_app"),
}
"""The subcommands, in the order of ``tetherland --help``: name -> (module, function or
Typer app). A command's module is imported when the command runs: ``tetherland show``
does not load the simulator, the solvers and matplotlib, and neither does a campaign's
spawned worker, which runs the console script again as its ``__main__`` (3 s of imports
per process before)."""

SUMMARIES: dict[str, str] = {
    "scenarios": "List the built-in scenarios (or print one with --show).",
    "show": "Print a scenario with its overrides applied, every value resolved, as TOML.",
    "analyze": "Analyse landing on the scenario's surface with and without a tether (Table 6.1).",
    "design": "Search the cable length, attachment offset along z_B, anchor height and "
    "hooking approach with which the scenario's vehicle can land on and take off from the "
    "slope.",
    "mission": "Fly the full mission closed loop (MuJoCo, sensors, UKF, planner, "
    "controllers, supervisor).",
    "judge": "Judge a saved run again from its log.npz and run.json (any landing method).",
    "export": "Convert a saved run: --mcap writes run.mcap for Foxglove or Rerun.",
    "plan": "Plan the tethered landing or takeoff (OCP 6.21 or spline) and write "
    "trajectory.csv, trajectory.png and plan.json into the output directory (an earlier "
    "plan there is replaced as a whole only with --overwrite).",
    "replay": "Fly run RUN_ID of a campaign again, exactly as the campaign did (its "
    "scenario and sweep value, seed, perturbation, wind and fault), write its run "
    "directory, and explain it: when, in which phase and why it failed.",
    "campaign": "Randomised runs in parallel (campaign SCENARIO), or the report of one "
    "(campaign report DIR).",
}
"""Each subcommand's short help (the first sentence of its own help), so that
``tetherland --help`` lists the commands without importing their modules (2-3 s: every
command's module loads the simulator or the solvers). A test keeps them equal to the
commands' own."""


class _RootGroup(typer.core.TyperGroup):
    """The root command: its help lists :data:`SUMMARIES`, not the built commands."""

    def list_commands(self, ctx: Any) -> list[str]:
        """The subcommands' names, in :data:`COMMANDS`' order (typer's own lists the
        items, which builds every command)."""
        return list(self.commands)

    def format_commands(self, ctx: Any, formatter: Any) -> None:
        """The "Commands" section of ``tetherland --help``, as click writes it (each
        summary shortened to the width left beside the longest name)."""
        names = list(self.list_commands(ctx))
        limit = formatter.width - 6 - max(len(name) for name in names)
        rows = [
            (name, typer.core.TyperCommand(name, help=SUMMARIES[name]).get_short_help_str(limit))
            for name in names
        ]
        with formatter.section("Commands"):
            formatter.write_dl(rows)


app = typer.Typer(
    name="tetherland",
    cls=_RootGroup,
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


def _subcommand(name: str) -> typer.core.TyperCommand | typer.core.TyperGroup:
    """The click command of subcommand ``name``, built as :data:`app` would build it."""
    module, attr = COMMANDS[name]
    target = getattr(importlib.import_module(module), attr)
    if isinstance(target, typer.Typer):  # a group of its own (campaign run / report)
        command = typer.main.get_command(target)
    else:
        single = typer.Typer(
            add_completion=False, pretty_exceptions_enable=False, rich_markup_mode=None
        )
        single.command(name)(target)
        command = typer.main.get_command(single)
    assert isinstance(command, typer.core.TyperCommand | typer.core.TyperGroup)
    return command


class _LazyCommands(MutableMapping[str, Any]):
    """The root group's ``commands``: each built by :func:`_subcommand` on first use."""

    def __init__(self) -> None:
        self._built: dict[str, Any] = {}

    def __getitem__(self, name: str) -> Any:
        if name not in self._built:
            if name not in COMMANDS:
                raise KeyError(name)
            self._built[name] = _subcommand(name)
        return self._built[name]

    def __setitem__(self, name: str, command: Any) -> None:
        raise TypeError(f"the tetherland commands are listed in COMMANDS (not {name!r})")

    def __delitem__(self, name: str) -> None:
        raise TypeError(f"the tetherland commands are listed in COMMANDS (not {name!r})")

    def __iter__(self) -> Iterator[str]:
        return iter(COMMANDS)

    def __len__(self) -> int:
        return len(COMMANDS)


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
    """The click command of :data:`app` with the subcommands of :data:`COMMANDS`, built
    once (building them takes 0.1 s: calling :func:`main` many times in one process, as
    the tests do, stays fast), each subcommand when it is first used."""
    command = typer.main.get_command(app)
    assert isinstance(command, typer.core.TyperGroup)
    command.commands = _LazyCommands()
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
