"""The unhooking pass (issue 11): no deeper than ``mission.hooking.unhook_depth``, away from
the surface first, and clear of the believed and of a perturbed surface."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from tetherland.analysis.clearance import level_vehicle_distance
from tetherland.config import load_scenario
from tetherland.errors import ConfigError
from tetherland.geometry import LandingGeometry, link_direction
from tetherland.mission.hooking import hooking_pass, unhooking_path
from tetherland.mission.plan import free_flight_legs, plan_mission
from tetherland.sim.plant import Plant
from tetherland.surface import surface_frame_from_slope

NAMES = ("wall90", "overhang93", "slope50", "pipe60")


def _hook_depth(scenario, geo, p_W) -> float:
    """Signed depth n.(p_hook - p_A) of the hook point for the level vehicle at p_W [m]
    (the hook model: the attachment point moved by hook_drop along n)."""
    hp = hooking_pass(scenario, geo)
    n = hp.n_W
    c, s = math.cos(hp.yaw), math.sin(hp.yaw)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    r_att = R @ np.asarray(scenario.vehicle.cable_attachment, dtype=float)
    hook = p_W + r_att + scenario.tether.hook_drop * n
    return float(n @ (hook - geo.p_A))


@pytest.mark.parametrize("name", NAMES)
def test_the_entry_lies_on_the_pass_axis_at_the_unhook_depth(name):
    """The hook point at the entry is unhook_depth beyond the anchor along n (clipped to
    the overshoot), at the end of the pass overshoot; both on the pass's axis."""
    sc = load_scenario(name)
    geo = LandingGeometry.from_scenario(sc)
    hp = hooking_pass(sc, geo)
    cfg = sc.mission
    depth = min(cfg.hooking.unhook_depth, cfg.hooking.overshoot)
    entry = hp.entry(cfg.hooking.unhook_depth, cfg.hooking.overshoot)
    assert _hook_depth(sc, geo, hp.p_end_W) == pytest.approx(cfg.hooking.overshoot, abs=1e-12)
    assert _hook_depth(sc, geo, entry) == pytest.approx(depth, abs=1e-12)
    off_axis = np.cross(entry - hp.p_start_W, hp.n_W)
    assert np.linalg.norm(off_axis) == pytest.approx(0.0, abs=1e-12)
    # clipped: never beyond the end of the pass
    np.testing.assert_allclose(hp.entry(10.0, cfg.hooking.overshoot), hp.p_end_W, atol=1e-12)


def test_the_path_backs_off_along_the_approach_direction_first():
    """From a point 6 cm deeper than the entry and 4 cm off the axis: the first corner is
    that point moved 6 cm along -n (the offset across n unchanged), then the entry, then
    the hooking start; from a shallower point the path goes straight to the entry."""
    sc = load_scenario("wall90")
    geo = LandingGeometry.from_scenario(sc)
    hp = hooking_pass(sc, geo)
    entry = hp.entry(sc.mission.hooking.unhook_depth, sc.mission.hooking.overshoot)
    n = hp.n_W
    across = np.cross(n, [0.0, 1.0, 0.0])
    across /= np.linalg.norm(across)
    deep = entry + 0.06 * n + 0.04 * across
    first, e, start = unhooking_path(deep, entry, hp.p_start_W)
    np.testing.assert_allclose(first, entry + 0.04 * across, atol=1e-12)
    np.testing.assert_allclose(e, entry, atol=1e-12)
    np.testing.assert_allclose(start, hp.p_start_W, atol=1e-12)
    shallow = entry - 0.03 * n + 0.04 * across
    path = unhooking_path(shallow, entry, hp.p_start_W)
    assert len(path) == 2
    # nowhere deeper along n than the deeper of the release point and the entry
    for p0 in (deep, shallow):
        deepest = max(float(n @ p0), float(n @ entry))
        assert max(float(n @ p) for p in unhooking_path(p0, entry, hp.p_start_W)) <= (
            deepest + 1e-12
        )


def _perturbed(surface, slope_error: float, shift: float):
    """``surface`` tilted by ``slope_error`` about its horizontal y_S axis through O_S and
    moved ``shift`` along its normal (positive: toward the vehicle)."""
    R = surface_frame_from_slope(surface.slope + slope_error)
    return dataclasses.replace(surface, R_WS=R, origin=surface.origin + shift * R[:, 2])


