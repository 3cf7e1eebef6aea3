"""Online re-planning of the landing from a perturbed mid-trajectory state (issue 13 item 5)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tetherland.config import load_scenario
from tetherland.planning import (
    CheckScope,
    ManeuverSpec,
    Planner,
    PlanningError,
    PlanStatus,
    ReplanSettings,
    build_ocp,
    kernels,
    verify_nodes,
)
from tetherland.planning.maneuver import remainder_ocp

ELAPSED = 2.0


@pytest.fixture(scope="module")
def planner() -> Planner:
    return Planner()


@pytest.fixture(scope="module")
def landing(planner):
    result = planner.plan(load_scenario("slope50"))
    assert result.success
    return result


def perturbed(landing, t: float = ELAPSED) -> np.ndarray:
    """The planned state at ``t`` with errors: +0.01 rad in phi, -0.01 rad in theta_A,
    +-0.02 rad/s in the rates."""
    x = landing.trajectory.state(t)
    x[:4] += [0.01, -0.01, 0.02, -0.02]
    return x


def resimulate(spec, times, x0, U):
    """DOP853 through the intervals with the re-plan's inputs held (independent of RK4)."""
    model = spec.model
    x, xs, ts = np.asarray(x0, dtype=float), [], []
    for k in range(len(times) - 1):
        sol = solve_ivp(
            lambda _t, y, u=U[k]: model.rhs(y, u), (times[k], times[k + 1]), x,
            method="DOP853", rtol=1e-11, atol=1e-12, dense_output=True,
        )  # fmt: skip
        grid = np.linspace(times[k], times[k + 1], 8, endpoint=False)
        ts.append(grid)
        xs.append(sol.sol(grid).T)
        x = sol.y[:, -1]
    ts.append([times[-1]])
    xs.append(x[None, :])
    return np.concatenate(ts), np.vstack(xs)


def test_replan_from_a_perturbed_state_meets_the_final_conditions_and_bounds(planner, landing):
    x0 = perturbed(landing)
    result = planner.replan(landing, x0, ELAPSED, nodes=50)
    assert result.status is PlanStatus.SOLVED, result.message
    assert result.verification.scope is CheckScope.NODES  # what was checked is explicit
    assert result.summary()["checked"] == "nodes"
    assert result.start_time == ELAPSED and result.spec.duration == pytest.approx(2.0)
    assert len(result.solution.U) == 50 and result.iterations <= 10
    spec = result.spec
    # independent re-simulation from the perturbed state with the planned inputs
    U = planner.rotor_inputs(spec, result.solution)
    t, X = resimulate(spec, result.solution.times, x0, U)
    final = X[-1]
    assert final[0] == pytest.approx(spec.phi_final, abs=1e-4)
    assert final[1] == pytest.approx(spec.theta_final, abs=1e-4)
    assert np.all(np.abs(final[2:4]) < 1e-4) and np.all(np.abs(final[8:12]) < 1e-3)
    thrusts = X[:, 4:8]
    assert thrusts.min() >= spec.f_lo - 1e-6 and thrusts.max() <= spec.f_hi + 1e-6
    tension = spec.model.derivatives(X.T)["tension"]
    assert np.all(tension >= spec.tension_floor(t) - 1e-2)
    assert np.all(X[:, 0] >= spec.phi_surface - 1e-4)
    # the handed-out trajectory starts at the perturbed state
    np.testing.assert_allclose(result.trajectory.state(0.0), x0, atol=1e-9)
    # the dense re-simulation check agrees with the cheap node check
    full = planner.replan(
        landing, x0, ELAPSED, nodes=50, settings=ReplanSettings(check=CheckScope.RESIMULATION)
    )
    assert full.success and full.verification.scope is CheckScope.RESIMULATION


def test_replans_reuse_one_compiled_solver(planner, landing):
    first = planner.replan(landing, perturbed(landing, 1.0), 1.0)
    later = [planner.replan(landing, perturbed(landing, t), t) for t in (1.5, 2.5, 3.0)]
    assert all(r.success for r in [first, *later])
    assert all(r.build_time_s == 0.0 for r in later)  # x0, T and the bounds are numbers
    assert {r.solution.structure_key for r in later} == {landing.solution.structure_key}


