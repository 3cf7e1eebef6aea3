"""Hooking clearance: analytic distances, the plant's contacts, the supervisor's refusal."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherland.analysis.clearance import (
    hooking_clearance,
    level_vehicle_distance,
    surface_distance,
)
from tetherland.config import load_scenario
from tetherland.geometry import LandingGeometry
from tetherland.mission import MissionError, plan_mission
from tetherland.rotations import rotation_from_z_and_yaw, rotmat_to_quat
from tetherland.sim.mjcf import FRAME_PARTS
from tetherland.sim.plant import Plant
from tetherland.state import RigidBodyState


def _surface(name: str, *overrides: str):
    scenario = load_scenario(name, overrides)
    return scenario, LandingGeometry.from_scenario(scenario).surface


def test_plane_distance_is_the_height_along_the_normal():
    _, surf = _surface("slope50")
    p = surf.origin + 0.3 * surf.z_S + 0.7 * surf.x_S - 0.2 * surf.y_S
    assert surface_distance(surf, p)[0] == pytest.approx(0.3, abs=1e-12)


def test_pipe_distance_from_the_axis():
    _, surf = _surface("pipe60")
    R = surf.pipe_radius
    axis = surf.origin - R * surf.z_S
    # on the top line, beside the pipe at its widest, and on the axis
    assert surface_distance(surf, surf.origin + 0.1 * surf.z_S)[0] == pytest.approx(0.1)
    side = axis + 2.0 * surf.x_S + (R + 0.05) * surf.y_S
    assert surface_distance(surf, side)[0] == pytest.approx(0.05)
    assert surface_distance(surf, axis + 5.0 * surf.x_S)[0] == pytest.approx(-R)
    # off the top line the pipe falls away from its tangent plane
    y = 0.15
    off = surf.origin + y * surf.y_S
    assert surface_distance(surf, off)[0] == pytest.approx(math.hypot(R, y) - R)


_UP = np.array([0.0, 0.0, 1.0])


def _level_state(p_W, yaw: float) -> RigidBodyState:
    R = rotation_from_z_and_yaw(_UP, yaw)
    return RigidBodyState.at_rest(np.asarray(p_W, dtype=float), rotmat_to_quat(R))


@pytest.mark.parametrize(
    ("name", "overrides"),
    [("slope50", ()), ("slope50", ("surface.slope_deg=65",)), ("pipe60", ())],
)
@pytest.mark.parametrize("yaw", [0.0, 0.4])
def test_predicted_distance_matches_the_plants_contacts(name, overrides, yaw):
    """1 cm into the surface the plant reports contact, 1 cm away it reports none."""
    scenario, surf = _surface(name, *overrides)
    plant = Plant(scenario)
    # above the anchor region, uphill of the landing point
    base = surf.origin - 0.6 * surf.x_S + 0.5 * _UP
    d0 = level_vehicle_distance(scenario, surf, base, yaw)
    for target, touching in ((-0.01, True), (0.01, False)):
        lo, hi = -1.0, 1.0  # bisect the height shift giving the target distance
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            d = level_vehicle_distance(scenario, surf, base + mid * _UP, yaw)
            lo, hi = (mid, hi) if d < target else (lo, mid)
        assert d0 != target
        plant.set_state(_level_state(base + hi * _UP, yaw))
        force = plant.frame_contact_force + float(np.sum(plant.lander_forces))
        assert (plant.data.ncon > 0) is touching
        assert (force > 0.0) is touching


@settings(max_examples=25, deadline=None)
@given(
    slope=st.floats(0.0, 75.0),
    drop=st.floats(0.0, 0.8),
    yaw=st.floats(-math.pi, math.pi),
)
def test_required_hook_drop_restores_the_margin_on_planes(slope, drop, yaw):
    scenario, surf = _surface(
        "slope50", f"surface.slope_deg={slope}", "tether.length=3.0", f"tether.hook_drop={drop}"
    )
    hook = surf.origin - 0.8 * surf.x_S  # a hook point on the surface
    up = np.array([0.0, 0.0, 1.0])
    check = hooking_clearance(scenario, surf, [hook + (drop + 0.03) * up], yaw, 0.02)
    assert check.required_hook_drop_m >= drop
    fixed = load_scenario(
        "slope50",
        [f"surface.slope_deg={slope}", "tether.length=3.0",
         f"tether.hook_drop={check.required_hook_drop_m}"],
    )  # fmt: skip
    raised = hook + (check.required_hook_drop_m + 0.03) * up
    again = hooking_clearance(fixed, surf, [raised], yaw, 0.02)
    assert again.clearance_m >= check.margin_m - 1e-9
    assert again.ok


def test_mission_plan_refuses_a_hook_drop_too_short_for_the_slope():
    scenario = load_scenario("slope50", ["surface.slope_deg=70"])
    with pytest.raises(MissionError, match=r"tether\.hook_drop = 0\.5 m is too short") as info:
        plan_mission(scenario, Plant(scenario).start_state())
    drop = str(info.value).split("set tether.hook_drop=")[1]  # the hint: a drop that works
    ok = load_scenario("slope50", ["surface.slope_deg=70", f"tether.hook_drop={drop}"])
    plan = plan_mission(ok, Plant(ok).start_state())
    wp = plan.waypoints
    check = hooking_clearance(
        ok, plan.geometry.surface, (wp.hook_start, wp.hook_end), wp.yaw,
        ok.mission.hooking.min_clearance,
    )  # fmt: skip
    assert check.ok and plan.clearance.ok
    assert check.clearance_m == pytest.approx(plan.clearance.clearance_m)


def _vehicle_surface_distance(plant: Plant) -> float:
    """MuJoCo's smallest signed distance between the surface and the vehicle's colliding
    geoms (mj_geomDistance) [m]."""
    import mujoco

    m, d = plant.model, plant.data
    surface = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "surface")
    fromto = np.zeros(6)
    geoms = [g for g in range(m.ngeom) if m.geom_bodyid[g] != 0 and m.geom_contype[g]]
    # hub, mount, four landers, legs, arms and rotor guards
    assert len(geoms) == 2 + 4 * 4 == len(FRAME_PARTS) + 4
    return min(mujoco.mj_geomDistance(m, d, surface, g, 1.0, fromto) for g in geoms)


@pytest.mark.parametrize("slope", [80.0, 90.0, 93.0])
@pytest.mark.parametrize("yaw", [0.0, 0.4, math.pi / 4])
def test_predicted_clearance_matches_mujoco_distances_on_walls(slope, yaw):
    """The level vehicle at known offsets from an 80 deg slope, a wall and an overhang:
    the predicted distance equals MuJoCo's geom distance (to the 5 deg rim sampling,
    < 0.1 mm), and the first contact appears within a millimetre of the prediction."""
    scenario, surf = _surface(
        "slope50", f"surface.slope_deg={slope}", "tether.length=0.4", "tether.hook_drop=0.3",
        "tether.capture_radius=0.05",
    )  # fmt: skip
    plant = Plant(scenario)
    for offset in (0.28, 0.32, 0.4, 0.6):
        p = surf.origin + offset * surf.z_S + 0.4 * _UP  # at the anchor's height
        plant.set_state(_level_state(p, yaw))
        predicted = level_vehicle_distance(scenario, surf, p, yaw)
        assert _vehicle_surface_distance(plant) == pytest.approx(predicted, abs=1e-4)
    # First contact: 1 mm short of the predicted touching position no contact, 1 mm past
    # it one at 1 mm penetration.
    base = surf.origin + 0.4 * _UP
    touching = (
        base + (0.5 - level_vehicle_distance(scenario, surf, base + 0.5 * surf.z_S, yaw)) * surf.z_S
    )  # distance is affine along z_S for a plane: exactly 0 here
    assert level_vehicle_distance(scenario, surf, touching, yaw) == pytest.approx(0.0, abs=1e-12)
    plant.set_state(_level_state(touching + 0.001 * surf.z_S, yaw))
    assert plant.data.ncon == 0 and plant.frame_contact_force == 0.0
    plant.set_state(_level_state(touching - 0.001 * surf.z_S, yaw))
    assert plant.data.ncon > 0
    deepest = min(plant.data.contact.dist)
    assert deepest == pytest.approx(-0.001, abs=1e-4)


MAGNET_WALL = ("mechanism.kind=magnet", "tether.length=0.38")
"""wall90 with the magnet mechanism (its boom 0.36 m at 40 deg, folding up to 60 deg)."""


def _boom_geom_distance(plant: Plant) -> float:
    """MuJoCo's signed distance between the surface and the boom's capsule [m]."""
    import mujoco

    m, d = plant.model, plant.data
    ids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, n) for n in ("surface", "boom")]
    return mujoco.mj_geomDistance(m, d, ids[0], ids[1], 1.0, np.zeros(6))


@pytest.mark.parametrize("yaw", [0.0, 0.3])
def test_the_magnets_boom_distance_is_the_plants(yaw):
    """The level vehicle in front of wall90 with the magnet mechanism: the unfolded boom's
    predicted distance is MuJoCo's for the plant's capsule; along the wall's normal (yaw 0,
    the approach along -z_S) it is the hinge's distance less L cos(a) and the tube's radius,
    derived here; clipped, the magnet's face (parallel to the wall) is a further
    ``magnet_thickness`` nearer; empty, the boom folds up to 60 deg, past the wall's
    normal (40 + 60 > 90 deg), so its largest distance over its folds is the hinge's."""
    from tetherland.analysis.clearance import boom_distance, mechanism_distance
    from tetherland.models.hook import BOOM_RADIUS, magnet_boom

    scenario, surf = _surface("wall90", *MAGNET_WALL)
    m = scenario.mechanism
    boom = magnet_boom(scenario)
    L, a = m.boom_length, math.radians(m.boom_angle_deg)
    plant = Plant(scenario)
    R = rotation_from_z_and_yaw(_UP, yaw)
    for offset in (0.30, 0.33, 0.45):
        p = surf.origin + offset * surf.z_S + 0.1 * _UP
        plant.set_state(_level_state(p, yaw))
        unfolded = boom_distance(scenario, surf, p, R, 0.0)
        assert unfolded == pytest.approx(_boom_geom_distance(plant), abs=1e-6)
        hinge = float(surface_distance(surf, p + R @ boom.hinge_B)[0])
        if yaw == 0.0:
            assert unfolded == pytest.approx(hinge - L * math.cos(a) - BOOM_RADIUS, abs=1e-9)
            clipped = mechanism_distance(scenario, surf, p, R, "clipped")
            tip = hinge - L * math.cos(a)
            assert clipped == pytest.approx(tip - m.magnet_thickness, abs=1e-9)
        assert mechanism_distance(scenario, surf, p, R, "held") == pytest.approx(
            hinge - BOOM_RADIUS, abs=1e-9
        )
    # no mechanism on the vehicle: nothing to add
    plain, surf0 = _surface("wall90")
    assert mechanism_distance(plain, surf0, surf0.origin + 0.5 * surf0.z_S, R, "held") == math.inf


