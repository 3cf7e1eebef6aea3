"""The design search (issue 11, item 2): designs verified by the planner and the analysis,
overrides that reproduce them, the binding limit of infeasible requests, the hooking pass."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from tetherland import GRAVITY as g
from tetherland.analysis import Infeasibility, analyze
from tetherland.config import load_scenario
from tetherland.design import (
    DesignLimit,
    DesignSpace,
    feasibility_map,
    hooking_pass,
    is_robust,
    pass_clearance,
    plan_rotor_margin,
    rotor_margin,
    search_designs,
    steepest_slope,
)
from tetherland.errors import ConfigError
from tetherland.geometry import LandingGeometry
from tetherland.planning import Planner, PlanStatus

RELAXED = ("mission.hooking.overshoot=0.05", "tether.capture_radius=0.05")
EA = load_scenario("slope50").tether.effective_axial_stiffness  # the default Dyneema [N]


def _gamma(h: float, length: float, beta: float, mass: float = 1.0) -> float:
    """gamma of the landed link of the elastic cable: sin(gamma) = h/(l + s) with the
    stretch s = f_L l/EA of f_L = m g sin(beta)/cos(gamma) (6.10), by plain iteration."""
    s = 0.0
    for _ in range(100):
        gamma = math.asin(h / (length + s))
        s = mass * g * math.sin(beta) / math.cos(gamma) * length / EA
    return math.asin(h / (length + s))


"""Hooking settings with which walls are reachable (see test_wall_needs_a_short_overshoot)."""


@pytest.fixture(scope="module")
def planner() -> Planner:
    return Planner()


@pytest.fixture(scope="module")
def at_60(planner):
    return search_designs(load_scenario("slope50"), 60.0, planner=planner)


@pytest.fixture(scope="module")
def wall(planner):
    return search_designs(load_scenario("slope50", RELAXED), 90.0, planner=planner)


def test_designs_are_ranked_and_keep_the_margins(at_60):
    assert at_60.feasible and at_60.limit is None and at_60.reason == "ok"
    # robust designs first (margins kept with the belief off), then by the robust margin
    sc = load_scenario("slope50", ["surface.slope_deg=60"])
    keys = [(not is_robust(d, sc), -d.robust_rotor_margin) for d in at_60.designs]
    assert keys == sorted(keys)
    for d in at_60.designs:
        assert d.min_rotor_margin >= 0.25 - 1e-9  # the control margin, over both plans
        assert d.min_rotor_margin <= d.landed_rotor_margin + 1e-9  # the plans contain it
        assert d.min_clearance >= 0.02 - 1e-12  # mission.hooking.min_clearance
    # the analysis' best over the grid (some of it fails the hooking clearance)
    assert at_60.landed_margin >= max(d.landed_rotor_margin for d in at_60.designs) - 1e-12


def _check_design(d, base: tuple[str, ...] = ()) -> None:
    """Apply the printed overrides as `--set` would, re-plan with a fresh planner and
    re-check everything: solved, rotor bounds, tension > 0, same margins and clearance."""
    sc = load_scenario("slope50", [*base, *d.overrides])
    planner = Planner()
    plans = [planner.plan(sc, m) for m in ("landing", "takeoff")]
    v = sc.vehicle
    for plan in plans:
        assert plan.status is PlanStatus.SOLVED, plan.message
        check = plan.verification
        assert check.min_rotor_thrust >= v.f_min + v.control_margin - 1e-6
        assert check.max_rotor_thrust <= v.f_max - v.control_margin + 1e-6
        assert check.min_tension > 0.0
    assert plan_rotor_margin(sc, plans) == pytest.approx(d.min_rotor_margin, abs=1e-6)
    a = analyze(sc).tethered
    assert a.feasible
    assert rotor_margin(a.hover_rotor_thrusts, v.f_min, v.f_max) == pytest.approx(
        d.landed_rotor_margin, abs=1e-9
    )
    geo = LandingGeometry.from_scenario(sc)
    assert pass_clearance(sc, geo, hooking_pass(sc, geo)) == pytest.approx(
        d.min_clearance, abs=1e-5
    )


@pytest.mark.parametrize("rank", [0, 1])
def test_overrides_reproduce_the_design_with_the_planner_and_the_analysis(at_60, rank):
    _check_design(at_60.designs[rank])


def test_wall_designs_are_verified_by_the_planner_and_the_analysis(wall):
    """The best two designs on a vertical wall, re-planned and re-analysed."""
    for d in wall.designs[:2]:
        _check_design(d, RELAXED)


def test_overhang_design_is_verified_by_the_planner_and_the_analysis(planner):
    """93 deg (overhang93's slope): the best design, re-planned and re-analysed; its landed
    hover is the force balance f_R = m g cos(beta - gamma)/cos(gamma), sin(gamma) =
    h_att/(l + s) with the stretch s of the elastic cable."""
    over = search_designs(load_scenario("slope50", RELAXED), 93.0, planner=planner)
    assert over.feasible
    d = over.chosen
    _check_design(d, RELAXED)
    p = d.point
    beta = math.radians(93.0)
    gamma = _gamma(0.1 + p.attachment[2] - p.h_A, p.length, beta)
    a = analyze(load_scenario("slope50", [*RELAXED, *d.overrides])).tethered
    assert a.hover_thrust == pytest.approx(g * math.cos(beta - gamma) / math.cos(gamma), rel=1e-9)


def test_plan_margin_counts_the_cable_offset_torque_at_the_landed_hover(planner):
    """With the attachment 3 cm below the CoM, the rotor thrusts at the end of the landing
    plan (flatness with the offset) are the analysis' hover thrusts that cancel
    r_att x (f_L d~), and the margin is their closest approach to f_min or f_max."""
    sc = load_scenario("slope50")
    landing = planner.plan(sc, "landing")
    a = analyze(sc).tethered
    margin = plan_rotor_margin(sc, [landing])
    assert margin <= rotor_margin(a.hover_rotor_thrusts, 0.2, 6.0) + 1e-6  # plan tolerance
    from tetherland.models.flatness import FlatnessMap

    flat = FlatnessMap.from_scenario(sc, with_cable_offset=True)
    end = flat.evaluate_many(landing.trajectory.sample([landing.spec.duration]).outputs())
    np.testing.assert_allclose(end["rotor_thrusts"][0], a.hover_rotor_thrusts, atol=1e-4)
    # without an offset the margin is the planned thrusts' own
    centred = load_scenario("slope50", ["vehicle.cable_attachment=[0,0,0]"])
    plan = planner.plan(centred, "landing")
    v = plan.verification
    assert plan_rotor_margin(centred, [plan]) == pytest.approx(
        min(v.min_rotor_thrust - 0.2, 6.0 - v.max_rotor_thrust), abs=1e-6
    )


def test_wall_design_is_the_inclined_hover_force_balance(wall):
    """On a wall the landed hover needs f_R = m g tan(gamma), f_L = m g / cos(gamma),
    sin(gamma) = (h_R + r_z - h_A)/(l + s), s the stretch at f_L; with the cable at the CoM
    the four rotors share f_R."""
    assert wall.feasible
    for d in wall.designs:
        p = d.point
        gamma = _gamma(0.1 + p.attachment[2] - p.h_A, p.length, math.pi / 2)
        sc = load_scenario("slope50", [*RELAXED, *d.overrides])
        a = analyze(sc).tethered
        assert a.hover_thrust == pytest.approx(g * math.tan(gamma), rel=1e-9)
        assert a.hover_tension == pytest.approx(g / math.cos(gamma), rel=1e-9)
        if p.attachment[2] == 0.0:
            assert d.landed_rotor_margin == pytest.approx(g * math.tan(gamma) / 4 - 0.2)
        # the horizontal approach toward the wall: CoM hook_drop - overshoot from it
        assert p.approach_A == pytest.approx((-1.0, 0.0, 0.0))


def test_the_hooking_pass_decides_the_wall(planner, wall):
    """Hooking a wall along its normal, the pass ends hook_overshoot beyond the anchor: the
    frame (0.255 m ahead of the centre along x_A) keeps 2 cm only with
    hook_drop >= 0.275 + overshoot - h_A, and hook_drop + capture_radius < l. The rotor floor
    on the wall needs gamma = asin(0.1/l) with m g tan(gamma)/4 >= 0.45 N: l <= 0.554 m."""
    l_max = 0.1 / math.sin(math.atan(4 * 0.45 / g))
    assert l_max == pytest.approx(0.5541, abs=1e-4)
    # default pass (overshoot 0.12 m, capture 0.1 m): l > 0.275 + 0.12 + 0.1 = 0.495 m
    default = search_designs(load_scenario("slope50"), 90.0, planner=planner)
    assert default.feasible
    for d in default.designs:
        assert 0.495 < d.point.length <= l_max
        assert d.point.hook_drop >= 0.275 + 0.12 - d.point.h_A - 0.005
    # 5 cm overshoot and capture radius: shorter cables, more rotor margin
    assert wall.chosen.point.length < 0.495
    assert wall.chosen.min_rotor_margin > default.chosen.min_rotor_margin + 0.1
    # a 20 cm overshoot needs l > 0.575 + 0.1 m: no cable holds the wall, the pass binds
    long = search_designs(load_scenario("slope50", ["mission.hooking.overshoot=0.2"]), 90.0,
                          planner=planner)  # fmt: skip
    assert not long.feasible and long.limit is DesignLimit.HOOKING_CLEARANCE
    assert long.binding == "hooking_clearance" and long.landed_margin is not None
    assert "hooking pass" in long.reason and "\n" not in long.reason


@pytest.mark.parametrize(
    ("overrides", "slope", "attachments", "binding"),
    [
        ((), 140.0, (-0.03, 0.0, 0.025), Infeasibility.NO_INCLINED_HOVER),  # > 90 deg + gamma
        # (the rotor ceiling cannot bind for a whole grid of a vehicle that hovers: a
        # candidate with gamma < beta/2 lands with f_R < m g; rotors of 2.5 N cannot hover
        # 1 kg at all, test_hover_first.py)
        (("vehicle.f_min=1.0",), 100.0, (0.0,), Infeasibility.ROTOR_FLOOR),
        # the same vehicle with offsets allowed: the 2.5 cm offset at l = 0.2 m comes closest
        # (gamma = 38.7 deg lifts f_R/4 above the floor) but its torque takes a rotor below
        (("vehicle.f_min=1.0",), 100.0, (-0.03, 0.0, 0.025), Infeasibility.OFFSET_TORQUE),
    ],
)
def test_landed_hover_limits_bind(planner, overrides, slope, attachments, binding):
    space = DesignSpace(attachment_z=attachments)
    sc = load_scenario("slope50", list(overrides))
    r = search_designs(sc, slope, space, planner=planner)
    assert not r.feasible and r.planned == 0
    assert r.limit is DesignLimit.LANDED_HOVER and r.analysis_binding is binding
    assert r.binding == binding.value and binding.value in r.reason


def test_plan_rotor_margin_binds_when_the_start_hover_torque_is_too_large(planner):
    """A 10 N start tension on a 30 cm mast: the landed hover (1.2 N tension) is fine, but
    cancelling r_z f_L cos(phi + theta_A) in the taut start hover leaves the rotor range;
    the planner's pre-check (which bounds both hovers with the offset torque) refuses it."""
    sc = load_scenario("slope50", ["planner.start_tension=10"])
    space = DesignSpace(lengths=(1.0,), attachment_z=(0.3,), anchor_heights=(0.0,))
    r = search_designs(sc, 20.0, space, planner)
    assert r.limit is DesignLimit.PLAN and "cable-offset torque" in r.reason
    # the start hover's thrusts, by hand: f = G [f_R, tau_y] with tau_y = r_z f_L cos(phi+theta)
    landing = planner.plan(load_scenario("slope50", ["planner.start_tension=10",
                                                     "surface.slope_deg=20", "tether.length=1",
                                                     "vehicle.cable_attachment=[0,0,0.3]"]),
                           "landing")  # fmt: skip
    spec = landing.spec
    f_R, f_L = spec.hover("start")
    tau = 0.3 * f_L * math.cos(spec.phi_start + spec.theta_start)
    thrusts = spec.params.G @ np.array([f_R, tau])
    assert rotor_margin(thrusts, 0.2, 6.0) < 0.25  # beyond vehicle.control_margin
    assert f"{thrusts.max():.2f} N per rotor" in r.reason
    assert f"{tau:+.3f} N m" in r.reason


def test_invalid_slope_and_inputs_are_config_errors(planner):
    sc = load_scenario("slope50")
    for bad in (math.nan, math.inf, 181.0, -1.0):
        with pytest.raises(ConfigError, match=r"surface\.slope_deg.*\[0, 180\]"):
            search_designs(sc, bad, planner=planner)
    with pytest.raises(ConfigError, match=r"surface\.normal"):
        search_designs(load_scenario("slope50", ["surface.normal=[0.5,0,1]"]), 60.0)
    with pytest.raises(ConfigError, match="hook_drops"):
        DesignSpace(hook_drops=(0.2, 0.1))
    with pytest.raises(ConfigError, match=r"lengths.*allowed range"):
        DesignSpace(lengths=(0.0,))


def test_hooking_pass_is_the_missions_for_the_default_approach(slope50):
    """The hook hanging under the vehicle (default approach -z_W): the same pass, and the
    same clearance, as the mission plan checks before it flies."""
    from tetherland.mission.plan import plan_mission
    from tetherland.state import RigidBodyState

    start = RigidBodyState.at_rest(np.array([-1.5, 0.0, 1.2]))
    plan = plan_mission(slope50, start)
    hp = hooking_pass(slope50)
    np.testing.assert_allclose(hp.p_start_W, plan.waypoints.hook_start, atol=1e-12)
    np.testing.assert_allclose(hp.p_end_W, plan.waypoints.hook_end, atol=1e-12)
    assert hp.yaw == pytest.approx(plan.waypoints.yaw, abs=1e-15)
    geo = LandingGeometry.from_scenario(slope50)
    assert pass_clearance(slope50, geo, hp) == pytest.approx(plan.clearance.clearance_m, abs=1e-12)


def test_hook_drop_choice_is_the_best_on_the_grid(at_60):
    """The plane shortcut (clearance affine in the hook drop) picks what evaluating every
    hook drop of the grid would: the most clearance up to the target, then the shortest."""
    d = at_60.chosen
    base = load_scenario("slope50", list(d.overrides))
    geo = LandingGeometry.from_scenario(base)
    space = DesignSpace()
    capture = base.tether.capture_radius

    def score(drop: float) -> tuple[float, float]:
        sc = load_scenario("slope50", [*d.overrides, f"tether.hook_drop={drop}"])
        c = pass_clearance(sc, geo, hooking_pass(sc, geo))
        return (min(c, space.target_clearance), -drop)

    drops = [x for x in space.hook_drops if x + capture < base.tether.length]
    best = max(drops, key=score)
    assert d.point.hook_drop == pytest.approx(best)


def test_feasibility_map_cells_are_the_searches(planner, tmp_path):
    sc = load_scenario("slope50")
    fmap = feasibility_map(sc, planner=planner, slopes_deg=(60.0, 120.0), lengths=(0.5, 1.0))
    grid = fmap.grid("plan_margin")
    assert grid.shape == (2, 2)
    assert np.isnan(grid[:, 1]).all()  # 120 deg: no inclined hover with these cables
    space = replace(DesignSpace(), lengths=(1.0,), max_designs=1, shortlist=3)
    direct = search_designs(sc, 60.0, space, planner)
    assert grid[1, 0] == pytest.approx(direct.chosen.min_rotor_margin, abs=1e-9)
    cells = {(c.slope_deg, c.length): c for c in fmap.cells}
    assert cells[(120.0, 1.0)].binding == Infeasibility.NO_INCLINED_HOVER.value
    csv_rows = fmap.to_csv().strip().splitlines()
    assert len(csv_rows) == 1 + 4 and csv_rows[0].startswith("slope_deg,length_m")
    from tetherland.design.plot import save_map_figure

    png = save_map_figure(tmp_path / "map.png", fmap, direct.chosen)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size < 200_000


def test_steepest_slope_is_feasible_and_the_next_step_is_not(planner):
    """l = 1 m: the analysis bound is the closed form of the rotor floor, cable at the CoM,
    beta = gamma + acos(n f cos(gamma)/(m g)) with the stretched cable's gamma(beta)
    (sin(gamma) = 0.1/(l + s), a fixed point in beta); the verified steepest slope reaches
    it (hooking is not binding)."""
    sc = load_scenario("slope50")
    s = steepest_slope(sc, 1.0, planner=planner)
    beta = math.radians(85.0)
    for _ in range(100):
        gamma = _gamma(0.1, 1.0, beta)
        beta = gamma + math.acos(4 * 0.45 * math.cos(gamma) / g)
    closed = math.degrees(beta)
    assert s.landed_slope_deg >= closed - 1e-6
    assert s.slope_deg is not None and s.slope_deg <= s.landed_slope_deg
    space = replace(DesignSpace(), lengths=(1.0,), max_designs=1, shortlist=3)
    assert search_designs(sc, s.slope_deg, space, planner).feasible
    beyond = search_designs(sc, s.slope_deg + 0.25, space, planner)
    assert not beyond.feasible and beyond.binding == s.binding
