"""OCP statement, multiple-shooting transcription and the two NLP solvers."""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.planning import (
    InitialGuess,
    ManeuverSpec,
    MultipleShooting,
    OcpProblem,
    OcpSolver,
    SolverSettings,
    SolveStatus,
    build_ocp,
    stagewise,
)

SOLVERS = ("fatrop", "ipopt")


def double_integrator(x_final=(1.0, 0.0), v_max=np.inf, duration=1.0) -> OcpProblem:
    """min int u^2 dt, x'' = u, x(0) = 0, x(T) = x_final, velocity <= v_max."""
    x, u, p = ca.SX.sym("x", 2), ca.SX.sym("u"), ca.SX.sym("p", 2)
    t, T, h = ca.SX.sym("t"), ca.SX.sym("T"), ca.SX.sym("h")
    return OcpProblem(
        x=x, u=u, p=p, t=t, T=T, h=h,
        ode=ca.vertcat(x[1], u), stage_cost=u**2, terminal_cost=ca.SX(0),
        path=x[1], terminal=x - p,
        duration=duration, x0=np.zeros(2), p_value=np.asarray(x_final),
        path_lb=[-np.inf], path_ub=[v_max],
        x_lb=np.full(2, -np.inf), x_ub=np.full(2, np.inf), u_lb=[-np.inf], u_ub=[np.inf],
    )  # fmt: skip


def discrete_optimum(N: int, T: float = 1.0) -> np.ndarray:
    """Least-norm piecewise-constant input of the exactly discretised double integrator."""
    hk = T / N
    mid = (np.arange(N) + 0.5) * hk
    A = np.vstack((np.full(N, hk), hk * (T - mid)))  # final velocity, final position
    return np.linalg.lstsq(A, np.array([0.0, 1.0]), rcond=None)[0]


@pytest.mark.parametrize("solver", SOLVERS)
def test_known_answer_double_integrator(solver):
    N = 20
    ocp = OcpSolver(MultipleShooting(N, "rk4", 1), SolverSettings(solver, tol=1e-9))
    sol = ocp.solve(double_integrator())
    assert sol.status is SolveStatus.SUCCESS
    np.testing.assert_allclose(sol.U[:, 0], discrete_optimum(N), atol=1e-6)
    np.testing.assert_allclose(sol.X[-1], [1.0, 0.0], atol=1e-9)
    # the continuous optimum u = 6 - 12 t, up to O(h^2)
    np.testing.assert_allclose(sol.U[:, 0], 6 - 12 * (sol.times[:-1] + 0.5 / N), atol=0.05)
    assert sol.cost == pytest.approx(np.sum(discrete_optimum(N) ** 2) / N, rel=1e-6)


@pytest.mark.parametrize("solver", SOLVERS)
def test_path_constraint_is_enforced_and_costs(solver):
    ocp = OcpSolver(MultipleShooting(40, "rk4", 1), SolverSettings(solver, tol=1e-9))
    free = ocp.solve(double_integrator())
    capped = ocp.solve(double_integrator(v_max=1.3), guess=free)
    assert free.X[:, 1].max() > 1.4  # the free optimum peaks at 1.5
    assert capped.status is SolveStatus.SUCCESS
    assert capped.X[1:-1, 1].max() <= 1.3 + 1e-6
    assert capped.cost > free.cost


def test_structure_is_cached_across_scenarios():
    ocp = OcpSolver(MultipleShooting(30, "rk4", 1), SolverSettings("ipopt"))
    problems = [
        build_ocp(ManeuverSpec.from_scenario(load_scenario("slope50", [f"surface.slope_deg={s}"])))
        for s in (30, 60)
    ]
    assert problems[0].structure_key == problems[1].structure_key
    assert not np.allclose(problems[0].p_value, problems[1].p_value)
    first = ocp.solve(problems[0])
    second = ocp.solve(problems[1])
    assert first.build_time > 0 and second.build_time == 0.0
    assert first.success and second.success
    assert first.cost != pytest.approx(second.cost)
    other_form = build_ocp(ManeuverSpec.from_scenario(load_scenario("slope50")), form="rotor")
    assert other_form.structure_key != problems[0].structure_key


def test_transcription_orders_blocks_stage_wise_for_fatrop():
    problem = double_integrator()
    tr = MultipleShooting(5, "rk4", 2).transcribe(problem)
    kinds = [kind for kind, _ in tr.layout]
    assert kinds[:4] == ["gap", "init", "gap", "path"]
    assert kinds[-1] == "terminal" and kinds.count("gap") == 5
    assert len(tr.equality) == tr.nlp["g"].numel()
    assert sum(tr.equality) == 5 * 2 + 2 + 2  # gaps, initial state, terminal state
    X, U = np.arange(12.0).reshape(6, 2), np.arange(5.0).reshape(5, 1)
    X2, U2 = tr.unpack(tr.pack(X, U))
    np.testing.assert_array_equal(X2, X)
    np.testing.assert_array_equal(U2, U)
    with pytest.raises(ValueError):
        MultipleShooting(1)


