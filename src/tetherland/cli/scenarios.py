"""`tetherland scenarios` (the built-in scenarios) and `tetherland show` (one, resolved)."""

from __future__ import annotations

import json
import textwrap
from typing import Annotated, Any

import typer
from rich.table import Table

from tetherland.cli.common import ScenarioArg, SetOption, console, resolve_scenario
from tetherland.config import Scenario, builtin_scenarios, scenario_to_toml
from tetherland.config.schema import FieldDoc, fields, sections

COMMENT_WIDTH = 92
"""Width of the field descriptions of ``show --all`` [characters]."""


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


def show(
    scenario: ScenarioArg,
    overrides: SetOption = None,
    all_fields: Annotated[
        bool,
        typer.Option(
            "--all",
            help="Print every field, unset ones included (commented out), each with its "
            "meaning, unit and allowed range as TOML comments.",
        ),
    ] = False,
) -> None:
    """Print a scenario with its overrides applied, every value resolved, as TOML.

    A scenario file needs only the fields it changes: every field it leaves out takes its
    default (the values --all prints for a file that sets nothing)."""
    sc = resolve_scenario(scenario, overrides)
    typer.echo(annotated_toml(sc) if all_fields else scenario_to_toml(sc), nl=False)


def _toml_value(value: Any) -> str:
    """A JSON-mode value as a TOML value (JSON strings, numbers, booleans and arrays of
    them are TOML too)."""
    return json.dumps(value)


def _describe(doc: FieldDoc) -> str:
    """``[unit], range R, type T``: what a value of the field may be."""
    parts = [f"[{doc.unit}]"] if doc.unit else []
    if doc.range:
        parts.append(f"range {doc.range}")
    parts.append(doc.type)
    return ", ".join(parts)


def annotated_toml(scenario: Scenario) -> str:
    """Every field of ``scenario`` as TOML, in the schema's order, with its meaning above
    it and its unit, range and type after it as comments; a field left unset (None) is
    written commented out, ``# key =  # unset; ...``. The text loads back to the same
    scenario."""
    dumped = scenario.model_dump(mode="json")
    by_section: dict[str, list[FieldDoc]] = {}
    for doc in fields(Scenario):
        by_section.setdefault(doc.section, []).append(doc)
    lines: list[str] = []
    for section, _ in sections(Scenario):
        table: Any = dumped
        for part in filter(None, section.split(".")):
            table = table[part]
        if section:
            lines += ["", f"[{section}]"]
        for doc in by_section.get(section, []):
            if doc.meaning:
                lines += textwrap.wrap(doc.meaning, COMMENT_WIDTH, initial_indent="# ",
                                       subsequent_indent="# ")  # fmt: skip
            value = table.get(doc.name)
            if value is None:
                lines.append(f"# {doc.name} =  # unset; {_describe(doc)}")
            else:
                lines.append(f"{doc.name} = {_toml_value(value)}  # {_describe(doc)}")
    return "\n".join(lines).lstrip() + "\n"
