"""`tetherland scenarios`: list the built-in scenarios."""

from __future__ import annotations

from typing import Annotated

import typer
from rich.table import Table

from tetherland.cli.common import ScenarioArg, SetOption, console, resolve_scenario
from tetherland.config import builtin_scenarios, scenario_to_toml


def scenarios(
    show: Annotated[
        str | None,
        typer.Option("--show", help="Print one scenario, fully resolved, as TOML."),
    ] = None,
) -> None:
    """List the built-in scenarios (or print one with --show)."""
    if show is not None:
        typer.echo(scenario_to_toml(resolve_scenario(show, None)), nl=False)
        return
    table = Table(title="Built-in scenarios", show_lines=False)
    table.add_column("name", style="bold")
    table.add_column("description")
    for info in builtin_scenarios():
        table.add_row(info.name, info.description)
    console.print(table)


def show(scenario: ScenarioArg, overrides: SetOption = None) -> None:
    """Print a scenario with its overrides applied, every value resolved, as TOML."""
    typer.echo(scenario_to_toml(resolve_scenario(scenario, overrides)), nl=False)
