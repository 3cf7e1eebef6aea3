"""`tetherland design` with the magnet mechanism: the anchor height the magnet fixes, the
approach along the surface's normal, cables longer than the boom, one line when the rotor
floor binds (overhang93 as built)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.cli import main
from tetherland.cli.design import _table
from tetherland.config import load_scenario, with_overrides
from tetherland.design import DesignSpace, search_designs
from tetherland.design.search import DesignLimit
from tetherland.geometry import LandingGeometry, effective_h_R, stretched_link_length
from tetherland.mission.hooking import check_pass, hooking_pass, pass_clearance
from tetherland.mission.plan import MissionError, plan_mission
from tetherland.models.hook import magnet_reach_margin
from tetherland.sim.mjcf import SceneLayout

MAGNET = "mechanism.kind=magnet"
OVERHANG_BY_HAND = (  # docs/mechanism.md: overhang93's magnet as a user built it by hand
    MAGNET, "mechanism.boom_length=0.30", "mechanism.boom_angle_deg=20",
    "mechanism.plate_thickness=0.003", "mechanism.magnet_thickness=0.01",
)  # fmt: skip


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def _normal_A(sc) -> np.ndarray:
    """-z_S in F_A: the direction that presses the magnet's face on the plate."""
    geo = LandingGeometry.from_scenario(sc)
    return geo.R_WA.T @ -geo.surface.z_S


def _check_magnet_designs(base, overrides_list) -> None:
    """Every design's overrides load as a valid magnet scenario whose anchor height is the
    magnet's (plate + magnet thickness, the fields' values), whose cable outreaches the
    boom, whose approach is the surface's normal, and whose magnet meets the surface first
    and passes the frame ``min_clearance`` from it."""
    m = base.mechanism
    h_A = m.plate_thickness + m.magnet_thickness
    for overrides in overrides_list:
        assert f"anchor.h_A={h_A:.6g}" in overrides
        sc = with_overrides(base, overrides)  # validated: the magnet's h_A check passes
        assert sc.mechanism.kind == "magnet"
        assert sc.anchor.h_A == pytest.approx(h_A, abs=1e-12)
        assert sc.tether.length > m.boom_length
        n = np.asarray(sc.tether.approach_direction)
        assert np.allclose(n, _normal_A(sc), atol=1e-6)
        assert magnet_reach_margin(sc) > 0.0
        geo = LandingGeometry.from_scenario(sc)
        assert pass_clearance(sc, geo, hooking_pass(sc, geo)) >= (
            sc.mission.hooking.min_clearance - 1e-9
        )


def test_wall90_magnet_designs_keep_the_magnets_anchor_height(capsys):
    code, out, err = run(capsys, "design", "wall90", "--set", MAGNET, "--json")
    assert code == 0 and err == ""
    doc = json.loads(out)
    assert doc["feasible"] is True and doc["reason"] == "ok" and doc["designs"]
    base = load_scenario("wall90", [MAGNET])
    _check_magnet_designs(base, [d["overrides"] for d in doc["designs"]])
    # the search tried one anchor height: the grid is lengths longer than the boom x
    # attachment offsets
    space = DesignSpace()
    longer = [v for v in space.lengths if v > base.mechanism.boom_length]
    assert doc["candidates"] == len(longer) * len(space.attachment_z)


def _per_rotor_floor_thrust(sc, length: float) -> float:
    """The landed inclined hover's thrust per rotor with the cable at the centre of mass,
    f_R / 4 = m g (cos(beta) + tan(gamma) sin(beta)) / 4, sin(gamma) = (h_att - h_A)/(l + s)
    (docs/theory.md section 13; s the elastic cable's stretch) [N]."""
    v = sc.vehicle
    beta = math.radians(sc.surface.slope_deg)
    h = effective_h_R(sc) - sc.anchor.h_A
    link = stretched_link_length(h, length, beta, v.mass, sc.tether.effective_axial_stiffness)
    gamma = math.asin(h / link)
    return v.mass * GRAVITY * (math.cos(beta) + math.tan(gamma) * math.sin(beta)) / 4.0


def test_overhang93_magnet_as_built_the_rotor_floor_binds_in_one_line(capsys):
    base = load_scenario("overhang93", [MAGNET])
    m, v = base.mechanism, base.vehicle
    floor = v.f_min + v.control_margin
    space = DesignSpace()
    shortest = min(x for x in space.lengths if x > m.boom_length)
    # the shortest cable longer than the boom has the steepest cable, the largest f_R: below
    # the floor there, so at every longer one (the cable at the centre of mass)
    assert _per_rotor_floor_thrust(base, shortest) < floor
    # a shorter cable (inside the boom's length) would hold it
    held = [x for x in space.lengths if _per_rotor_floor_thrust(base, x) >= floor]
    assert held and max(held) <= m.boom_length

    result = search_designs(base)
    assert not result.feasible and result.limit is DesignLimit.LANDED_HOVER
    assert result.binding == "rotor_floor"
    assert "\n" not in result.reason
    assert f"mechanism.boom_length = {m.boom_length:g} m" in result.reason
    assert f"= {m.plate_thickness + m.magnet_thickness:g} m" in result.reason
    assert f"holds the landed hover is {max(held):g} m" in result.reason

    code, _, err = run(capsys, "design", "overhang93", "--set", MAGNET)
    lines = err.strip().splitlines()
    assert code == 1 and len(lines) == 1 and "rotor_floor binds" in lines[0]