OVERHANG_MAGNET = (
    "mechanism.kind=magnet", "tether.length=0.36", "mechanism.boom_angle_deg=20",
    "mechanism.plate_thickness=0.003", "mechanism.magnet_thickness=0.01",
)  # fmt: skip
"""overhang93 with the magnet as its campaign flies it (docs/walls.md), boom length apart."""


def test_the_take_up_keeps_the_empty_boom_foldable_out_of_the_overhang():
    """overhang93's take-up point (the level vehicle on the landing's start direction,
    the frame 2 cm from the overhang) puts the empty 0.32 m boom's unfolded tip behind the
    surface: the plan accepts it when the boom's 60 deg of fold take it out of the way,
    and refuses it, naming the boom, when the boom folds only 5 deg."""
    from tetherland.analysis.clearance import boom_distance, mechanism_distance

    s = load_scenario("overhang93", [*OVERHANG_MAGNET, "mechanism.boom_length=0.32"])
    plan = plan_mission(s, Plant(s).start_state())
    wp, surf = plan.waypoints, plan.geometry.surface
    R = rotation_from_z_and_yaw(_UP, wp.yaw)
    assert boom_distance(s, surf, wp.slack_out, R, 0.0) < 0.0  # unfolded: behind it
    assert mechanism_distance(s, surf, wp.slack_out, R, "held") >= 0.0  # folds clear
    stiff = load_scenario(
        "overhang93", [*OVERHANG_MAGNET, "mechanism.boom_length=0.32", "mechanism.boom_fold_deg=5"]
    )
    with pytest.raises(MissionError, match=r"take-up .* magnet's boom behind the surface"):
        plan_mission(stiff, Plant(stiff).start_state())