def test_the_unhooking_pass_keeps_the_belief_errors_clearance_on_a_wall():
    """wall90: on a wall with the horizontal approach n = -z_S, backing off from the end of
    the pass (overshoot beyond the anchor) to the entry (unhook_depth beyond it) adds
    exactly overshoot - unhook_depth of clearance. With the campaign's belief errors
    (the wall 1 deg off and 1 cm nearer) the reverse pass keeps more than
    mission.hooking.min_clearance from the perturbed wall at every corner (a plane's distance
    is linear along each straight leg), where the old end of the pass did not (for the
    wall leaning toward the vehicle)."""
    sc = load_scenario("wall90")
    cfg = sc.mission
    geo = LandingGeometry.from_scenario(sc)
    hp = hooking_pass(sc, geo)
    assert hp.n_W @ geo.surface.z_S == pytest.approx(-1.0, abs=1e-12)  # the premise
    entry = hp.entry(cfg.hooking.unhook_depth, cfg.hooking.overshoot)
    gain = cfg.hooking.overshoot - cfg.hooking.unhook_depth
    d_end = level_vehicle_distance(sc, geo.surface, hp.p_end_W, hp.yaw)
    d_entry = level_vehicle_distance(sc, geo.surface, entry, hp.yaw)
    assert d_entry - d_end == pytest.approx(gain, abs=1e-9)
    # the release point of the plan, on the planned takeoff end direction
    plan = plan_mission(sc, Plant(sc).start_state())
    wp = plan.waypoints
    np.testing.assert_allclose(wp.unhook_entry, entry, atol=1e-12)
    takeoff = plan.takeoff_trajectory
    d_T = geo.R_WA @ link_direction(float(takeoff.output(takeoff.duration).phi[0]), 0.0)
    release_leg = free_flight_legs(sc, geo, wp, d_T)["release"]
    assert len(release_leg) >= 3
    np.testing.assert_allclose(release_leg[-2], entry, atol=1e-12)
    old = []
    for slope_error in (math.radians(-1.0), math.radians(1.0)):
        wrong = _perturbed(geo.surface, slope_error, 0.01)
        d_path = min(level_vehicle_distance(sc, wrong, p, hp.yaw) for p in release_leg)
        d_old = level_vehicle_distance(sc, wrong, hp.p_end_W, hp.yaw)
        old.append(d_old)
        assert d_path >= cfg.hooking.min_clearance
        # a rigid translation by v changes a plane distance by v.z_S
        d_entry = level_vehicle_distance(sc, wrong, entry, hp.yaw)
        assert d_entry == pytest.approx(d_old - gain * float(hp.n_W @ wrong.z_S), abs=1e-9)
    # the wall leaning toward the vehicle: the old reverse pass's end was too close
    assert min(old) < cfg.hooking.min_clearance


def test_unhook_depth_is_validated():
    with pytest.raises(ConfigError, match=r"mission\.hooking\.unhook_depth"):
        load_scenario("wall90", ["mission.hooking.unhook_depth=0"])


def test_the_back_off_keeps_the_hooked_cable_slack():
    """A vertical pass (n = -z_W) and a release point beside the anchor, 0.5 m deeper than
    the entry: backing off straight up by the full 0.5 m would put the centre of mass
    beyond the ball (c, R); with ``reach`` the corner is the point of the vertical line
    on the sphere |p - c| = R (solved here by hand), and the segment to the entry stays
    inside (a convex ball)."""
    c, R = np.array([0.0, 0.0, 0.0]), 1.0
    n = np.array([0.0, 0.0, -1.0])
    start = np.array([0.0, 0.0, 0.9])
    entry = start + 0.1 * n  # 0.8 m above the anchor
    p0 = np.array([0.7, 0.0, 0.3])  # 0.76 m from c, 0.5 m deeper than the entry
    free = unhooking_path(p0, entry, start)
    assert np.linalg.norm(free[0] - c) > R  # the unlimited back-off leaves the ball
    corner, e, _ = unhooking_path(p0, entry, start, (c, R))
    z = math.sqrt(R * R - 0.7 * 0.7)  # on the vertical through p0, on the sphere
    np.testing.assert_allclose(corner, [0.7, 0.0, z], atol=1e-12)
    np.testing.assert_array_equal(e, entry)
    for lam in np.linspace(0.0, 1.0, 11):
        assert np.linalg.norm((1 - lam) * corner + lam * entry - c) <= R + 1e-12
    # far inside the ball the full back-off is kept: the corner at the entry's depth
    (corner, _, _) = unhooking_path(p0, entry, start, (c, 10.0))
    assert n @ corner == pytest.approx(n @ entry)
