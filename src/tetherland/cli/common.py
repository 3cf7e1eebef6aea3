"""Options and helpers shared by every command."""

from __future__ import annotations

import math
from typing import Annotated

import typer
from rich.console import Console

from tetherland.config import Scenario, load_scenario

ScenarioArg = Annotated[
    str,
    typer.Argument(
        help="Built-in scenario name (see `tetherland scenarios`) or path to a TOML file."
    ),
]
SetOption = Annotated[
    list[str] | None,
    typer.Option(
        "--set",
        help="Override a scenario value, e.g. --set surface.slope_deg=70 (value parsed as TOML). "
        "Repeatable.",
        metavar="SECTION.KEY=VALUE",
    ),
]
JsonOption = Annotated[
    bool, typer.Option("--json", help="Print a JSON document on stdout instead of tables.")
]

console = Console()
err_console = Console(stderr=True)


def resolve_scenario(source: str, overrides: list[str] | None) -> Scenario:
    """Load the scenario named on the command line (raises ConfigError on bad input)."""
    return load_scenario(source, overrides or [])


def deg(value: float | None, digits: int = 2) -> str:
    """Format radians as degrees, or '-' for None."""
    return "-" if value is None else f"{math.degrees(value):.{digits}f} deg"


def vec(v) -> str:
    """Format a 3-vector."""
    return "[" + ", ".join(f"{float(x):+.3f}" for x in v) + "]"
