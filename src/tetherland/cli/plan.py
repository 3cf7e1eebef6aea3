"""`tetherland plan`: the optimal (or spline) landing/takeoff trajectory, as CSV and PNG."""

from __future__ import annotations

import math
from enum import StrEnum
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.table import Table

from tetherland.cli.common import (
    JsonOption,
    OverwriteOption,
    ScenarioArg,
    SetOption,
    console,
    default_output,
    resolve_scenario,
)
from tetherland.io import OutputDir, atomic_write_json, dumps_json
from tetherland.planning import Maneuver, Planner, PlanningError, PlanResult
from tetherland.planning.plot import save_plan_figure
from tetherland.provenance import provenance


class _Maneuver(StrEnum):
    landing = "landing"
    takeoff = "takeoff"


class _Solver(StrEnum):
    fatrop = "fatrop"
    ipopt = "ipopt"


class _Method(StrEnum):
    ocp = "ocp"
    spline = "spline"


ManeuverOption = Annotated[
    _Maneuver, typer.Option("--maneuver", help="Tethered landing or takeoff.", case_sensitive=False)
]
SolverOption = Annotated[
    _Solver | None,
    typer.Option("--solver", help="NLP solver (default: planner.solver).", case_sensitive=False),
]
MethodOption = Annotated[
    _Method | None,
    typer.Option(
        "--method",
        help="Optimal control problem (6.21) or spline (default: planner.method).",
        case_sensitive=False,
    ),
]
OutOption = Annotated[
    Path | None,
    typer.Option("--out", help="Output directory (default: out/<scenario>/plan).", file_okay=False),
]


def _table(result: PlanResult, files: dict[str, str]) -> Table:
    s = result.summary()
    table = Table(title=f"{result.maneuver.value} plan: {result.status.value}", show_header=False)
    table.add_column(style="bold")
    table.add_column()
    table.add_row("method", result.method + (f" ({result.solver})" if result.solver else ""))
    if result.method == "ocp" and s["cost"] is not None:
        table.add_row(
            "solve", f"{s['iterations']} iterations, {1e3 * s['solve_time_s']:.1f} ms"
            + (f" (+ {s['build_time_s']:.2f} s to build the solver)" if s["build_time_s"] else "")
        )  # fmt: skip
        table.add_row("cost J", f"{s['cost']:.6g}")
    b = s["boundary"]
    table.add_row(
        "phi, theta_A",
        f"{b['phi_start_deg']:.2f}, {b['theta_A_start_deg']:.2f} deg -> "
        f"{b['phi_final_deg']:.2f}, {b['theta_A_final_deg']:.2f} deg in {s['duration_s']:g} s",
    )
    if s["final_error"] is not None:
        fe = s["final_error"]
        table.add_row(
            "final error",
            f"phi {fe['phi_rad']:.1e} rad, theta_A {fe['theta_A_rad']:.1e} rad, "
            f"phi' {fe['phi_rate']:.1e}, theta_A' {fe['theta_A_rate']:.1e} rad/s",
        )
        table.add_row("min tension", f"{s['min_tension_N']:.3f} N")
        table.add_row(
            "rotor thrusts", f"{s['min_rotor_thrust_N']:.3f} .. {s['max_rotor_thrust_N']:.3f} N"
        )
    for name, path in files.items():
        table.add_row(name, path)
    if not result.success:
        table.add_row("reason", result.message)
    return table


def plan(
    scenario: ScenarioArg,
    overrides: SetOption = None,
    maneuver: ManeuverOption = _Maneuver.landing,
    solver: SolverOption = None,
    method: MethodOption = None,
    out: OutOption = None,
    overwrite: OverwriteOption = False,
    json: JsonOption = False,
) -> int:
    """Plan the tethered landing or takeoff (OCP 6.21 or spline) and write trajectory.csv,
    trajectory.png and plan.json into the output directory (an earlier plan there is
    replaced as a whole only with --overwrite).

    Exits with 1 and a one-line reason when no valid plan exists (infeasible, solver
    failure), with 2 on bad input.
    """
    sc = resolve_scenario(scenario, overrides)
    target = OutputDir(
        out if out is not None else default_output(sc.name, "plan"), overwrite=overwrite
    )
    result = Planner().plan(
        sc,
        Maneuver(maneuver.value),
        method=None if method is None else method.value,
        solver=None if solver is None else solver.value,
    )
    summary = result.summary()
    doc: dict[str, Any] = {"scenario": sc.name, **summary}
    files: dict[str, str] = {}
    doc["files"] = files
    doc["provenance"] = provenance(
        sc,
        extra={"maneuver": result.maneuver.value, "method": result.method, "solver": result.solver},
    )
    if result.success:  # written all at once: no file of an earlier plan stays beside them
        traj = result.require()
        with target.staging() as stage:
            traj.save_csv(stage / "trajectory.csv")
            save_plan_figure(
                stage / "trajectory.png",
                traj,
                result.spec,
                title=f"{sc.name}: {result.maneuver.value} ({result.method}), "
                f"slope {math.degrees(result.spec.theta_surface):.0f} deg",
            )
            for role, name in (("trajectory", "trajectory.csv"), ("plot", "trajectory.png"),
                               ("summary", "plan.json")):  # fmt: skip
                files[role] = str(target.path / name)
            atomic_write_json(stage / "plan.json", doc)
    if json:
        typer.echo(dumps_json(doc), nl=False)
    else:
        console.print(_table(result, files))
    if not result.success:
        # A valid request without a valid plan: exit 1 (bad input exits 2), one line.
        err = PlanningError(f"{result.maneuver.value} plan {result.status.value}: {result.message}")
        typer.echo(f"error: {err}", err=True)
        raise typer.Exit(1)
    return 0
