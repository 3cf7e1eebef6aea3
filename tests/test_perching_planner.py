"""Contact-free perching planner: re-simulation on the 3D rigid body, slopes, infeasibility,
free final time, trajectory derivatives and CSV."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tetherland import GRAVITY as g
from tetherland.config import load_scenario
from tetherland.errors import ConfigError
from tetherland.geometry import LandingGeometry
from tetherland.models.airframe import PROP_RADIUS_FRACTION
from tetherland.models.quadrotor import RotorLayout
from tetherland.models.rigid_body import RigidBodyParams, rigid_body_rhs
from tetherland.planning.perching import (
    FreeFlightTrajectory,
    PerchingError,
    PerchingPlanner,
    PerchStatus,
    free_flight_trajectory_from_csv,
    load_free_flight_trajectory,
)
from tetherland.planning.perching.model import GUARD_RADIUS_FRACTION
from tetherland.rotations import quat_to_rotmat, rotation_from_z_and_yaw, rotmat_to_quat


@pytest.fixture(scope="module")
def planner() -> PerchingPlanner:
    return PerchingPlanner()


def _scenario(slope: float, *extra: str):
    return load_scenario("slope50", [f"surface.slope_deg={slope}", *extra])


def resimulate(
    traj: FreeFlightTrajectory, scenario, drag: tuple[float, float] = (0.0, 0.0)
) -> tuple[np.ndarray, np.ndarray]:
    """Integrate the 3D rigid body (6.1)-(6.2) with DOP853 from the hover start, driven by
    the thrust and torque of the extension [f_R, tau, f_R', tau'] under the planned inputs
    U (held per interval) -- independent of the planner's RK4 and of the trajectory class.
    ``drag``: (d_x, d_y), the plant's rotor drag F = -R diag(d_x, d_y, 0) R^T v (3D, in
    F_W), at the rotor speed sqrt(f_R / (m g)) times the hover speed.

    Returns the times and the states (n, 13 + 4)."""
    params = RigidBodyParams.from_config(scenario.vehicle)
    x0_plane = traj.X[0]
    p0 = traj.meta.p_L + traj.meta.R_WA[:, [0, 2]] @ x0_plane[0:2]
    R0 = rotation_from_z_and_yaw([0.0, 0.0, 1.0], traj.meta.heading)
    x = np.concatenate((p0, np.zeros(3), rotmat_to_quat(R0), np.zeros(3), x0_plane[6:10]))

    D = np.diag([drag[0], drag[1], 0.0])
    mg = scenario.vehicle.mass * g

    def rhs(_t, z, u):
        f_R, tau, df, dtau = z[13:]
        R = quat_to_rotmat(z[6:10] / np.linalg.norm(z[6:10]))
        f_drag = -R @ D @ R.T @ z[3:6] * math.sqrt(max(f_R, 0.0) / mg)
        body = rigid_body_rhs(z[:13], f_R, np.array([0.0, tau, 0.0]), params, f_drag)
        return np.concatenate((body, [df, dtau, u[0], u[1]]))

    ts, xs = [0.0], [x]
    for k in range(len(traj.times) - 1):
        sol = solve_ivp(
            rhs, (traj.times[k], traj.times[k + 1]), xs[-1], method="DOP853",
            rtol=1e-10, atol=1e-12, args=(traj.U[k],), dense_output=True,
        )  # fmt: skip
        inner = np.linspace(traj.times[k], traj.times[k + 1], 9)[1:]
        ts += list(inner)
        xs += list(sol.sol(inner).T)
    return np.array(ts), np.array(xs)


@pytest.mark.parametrize("slope", [0.0, 20.0, 40.0, 60.0])
def test_plan_meets_landing_conditions_on_the_rigid_body(planner, slope):
    sc = _scenario(slope)
    result = planner.plan(sc)
    assert result.status is PerchStatus.SOLVED, result.message
    traj = result.require()
    # the plant's rotor drag (the published fit, on by default) is the plan's believed one
    assert traj.meta.rotor_drag == sc.controller.rotor_drag[0] == sc.aero.rotor_drag[0] > 0
    _, xs = resimulate(traj, sc, drag=tuple(sc.aero.rotor_drag))
    geo = LandingGeometry.from_scenario(sc)
    z_S = geo.surface.z_S
    end = xs[-1]
    R_end = quat_to_rotmat(end[6:10])
    p_RL = end[0:3] - geo.h_R * R_end[:, 2]
    assert np.linalg.norm(p_RL - geo.p_L) < 0.01  # condition (1) within 1 cm
    assert math.degrees(math.acos(min(1.0, R_end[:, 2] @ z_S))) < 1.0  # (2) within 1 deg
    v_planned = -sc.perching.approach_speed * z_S
    assert np.linalg.norm(end[3:6] - v_planned) < 0.05  # (3): the planned touchdown velocity
    assert np.linalg.norm(end[3:6]) < sc.perching.approach_speed + 0.05
    assert np.linalg.norm(end[10:13]) < 0.01  # omega(t_L) = 0
    # rotor thrusts within the vehicle's limits all along
    G = RotorLayout.from_config(sc.vehicle).allocation_inverse
    f = xs[:, 13:15] @ np.column_stack((G[:, 0], G[:, 2])).T
    assert f.min() >= sc.vehicle.f_min and f.max() <= sc.vehicle.f_max
    # no lander tip below the surface before t_L (3D pose, true lander positions)
    w, h = sc.vehicle.lander_half_width, sc.vehicle.h_R
    tips = np.array([[w, w, -h], [-w, w, -h], [-w, -w, -h], [w, -w, -h]])
    R = np.array([quat_to_rotmat(q) for q in xs[:-1, 6:10]])
    heights = (xs[:-1, None, 0:3] + np.einsum("nij,kj->nki", R, tips) - geo.p_L) @ z_S
    assert heights.min() > -1e-3
    assert result.solve_time_s > 0 and result.cost is not None and result.cost > 0


def test_flat_ground_is_a_vertical_descent(planner):
    result = planner.plan(_scenario(0.0))
    traj = result.require()
    s = traj.sample(np.linspace(0.0, traj.duration, 400))
    horizontal = s.p_W[:, 0, :2] - traj.meta.p_L[:2]
    assert np.abs(horizontal).max() < 1e-4
    assert np.abs(s.states[:, 2]).max() < 1e-4  # no pitch
    assert np.all(np.diff(s.p_W[:, 0, 2]) <= 1e-9)  # only going down
    # condition (4) can hold on flat ground: the touchdown acceleration is zero
    assert np.linalg.norm(s.p_W[-1, 2]) < 1e-6


def test_steep_plan_accepts_condition5_failure_but_not_limits(planner):
    """Planning works on 60 deg (where condition (5) fails after touchdown) and the plan
    stays in the planned bounds [f_min + margin, f_max - margin]."""
    sc = _scenario(60.0)
    result = planner.plan(sc)
    v = result.verification
    assert result.success and v is not None
    lo = sc.vehicle.f_min + sc.vehicle.control_margin
    hi = sc.vehicle.f_max - sc.vehicle.control_margin
    assert lo - 1e-6 <= v.min_rotor_thrust and v.max_rotor_thrust <= hi + 1e-6
    # touchdown thrust m g cos(beta): zero normal acceleration, least |a| = g sin(beta)
    assert v.touchdown_thrust == pytest.approx(g * math.cos(math.radians(60.0)), abs=1e-6)


def test_too_weak_rotors_are_reported(planner):
    result = planner.plan(_scenario(20.0, "vehicle.f_max=2.6"))
    assert result.status is PerchStatus.INFEASIBLE
    assert "cannot hover" in result.message and result.trajectory is None
    assert result.solves == 0
    with pytest.raises(PerchingError, match="infeasible"):
        result.require()


def test_solver_reports_a_maneuver_beyond_the_rotors(planner):
    """Hover is possible (2.45 N of 2.5 N per rotor), tilting to 60 deg and stopping is not."""
    result = planner.plan(_scenario(60.0, "vehicle.f_max=2.75"))
    assert result.status is PerchStatus.INFEASIBLE
    assert "cannot reach z_B = z_S" in result.message
    assert result.solves > 0 and result.trajectory is None


def test_slope_too_steep_for_the_touchdown_thrust(planner):
    result = planner.plan(_scenario(80.0))
    assert result.status is PerchStatus.INFEASIBLE
    assert "slope too steep" in result.message


def test_fixed_duration_is_used(planner):
    result = planner.plan(_scenario(20.0, "perching.duration=2.0"))
    assert result.success and result.duration == 2.0 and result.solves == 1
    assert result.trajectory.duration == pytest.approx(2.0)


def test_free_final_time_beats_its_neighbours(planner):
    sc = _scenario(40.0)
    free = planner.plan(sc)
    k = sc.perching.weights.k_time
    best = free.cost + k * free.duration
    for dT in (-0.25, 0.25):
        fixed = planner.plan(sc, duration=free.duration + dT)
        assert fixed.success
        assert best <= fixed.cost + k * fixed.duration + 1e-6


def test_zero_approach_speed_lands_at_rest(planner):
    result = planner.plan(_scenario(40.0), approach_speed=0.0)
    traj = result.require()
    end = traj.sample([traj.duration])
    assert np.linalg.norm(end.p_W[0, 1]) < 1e-3


def test_flat_outputs_are_consistent_derivatives(planner):
    traj = planner.plan(_scenario(40.0)).require()
    rng = np.random.default_rng(7)
    h = 1e-4
    for t in rng.uniform(0.05, traj.duration - 0.05, 12):
        rows = traj.sample([t - h, t, t + h]).p_W
        for k in range(3):  # p -> v -> a -> jerk by central differences (C^3 and smooth)
            np.testing.assert_allclose(
                (rows[2, k] - rows[0, k]) / (2 * h), rows[1, k + 1], atol=2e-4 * (k + 1)
            )
    s = traj.sample(np.linspace(0.0, traj.duration, 50))
    m = traj.meta.mass
    acc = s.thrust[:, None] / m * s.z_B - np.array([0.0, 0.0, g])
    # the tracker's rows carry the thrust's acceleration (the default plan has the
    # believed rotor drag: the flat outputs' acceleration is that plus D / m, D = -d s
    # (v.x_B) x_B, s = sqrt(f_R / (m g)))
    np.testing.assert_allclose(acc, s.reference_W[:, 2], atol=1e-9)
    np.testing.assert_array_equal(s.reference_W[:, :2], s.p_W[:, :2])
    d = traj.meta.rotor_drag
    assert d > 0.0
    x_B = s.R_WB[:, :, 0]
    D = -d * np.sqrt(s.thrust / (m * g)) * np.einsum("ni,ni->n", s.p_W[:, 1], x_B)
    np.testing.assert_allclose(acc + D[:, None] * x_B / m, s.p_W[:, 2], atol=1e-9)
    for t in rng.uniform(0.05, traj.duration - 0.05, 12):
        rows = traj.sample([t - h, t, t + h]).reference_W
        for k in (3, 4):  # the thrust's acceleration -> jerk -> snap (central differences)
            np.testing.assert_allclose(
                (rows[2, k - 1] - rows[0, k - 1]) / (2 * h), rows[1, k], atol=2e-3 * k
            )
    rotors = s.rotor_thrusts @ RotorLayout.from_config(_scenario(40.0).vehicle).allocation.T
    np.testing.assert_allclose(rotors[:, 0], s.thrust, atol=1e-9)
    np.testing.assert_allclose(rotors[:, 1:], s.torque_B, atol=1e-9)


def test_csv_round_trip(planner, tmp_path):
    traj = planner.plan(_scenario(20.0)).require()
    path = traj.save_csv(tmp_path / "perch.csv")
    again = load_free_flight_trajectory(path)
    times = np.random.default_rng(3).uniform(-0.1, traj.duration + 0.1, 30)
    a, b = traj.sample(times), again.sample(times)
    np.testing.assert_allclose(a.p_W, b.p_W, atol=1e-12)
    np.testing.assert_allclose(a.R_WB, b.R_WB, atol=1e-12)
    np.testing.assert_allclose(a.rotor_thrusts, b.rotor_thrusts, atol=1e-12)
    assert again.meta.scenario == traj.meta.scenario
    with pytest.raises(Exception, match="kind"):
        free_flight_trajectory_from_csv(path.read_text().replace("free-flight", "ocp"))


def test_guard_radius_matches_the_simulated_vehicle():
    assert GUARD_RADIUS_FRACTION == PROP_RADIUS_FRACTION


def test_explicit_start_point(planner):
    geo = LandingGeometry.from_scenario(_scenario(30.0))
    x_A = geo.R_WA[:, 0]
    start = geo.p_L + 0.6 * x_A + np.array([0.0, 0.0, 0.5])  # downhill and up, in the plane
    sc = _scenario(30.0, f"perching.hover_position=[{start[0]}, {start[1]}, {start[2]}]")
    traj = planner.plan(sc).require()
    np.testing.assert_allclose(traj.flat_outputs(0.0)[0], start, atol=1e-12)
    off = start + 0.1 * geo.R_WA[:, 1]
    bad = _scenario(30.0, f"perching.hover_position=[{off[0]}, {off[1]}, {off[2]}]")
    with pytest.raises(ConfigError, match="off the vertical plane"):
        planner.plan(bad)


# -- rotor drag in the plan's model (issue 23) ------------------------------------------
DRAG = 0.45
"""The published small-quadrotor fit of docs/aero.md [N s/m]."""


def test_steady_flight_through_the_drag_is_the_derived_equilibrium():
    """Level flight at V through the drag d: F z_B + D = m g z_W with D = -d s (v.x_B) x_B,
    s = sqrt(F / (m g)). Along z_B (D is across it): F = m g cos(theta); along x_B:
    m g sin(theta) = d s V cos(theta), i.e. tan(theta) = d V sqrt(cos(theta)) / (m g)."""
    from scipy.optimize import brentq

    from tetherland.planning.perching.model import NUMPY, flat_derivatives, rhs

    m, J, V = 1.1, 0.01, 1.5
    th = brentq(lambda a: math.tan(a) - DRAG * V * math.sqrt(math.cos(a)) / (m * g), 0.0, 1.0)
    F = m * g * math.cos(th)
    x = np.array([0.3, 1.0, th, V, 0.0, 0.0, F, 0.0, 0.0, 0.0])
    u = np.zeros(2)
    xdot = rhs(x, u, m, J, g, NUMPY, DRAG)
    np.testing.assert_allclose(xdot[3:6], 0.0, atol=1e-12)  # steady: no acceleration
    d = flat_derivatives(x[:, None], u[:, None], m, J, g, DRAG)
    for key in ("acc", "jerk", "snap"):
        np.testing.assert_allclose(d[key][:, 0], 0.0, atol=1e-12)
    # without the drag in the model the same state accelerates backwards by exactly D / m
    free = rhs(x, u, m, J, g, NUMPY)
    D = DRAG * math.sqrt(math.cos(th)) * V * math.cos(th)  # d s (v . x_B)
    np.testing.assert_allclose(free[3:5], D / m * np.array([math.cos(th), -math.sin(th)]),
                               rtol=1e-12)  # fmt: skip
    # a level vertical descent has no velocity in the rotor plane: no drag, hover thrust
    x_down = np.array([0.0, 1.0, 0.0, 0.0, -0.8, 0.0, m * g, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(rhs(x_down, u, m, J, g, NUMPY, DRAG)[3:5], 0.0, atol=1e-12)


def test_flat_outputs_with_drag_are_consistent_derivatives(planner):
    traj = planner.plan(_scenario(50.0, f"controller.rotor_drag=[{DRAG}, {DRAG}]")).require()
    assert traj.meta.rotor_drag == DRAG
    t = np.linspace(0.05, traj.duration - 0.05, 40)
    h = 1e-4
    mid, lo, hi = traj.sample(t), traj.sample(t - h), traj.sample(t + h)
    for k in range(1, 4):  # velocity, acceleration, jerk from the row above (central diff)
        numeric = (hi.p_W[:, k - 1] - lo.p_W[:, k - 1]) / (2 * h)
        scale = np.abs(mid.p_W[:, k]).max()
        assert np.abs(numeric - mid.p_W[:, k]).max() < 1e-4 * max(scale, 1.0)


def test_the_drag_plan_flies_the_rigid_body_through_the_plant_drag(planner):
    """The plan's thrust and attitude cancel the drag: (i) along the plan the thrust vector
    F z_B is m (a + g z_W) plus the drag d s (v.x_B) x_B, with a from the planned
    positions by finite differences; (ii) the 3D rigid body with the plant's drag law,
    driven by the planned thrust and torque, meets the landing conditions, where the
    drag-free plan misses them."""
    on = _scenario(50.0, f"controller.rotor_drag=[{DRAG}, {DRAG}]")
    traj = planner.plan(on).require()
    m = on.vehicle.mass
    h = 1e-4
    t = np.linspace(0.05, traj.duration - 0.05, 60)
    s = traj.sample(t)
    p = [traj.sample(t + k * h).p_W[:, 0] for k in (-1, 0, 1)]
    a = (p[2] - 2 * p[1] + p[0]) / h**2
    v = (p[2] - p[0]) / (2 * h)
    x_B, z_B = s.R_WB[:, :, 0], s.R_WB[:, :, 2]
    scale = np.sqrt(s.thrust / (m * g))
    drag = DRAG * scale * np.einsum("ni,ni->n", v, x_B)
    wanted = m * (a + np.array([0.0, 0.0, g])) + drag[:, None] * x_B
    np.testing.assert_allclose(s.thrust[:, None] * z_B, wanted, atol=2e-3 * m * g)
    assert np.abs(drag).max() > 0.3  # the drag the plan carries is not small
    geo = LandingGeometry.from_scenario(on)

    def landing_error(tr):
        _, xs = resimulate(tr, on, drag=(DRAG, DRAG))
        end = xs[-1]
        R_end = quat_to_rotmat(end[6:10])
        miss = np.linalg.norm(end[0:3] - geo.h_R * R_end[:, 2] - geo.p_L)
        return miss, np.linalg.norm(end[3:6] + on.perching.approach_speed * geo.surface.z_S)

    miss, speed_error = landing_error(traj)
    # the planner's model is the plant's drag law in the plane: the same motion (RK4 vs
    # DOP853), to the millimetre; the drag-free plan through the same drag misses by cm
    assert miss < 1e-3 and speed_error < 1e-2
    free = planner.plan(_scenario(50.0, f"controller.rotor_drag=[{DRAG}, {DRAG}]",
                                  "perching.model_rotor_drag=false")).require()  # fmt: skip
    assert free.meta.rotor_drag == 0.0
    miss_free, speed_free = landing_error(free)
    assert miss_free > 0.05 and speed_free > 0.2


def test_drag_option_off_gives_the_drag_free_plan_bit_for_bit(planner):
    base = planner.plan(_scenario(50.0, "controller.rotor_drag=[0, 0]")).require()
    off = planner.plan(_scenario(50.0, f"controller.rotor_drag=[{DRAG}, {DRAG}]",
                                 "perching.model_rotor_drag=false")).require()  # fmt: skip
    for name in ("times", "X", "U"):
        assert np.array_equal(getattr(base, name), getattr(off, name))
    assert base.to_csv() == off.to_csv() and "rotor_drag" not in base.to_csv()
    on = planner.plan(_scenario(50.0, f"controller.rotor_drag=[{DRAG}, {DRAG}]")).require()
    assert on.duration != base.duration  # (the drag plan is another plan)
    # the drag plan round-trips through its CSV with its coefficient
    back = free_flight_trajectory_from_csv(on.to_csv())
    assert back.meta.rotor_drag == DRAG
    t = np.linspace(0.0, on.duration, 30)
    np.testing.assert_allclose(back.sample(t).p_W, on.sample(t).p_W, atol=1e-9)
