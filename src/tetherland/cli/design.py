"""`tetherland design`: cable, attachment, anchor height and hooking approach for a slope."""

from __future__ import annotations

import math
import os
from dataclasses import replace
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.markup import escape
from rich.table import Table

from tetherland import __version__
from tetherland.campaign.executors import make_executor
from tetherland.cli.common import (
    JsonOption,
    OverwriteOption,
    ScenarioArg,
    SetOption,
    console,
    resolve_scenario,
)
from tetherland.design import DesignResult, feasibility_map, search_designs, verify_designs
from tetherland.design.map import MAP_LENGTHS, MAP_SLOPES_DEG
from tetherland.design.plot import save_map_figure
from tetherland.io import OutputDir, atomic_write_json, atomic_write_text, dumps_json
from tetherland.planning import Planner
from tetherland.provenance import provenance

SlopeOption = Annotated[
    float | None,
    typer.Option(
        "--slope-deg",
        help="Slope to design for, 0-180 deg (90: wall, > 90: overhang); default: the "
        "scenario's surface.slope_deg.",
    ),
]
OutOption = Annotated[
    Path | None,
    typer.Option(
        "--out",
        help="Also write the feasibility map (PNG, CSV, JSON) and design.json here "
        "(slower: it designs every slope and cable length).",
        file_okay=False,
    ),
]
VerifyOption = Annotated[
    int,
    typer.Option(
        "--verify",
        help="Fly this many perturbed missions (the campaign's perturbations) of each of the "
        "--candidates best designs and rank them by the lower bound of their success rate's "
        "95 % interval (0: do not fly).",
        min=0,
    ),
]
CandidatesOption = Annotated[
    int, typer.Option("--candidates", help="How many of the best designs --verify flies.", min=1)
]
SeedOption = Annotated[
    int, typer.Option("--seed", help="Base seed of the --verify missions (a campaign's --seed).")
]
WorkersOption = Annotated[
    int | None,
    typer.Option("--workers", help="Parallel workers for --verify (default: all cores).", min=1),
]
_FILES = {"map": "feasibility_map.png", "map_data": "feasibility_map.json",
          "map_csv": "feasibility_map.csv", "design": "design.json"}  # fmt: skip
"""What ``--out`` holds, by role."""


def _table(result: DesignResult, mechanism: str = "disk") -> Table:
    """The designs as a table, best first. ``mechanism`` is the scenario's
    ``mechanism.kind``: the magnet has no hook drop (its boom holds the eye), so that column
    reads "n/a" for it."""
    table = Table(title=f"Designs for {result.slope_deg:g} deg, best first")
    verified = any(d.verified is not None for d in result.designs)
    columns = ["#", "l [m]", "r_att z [m]", "h_A [m]", "approach elev. [deg]", "hook drop [m]",
               "rotor margin [N] robust (nominal)", "believed hovers [N]",
               "clearance [cm] robust (nominal)"]  # fmt: skip
    for name in columns + (["verified (95 % low)"] if verified else []):
        table.add_column(name, justify="right")
    for k, d in enumerate(result.designs, 1):
        p = d.point
        x, y, z = p.approach_A
        # elevation below the horizontal toward the surface: 90 lowers the hook, 0 is level
        elevation = round(math.degrees(math.atan2(-z, math.hypot(x, y))))  # int: no "-0"
        row = [
            str(k), f"{p.length:g}", f"{p.attachment[2]:g}", f"{p.h_A:g}", f"{elevation:.0f}",
            "n/a" if mechanism == "magnet" else f"{p.hook_drop:g}",
            f"{d.robust_rotor_margin:.3f} ({d.min_rotor_margin:.3f})",
            f"{d.believed_hover_margin:+.3f}",
            f"{100 * d.robust_clearance:.1f} ({100 * d.min_clearance:.1f})",
        ]  # fmt: skip
        if verified:
            v = d.verified
            row.append("-" if v is None else f"{v.successes}/{v.runs} ({100 * v.ci_low:.0f} %)")
        table.add_row(*row)
    return table