def test_unperturbed_replan_on_the_same_nodes_is_the_rest_of_the_plan(planner):
    """Bellman: from its own state at node 25, the rest of the optimal plan is optimal for
    the rest of the maneuver (same 0.08 s nodes, same integrator, same cost and bounds)."""
    landing = planner.plan(load_scenario("slope50", ["planner.tolerance=1e-10"]))
    k = 25
    t_k = landing.solution.times[k]
    x_k = planner.rotor_states(landing.spec, landing.solution)[k]  # the solver's node
    tight = ReplanSettings(tol=1e-10, max_iter=100)
    rest = planner.replan(landing, x_k, t_k, nodes=25, settings=tight)
    assert rest.success, rest.message
    np.testing.assert_allclose(rest.solution.X, landing.solution.X[k:], atol=1e-8)
    np.testing.assert_allclose(rest.solution.U, landing.solution.U[k:], atol=1e-7)


def test_chained_replans_keep_the_maneuver_clock(planner, landing):
    first = planner.replan(landing, perturbed(landing, 1.0), 1.0)
    # one second later along the re-plan, with a new small error
    x = first.trajectory.state(1.0)
    x[0] -= 0.005
    second = planner.replan(first, x, 2.0)
    assert second.success, second.message
    assert second.start_time == 2.0 and second.spec.duration == pytest.approx(2.0)
    assert second.spec.phi_final == landing.spec.phi_final


def test_node_check_catches_gaps_and_thrusts_beyond_the_bounds(planner, landing):
    result = planner.replan(landing, perturbed(landing), ELAPSED)
    spec, sol = result.spec, result.solution
    X = planner.rotor_states(spec, sol)
    U = planner.rotor_inputs(spec, sol)
    ok = verify_nodes(spec, sol.times, X, U, 1)
    assert ok.ok and ok.scope is CheckScope.NODES
    broken = X.copy()
    broken[20, 0] += 1e-3  # a node off the motion
    v = verify_nodes(spec, sol.times, broken, U, 1)
    assert any("shooting gaps" in p for p in v.problems)
    steep = X.copy()
    steep[30, 8:12] += 200.0  # thrust rates whose arc leaves the bounds between the nodes
    v = verify_nodes(spec, sol.times, steep, U, 1)
    assert any("rotor thrusts" in p for p in v.problems)


def test_bad_replan_requests_are_refused(planner, landing):
    x = perturbed(landing)
    with pytest.raises(ValueError, match="elapsed must be in"):
        planner.replan(landing, x, 3.95)
    with pytest.raises(ValueError, match="12 finite numbers"):
        planner.replan(landing, x[:8], 1.0)
    spline = planner.plan(load_scenario("slope50"), method="spline")
    with pytest.raises(PlanningError, match="solved OCP plan"):
        planner.replan(spline, x, 1.0)


def test_gap_kernel_agrees_with_its_numpy_reference():
    """The compiled interval integration equals the model's numpy RK4 (random states)."""
    spec = ManeuverSpec.from_scenario(load_scenario("slope50"))
    rng = np.random.default_rng(11)
    N = 30
    X = np.tile(spec.x_start, (N + 1, 1)) + rng.normal(scale=0.3, size=(N + 1, 12))
    U = rng.normal(scale=5.0, size=(N, 4))
    h = rng.uniform(0.01, 0.1, N)
    for steps in (1, 3):
        fast = kernels.interval_ends(X, U, h, steps, spec.params.coefficients)
        plain = kernels.interval_ends_reference(spec.model, X, U, h, steps)
        np.testing.assert_allclose(fast, plain, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("form", ["wrench", "rotor"])
def test_remainder_ocp_has_the_numbers_of_the_full_statement(form):
    """The re-plan's shortcut (only x0, T and the tension ramp recomputed) states the same
    problem as building the OCP of the remaining maneuver from scratch."""
    sc = load_scenario("slope50", ["surface.slope_deg=0"])
    spec = ManeuverSpec.from_scenario(sc, "takeoff")  # landed on flat ground: no tension
    x = spec.x_start
    x[2] = 0.01  # lifting off
    rest = spec.remainder(x, 0.3)
    assert rest.start_tension < spec.min_tension  # the bound ramps from the state's tension
    assert rest.tension_floor(0.0) == pytest.approx(rest.start_tension, abs=1e-12)
    ramp = spec.tension_ramp * spec.duration  # the same absolute ramp length as the plan's
    assert rest.tension_floor(ramp) == pytest.approx(spec.min_tension)
    full = build_ocp(rest, form)
    short = remainder_ocp(build_ocp(spec, form), rest)
    assert short.structure_key == full.structure_key
    for name in ("duration", "x0", "p_value", "path_lb", "path_ub", "x_lb", "x_ub"):
        np.testing.assert_allclose(getattr(short, name), getattr(full, name), rtol=0, atol=1e-12)