def test_wrench_and_rotor_forms_state_the_same_problem():
    """The chapter's rotor form (12 states) and the wrench form (8 states) agree."""
    spec = ManeuverSpec.from_scenario(load_scenario("slope50"))
    results = {}
    for form in ("wrench", "rotor"):
        problem = build_ocp(spec, form)
        ocp = OcpSolver(MultipleShooting(40, "rk4", 1), SolverSettings("ipopt", tol=1e-9))
        results[form] = ocp.solve(problem)
        assert results[form].success
    w, r = results["wrench"], results["rotor"]
    assert w.cost == pytest.approx(r.cost, rel=1e-6)
    np.testing.assert_allclose(w.X[:, :4], r.X[:, :4], atol=1e-5)
    np.testing.assert_allclose(w.U, r.U, atol=1e-3)  # inputs [f_R'', tau_y''] in N/s^2, N m/s^2
    np.testing.assert_allclose(r.X[:, 4:8] @ spec.params.Gamma_M.T, w.X[:, 4:6], atol=1e-6)


def test_bad_guess_shape_is_rejected():
    ocp = OcpSolver(MultipleShooting(10, "rk4", 1), SolverSettings("ipopt"))
    with pytest.raises(ValueError, match="guess shapes"):
        ocp.solve(double_integrator(), InitialGuess(X=np.zeros((5, 2)), U=np.zeros((4, 1))))


def test_problem_validation():
    with pytest.raises(ValueError, match="duration"):
        double_integrator(duration=0.0)
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u")
    with pytest.raises(ValueError, match="ode"):
        OcpProblem(
            x=x, u=u, p=ca.SX.sym("p", 0), t=ca.SX.sym("t"), T=ca.SX.sym("T"), h=ca.SX.sym("h"),
            ode=x[0], stage_cost=u**2, terminal_cost=ca.SX(0), path=ca.SX(0, 1), terminal=x,
            duration=1.0, x0=[0, 0], p_value=[], path_lb=[], path_ub=[],
            x_lb=[-1, -1], x_ub=[1, 1], u_lb=[-1], u_ub=[1],
        )  # fmt: skip


def test_with_numbers_validates_what_it_changes():
    """with_numbers checks the numbers it is given (their sizes, finiteness, the bounds
    they pair with) and keeps the statement."""
    problem = double_integrator(v_max=1.3)
    other = problem.with_numbers(x0=[0.5, 0.0], duration=2.0)
    assert other.structure_key == problem.structure_key
    np.testing.assert_array_equal(other.x0, [0.5, 0.0])
    assert other.duration == 2.0 and problem.duration == 1.0
    for numbers, match in (
        ({"x0": [0.0, np.nan]}, "NaN"),
        ({"x0": [0.0]}, "x0 must have 2"),
        ({"duration": -1.0}, "duration"),
        ({"x_lb": [2.0, 2.0], "x_ub": [1.0, 1.0]}, "x_lb > x_ub"),
        ({"u_lb": [1.0], "u_ub": [0.0]}, "u_lb > u_ub"),
        ({"path_lb": [2.0]}, "path_lb > path_ub"),
        ({"p_value": [1.0, np.inf]}, "finite"),
    ):
        with pytest.raises(ValueError, match=match):
            problem.with_numbers(**numbers)
    with pytest.raises(TypeError, match="unexpected"):
        problem.with_numbers(x=[0.0])


@pytest.mark.skipif(not stagewise.available(), reason="no C compiler")
def test_jit_compiled_solver_finds_the_same_optimum(tmp_path, monkeypatch):
    """SolverSettings.jit compiles the NLP's interval functions to C: same iterates, same
    optimum, no compiler files left in the working directory (the library goes to the
    cache directory)."""
    work, cache = tmp_path / "work", tmp_path / "cache"
    work.mkdir()
    monkeypatch.chdir(work)
    monkeypatch.setenv(stagewise.CACHE_ENV, str(cache))
    tr = MultipleShooting(20, "rk4", 1)
    settings = SolverSettings("fatrop", tol=1e-9, jit=False)
    plain = OcpSolver(tr, settings).solve(double_integrator(v_max=1.3))
    solver = OcpSolver(tr, replace(settings, jit=True))
    jit = solver.solve(double_integrator(v_max=1.3))
    assert solver.compiled and len(list(cache.iterdir())) == 1
    assert plain.success and jit.success
    assert jit.iterations == plain.iterations
    np.testing.assert_allclose(jit.U, plain.U, atol=1e-10)
    assert jit.X[1:-1, 1].max() <= 1.3 + 1e-6
    assert list(work.iterdir()) == []