def test_overhang93_magnet_built_by_hand_has_designs():
    # docs/mechanism.md's overhang93 settings: a 1.3 cm anchor height and a 30 cm boom
    base = load_scenario("overhang93", list(OVERHANG_BY_HAND))
    result = search_designs(base)
    assert result.feasible, result.reason
    _check_magnet_designs(base, [d.overrides for d in result.designs])


def test_no_cable_longer_than_the_boom_is_one_line():
    base = load_scenario("wall90", [MAGNET])
    space = DesignSpace(lengths=(0.3, base.mechanism.boom_length))
    result = search_designs(base, space=space)
    assert not result.feasible and result.limit is DesignLimit.LANDED_HOVER
    assert result.candidates == 0 and "\n" not in result.reason
    assert f"longer than the magnet's mechanism.boom_length = {base.mechanism.boom_length:g}" in (
        result.reason
    )


@pytest.mark.slow
def test_wall90_magnet_verified_design_lands(capsys):
    code, out, _ = run(capsys, "design", "wall90", "--set", MAGNET, "--verify", "1",
                         "--candidates", "1", "--workers", "1", "--json")  # fmt: skip
    assert code == 0
    doc = json.loads(out)
    verified = doc["designs"][0]["verified"]
    assert verified is not None and verified["runs"] == 1 and verified["successes"] == 1


def test_a_design_the_missions_plan_refuses_is_not_listed():
    """overhang93's magnet by hand with a 32 cm cable, 2 cm over the 30 cm boom: the landed
    hover and the landing and takeoff plans hold, but the mission's plan refuses the
    take-up (the frame within min_clearance of the overhang): the search names that stage,
    and every design it lists plans as a mission."""
    base = load_scenario("overhang93", list(OVERHANG_BY_HAND))
    short = with_overrides(base, ["tether.length=0.32"])
    start = SceneLayout.from_scenario(short).start_state(short.vehicle.h_R)
    with pytest.raises(MissionError, match="take-up"):
        plan_mission(short, start)
    result = search_designs(base, space=DesignSpace(lengths=(0.32,), attachment_z=(0.0,)))
    assert not result.feasible and result.limit is DesignLimit.MISSION_PLAN
    assert "take-up" in result.reason and "\n" not in result.reason
    assert "tetherland design" not in result.reason  # the mission's hint, not repeated here
    ok = search_designs(base, space=DesignSpace(attachment_z=(0.0,)))
    assert ok.feasible
    for d in ok.designs:
        sc = d.point.apply(base)
        plan_mission(sc, SceneLayout.from_scenario(sc).start_state(sc.vehicle.h_R))
    # the table: the magnet has no hook drop (the boom holds the eye), whatever the
    # scenario's tether.hook_drop; the same designs under a point hook would show it
    for kind, expected in (("magnet", ["n/a"]), ("disk", [f"{base.tether.hook_drop:g}"])):
        drops = {c.header: list(c.cells) for c in _table(ok, kind).columns}["hook drop [m]"]
        assert drops == expected * len(ok.designs), kind


def test_a_magnet_pass_too_close_to_the_wall_names_the_normal_approach_not_the_hook_drop():
    """wall90's magnet on an 80 deg wall keeps wall90's level approach: pressing the face
    on the plate along it brings the frame's lower edge within min_clearance of a wall that
    leans 10 deg away at its foot. The magnet's eye sits on the boom's tip, so the hook drop
    the point hook would get named plays no part: the line names the approach along the
    wall's inward normal, -z_S in F_A, and that approach plans."""
    sc = load_scenario("wall90", [MAGNET, "surface.slope_deg=80", "tether.length=0.38"])
    start = SceneLayout.from_scenario(sc).start_state(sc.vehicle.h_R)
    geo = LandingGeometry.from_scenario(sc)
    assert not check_pass(sc, geo, hooking_pass(sc, geo)).ok
    with pytest.raises(MissionError) as err:
        plan_mission(sc, start)
    message = str(err.value)
    assert "\n" not in message and "hook_drop" not in message
    n_A = _normal_A(sc)
    e = math.radians(90.0 - 80.0)  # the normal's elevation below the level approach
    np.testing.assert_allclose(n_A, [-math.cos(e), 0.0, -math.sin(e)], atol=1e-12)
    written = ",".join(f"{v:.6g}" for v in n_A)
    assert f"tether.approach_direction=[{written}]" in message
    assert "tetherland design wall90" in message
    normal = with_overrides(sc, [f"tether.approach_direction=[{written}]"])
    plan_mission(normal, start)  # the named approach plans
    # already along the normal and still too close: only the design command is named
    strict = with_overrides(normal, ["mission.hooking.min_clearance=0.2"])
    with pytest.raises(MissionError) as err:
        plan_mission(strict, start)
    message = str(err.value)
    assert message.startswith(f"tether.approach_direction = [{written}] presses the magnet")
    assert "approach along" not in message and "tetherland design wall90" in message
