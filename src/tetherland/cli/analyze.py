"""`tetherland analyze`: landing conditions and feasibility, contact-free vs tethered."""

from __future__ import annotations

import typer
from rich.markup import escape
from rich.table import Table

from tetherland.analysis import Infeasibility, LandingAnalysis
from tetherland.analysis import analyze as run_analysis
from tetherland.cli.common import (
    JsonOption,
    ScenarioArg,
    SetOption,
    console,
    deg,
    resolve_scenario,
    vec,
)
from tetherland.config import Scenario
from tetherland.io import dumps_json
from tetherland.provenance import provenance


def analyze(scenario: ScenarioArg, overrides: SetOption = None, json: JsonOption = False) -> None:
    """Analyse landing on the scenario's surface with and without a tether (Table 6.1).

    Exits with 1 and one line naming the binding reason when the tethered landing is
    infeasible on this surface (the report is still printed), with 2 on bad input.
    """
    sc = resolve_scenario(scenario, overrides)
    result = run_analysis(sc)
    if json:
        doc = {"scenario": sc.name, **result.to_dict(), "provenance": provenance(sc)}
        typer.echo(dumps_json(doc), nl=False)
    else:
        _print_report(sc, result)
    t = result.tethered
    if not t.feasible:
        binding = t.binding.value if t.binding is not None else "unknown"
        why = t.reasons[0] if t.reasons else "no feasible landed hover"
        typer.echo(
            f"error: tethered landing infeasible on {deg(result.geometry.surface.slope, 1)} "
            f"(binding: {binding}): {why}",
            err=True,
        )
        raise typer.Exit(1)


def _print_report(sc: Scenario, result: LandingAnalysis) -> None:
    """The human-readable report: geometry, Table 6.1, reasons and binding limits."""

    t, g = result.tethered, result.geometry
    console.print(
        f"[bold]{sc.name}[/bold]: {sc.description or sc.surface.kind}\n"
        f"surface {sc.surface.kind}, slope {deg(g.surface.slope, 1)}, mu = {sc.surface.friction}; "
        f"vehicle {sc.vehicle.mass} kg, rotors {sc.vehicle.f_min}-{sc.vehicle.f_max} N; "
        f"cable {sc.tether.length} m"
    )
    hover = result.hover  # before anything else: no landing without a hover in free flight
    if hover.ok:
        console.print(
            f"hover in free flight: ok (thrust-to-weight {result.limits.thrust_to_weight():.2f}, "
            f"needs >= {result.limits.hover_thrust_to_weight:.2f} with the control margin)"
        )
    else:
        console.print(f"[bold red]{Infeasibility.CANNOT_HOVER.value}:[/bold red] "
                      f"{escape(hover.message)}")  # fmt: skip
    geo = Table(title="Tethered landing geometry (6.8)-(6.13)", show_header=False)
    geo.add_column(style="bold")
    geo.add_column()
    geo.add_row("anchor p_A", vec(t.anchor_point) + " m")
    geo.add_row("landing point p~_L", vec(t.landing_point) + " m")
    geo.add_row("d~", vec(t.d_tilde))
    geo.add_row("c = (h_att - h_A)/l", f"{t.c:.4f}")
    geo.add_row("phi*, theta_A*", f"{deg(t.phi_star)}, {deg(t.theta_A_star)}")
    geo.add_row(
        "inclined hover f_R, f_L",
        f"{t.hover_thrust:.3f} N ({t.hover_thrust / 4:.3f} N per rotor), {t.hover_tension:.3f} N",
    )
    console.print(geo)

    table = Table(title="Table 6.1 for this scenario")
    table.add_column("", style="bold")
    table.add_column("contact-free flight")
    table.add_column("tethered")
    for row in result.table():
        table.add_row(row.label, row.free_flight, row.tethered)
    console.print(table)
    for name, reasons in (("contact-free", result.free_flight.reasons), ("tethered", t.reasons)):
        for reason in reasons:
            console.print(f"[yellow]{name}:[/yellow] {escape(reason)}")
    for name, binding in (("contact-free", result.free_flight.binding), ("tethered", t.binding)):
        if binding is not None:
            console.print(f"[bold]{name} infeasible here, binding: {binding.value}[/bold]")