def design(
    scenario: ScenarioArg,
    overrides: SetOption = None,
    slope_deg: SlopeOption = None,
    out: OutOption = None,
    overwrite: OverwriteOption = False,
    json: JsonOption = False,
    verify: VerifyOption = 0,
    candidates: CandidatesOption = 3,
    seed: SeedOption = 0,
    workers: WorkersOption = None,
) -> int:
    """Search the cable length, attachment offset along z_B, anchor height and hooking
    approach with which the scenario's vehicle can land on and take off from the slope.

    Candidates pass the landed-hover analysis, the hooking clearance and the planner
    (landing and takeoff OCPs solved and verified); they are ranked by the rotor margin
    over both plans, cable-offset torque included, then by clearance while hooking, both
    with the belief off by the [perturbation] bounds (robust first; a design whose
    boundary hovers, computed from such a belief, leave the rotors below the control
    margin ("believed hovers" < 0) is one the robot refuses to fly on part of the
    beliefs, and is not robust). --verify N flies N
    perturbed missions of each of the --candidates best and ranks them by the lower bound
    of their success rate's 95 % interval, then by those margins. The
    overrides of a design reproduce it with any other command (--set). Exits with 1 and
    a one-line reason when no design exists, with 2 on bad input.
    """
    sc = resolve_scenario(scenario, overrides)
    target = OutputDir(out, overwrite=overwrite) if out is not None else None
    planner = Planner()
    result = search_designs(sc, slope_deg, planner=planner, fixes=True)
    if verify and result.feasible:
        executor = make_executor("local", workers or os.cpu_count() or 1)
        try:
            ranked = verify_designs(sc, result.designs, verify, seed, executor, candidates)
        finally:
            executor.close()
        result = replace(result, designs=ranked)
    doc: dict[str, Any] = result.to_dict()
    files: dict[str, str] = {}
    doc["files"] = files
    extra: dict[str, Any] = {"slope_deg": result.slope_deg}
    if verify:
        extra.update(verify=verify, candidates=candidates, verify_seed=seed)
    doc["provenance"] = provenance(sc, extra=extra)
    if target is not None:
        fmap = feasibility_map(sc, planner=planner, slopes_deg=MAP_SLOPES_DEG, lengths=MAP_LENGTHS)
        record = provenance(sc, extra={"slope_deg": result.slope_deg})
        title = (
            f"{sc.name}: {sc.vehicle.mass:g} kg, rotors {sc.vehicle.f_min:g}-"
            f"{sc.vehicle.f_max:g} N, control margin {sc.vehicle.control_margin:g} N\n"
            f"hooking pass: overshoot {sc.mission.hooking.overshoot:g} m, capture radius "
            f"{sc.tether.capture_radius:g} m"
        )
        header = (
            f"# tetherland {__version__} ({record['git_commit']}), scenario {sc.name}; "
            "provenance in feasibility_map.json\n"
        )
        map_doc = {
            **fmap.to_dict(),
            "chosen": None if result.chosen is None else result.chosen.to_dict(),
            "provenance": record,
        }
        doc["map_wall_time_s"] = fmap.wall_time_s
        files.update({role: str(target.path / name) for role, name in _FILES.items()})
        with target.staging() as stage:  # all at once: nothing of an earlier design stays
            save_map_figure(stage / "feasibility_map.png", fmap, result.chosen, title)
            atomic_write_json(stage / "feasibility_map.json", map_doc)
            atomic_write_text(stage / "feasibility_map.csv", header + fmap.to_csv())
            atomic_write_json(stage / "design.json", doc)
    if json:
        typer.echo(dumps_json(doc), nl=False)
    else:
        v = sc.vehicle
        console.print(
            f"[bold]{sc.name}[/bold]: {v.mass:g} kg, rotors {v.f_min:g}-{v.f_max:g} N "
            f"(control margin {v.control_margin:g} N), {sc.surface.kind} at "
            f"{result.slope_deg:g} deg"
        )
        if result.feasible:
            console.print(_table(result, sc.mechanism.kind))
            chosen = result.chosen
            assert chosen is not None
            console.print(
                "chosen: " + escape(" ".join(f"--set {o}" for o in chosen.overrides)),
                soft_wrap=True,
            )
        console.print(
            f"{result.candidates} candidates analysed, {result.planned} planned, "
            f"{result.wall_time_s:.2f} s"
            + (f"; map {doc['map_wall_time_s']:.1f} s" if "map_wall_time_s" in doc else "")
        )
        for name, path in files.items():
            console.print(f"{name}: {escape(path)}")
    if not result.feasible:
        typer.echo(f"error: {result.reason}", err=True)
        raise typer.Exit(1)
    return 0
