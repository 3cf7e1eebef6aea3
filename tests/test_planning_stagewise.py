"""The NLP assembled from compiled interval functions (:mod:`tetherland.planning.stagewise`)
against CasADi's own differentiation of the flat NLP, and the plans it gives against the
plain statement's."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.models.planar import parametric_rk4_step
from tetherland.planning import ManeuverSpec, Planner, build_ocp, stagewise
from tetherland.planning.ocp import OcpProblem
from tetherland.planning.planner import trajectory_meta
from tetherland.planning.shooting import HeldInputSimulator
from tetherland.planning.solvers import OcpSolver, SolverSettings
from tetherland.planning.transcription import MultipleShooting
from tetherland.planning.verify import verify

needs_compiler = pytest.mark.skipif(not stagewise.available(), reason="no C compiler")


def _landing_problem(form: str = "wrench", extra: tuple[str, ...] = ()):
    return build_ocp(ManeuverSpec.from_scenario(load_scenario("slope50", list(extra))), form)


def _double_integrator(v_max: float | None = None):
    """min int u^2 from rest at 0 to rest at 1 (no path constraint, or the one row
    v <= v_max [m/s])."""
    x, u = ca.SX.sym("x", 2), ca.SX.sym("u")
    path, bound = (ca.SX(0, 1), []) if v_max is None else (x[1], [v_max])
    return OcpProblem(
        x=x, u=u, p=ca.SX.sym("p", 0), t=ca.SX.sym("t"), T=ca.SX.sym("T"), h=ca.SX.sym("h"),
        ode=ca.vertcat(x[1], u), stage_cost=u**2, terminal_cost=ca.SX(0), path=path,
        terminal=x - ca.DM([1, 0]), duration=1.0, x0=[0, 0], p_value=[],
        path_lb=[-v for v in bound], path_ub=bound, x_lb=[-5, -5], x_ub=[5, 5], u_lb=[-50],
        u_ub=[50],
    )  # fmt: skip


@pytest.mark.parametrize(
    ("problem", "steps"),
    [
        pytest.param(_landing_problem, 2, id="landing-wrench"),
        pytest.param(lambda: _landing_problem("rotor"), 1, id="landing-rotor"),
        pytest.param(_double_integrator, 3, id="no-path"),
        pytest.param(lambda: _double_integrator(1.3), 2, id="one-path-row"),
    ],
)
def test_stagewise_functions_equal_casadis_own_derivatives(problem, steps):
    """f, g, grad f, the constraint Jacobian, the Lagrangian's gradient and Hessian and the
    multipliers' pass, at random points and multipliers, equal those CasADi derives from
    the flat NLP (the same functions fatrop would call)."""
    rng = np.random.default_rng(3)
    prob = problem()
    tr = MultipleShooting(6, "rk4", steps).transcribe(prob)
    fast = stagewise.functions(tr)
    oracle = ca.Function("nlp", [tr.nlp["x"], tr.nlp["p"]], [tr.nlp["f"], tr.nlp["g"]],
                         ["x", "p"], ["f", "g"])  # fmt: skip
    gamma = {"gamma": ["f", "g"]}
    reference = {
        "nlp_f": oracle.factory("f", ["x", "p"], ["f"]),
        "nlp_g": oracle.factory("g", ["x", "p"], ["g"]),
        "nlp_grad_f": oracle.factory("gf", ["x", "p"], ["grad:f:x"]),
        "nlp_jac_g": oracle.factory("jg", ["x", "p"], ["g", "jac:g:x"]),
        "nlp_hess_l": oracle.factory(
            "hl", ["x", "p", "lam:f", "lam:g"], ["grad:gamma:x", "hess:gamma:x:x"], gamma
        ),
        "nlp_grad": oracle.factory(
            "gr", ["x", "p", "lam:f", "lam:g"], ["f", "g", "grad:gamma:x", "grad:gamma:p"], gamma
        ),
    }
    assert set(fast) == {"nlp", *reference}
    n_g = len(tr.equality)
    for _ in range(3):
        X = np.tile(prob.x0, (7, 1)) + rng.normal(scale=0.2, size=(7, tr.nx))
        w = tr.pack(X, rng.normal(scale=3.0, size=(6, tr.nu)))
        P = tr.parameters(prob) * rng.uniform(0.9, 1.1, tr.nlp["p"].numel())
        lam = [rng.uniform(0.1, 2.0), rng.normal(size=n_g)]
        for name, ref in reference.items():
            args = [w, P, *lam] if ref.n_in() == 4 else [w, P]
            want, got = ref.call(args), fast[name].call(args)
            for a, b in zip(want, got, strict=True):
                assert a.shape == b.shape
                a, b = np.array(ca.densify(a)), np.array(ca.densify(b))
                np.testing.assert_allclose(b, a, rtol=1e-12, atol=1e-12 * max(1.0, abs(a).max()))
    # the Jacobian has CasADi's structural nonzeros (fatrop detects the same stages), the
    # Hessian's dense blocks hold all of CasADi's
    jac = fast["nlp_jac_g"].sparsity_out(1)
    assert jac.is_equal(reference["nlp_jac_g"].sparsity_out(1))
    hess = fast["nlp_hess_l"].sparsity_out(1)
    assert hess.is_symmetric()
    assert (reference["nlp_hess_l"].sparsity_out(1) + hess).nnz() == hess.nnz()


@needs_compiler
def test_library_is_compiled_once_and_found_in_the_cache(tmp_path, monkeypatch):
    monkeypatch.setenv(stagewise.CACHE_ENV, str(tmp_path))
    tr = MultipleShooting(5, "rk4", 1).transcribe(_double_integrator())
    path = stagewise.library(tr)
    assert path.parent == tmp_path and path.suffix == ".so"
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no source or temporary left
    stamp = path.stat().st_mtime_ns
    assert stagewise.library(tr) == path and path.stat().st_mtime_ns == stamp
    other = stagewise.library(MultipleShooting(6, "rk4", 1).transcribe(_double_integrator()))
    assert other != path


@needs_compiler
@pytest.mark.parametrize("extra", [(), ("surface.slope_deg=70",)], ids=["slope50", "slope70"])
def test_compiled_fatrop_takes_the_plain_statements_iterates(extra):
    """fatrop on the compiled interval functions and on CasADi's flat functions: the same
    iterations and the same optimum to rounding (the evaluation changes, not the NLP)."""
    sc = load_scenario("slope50", list(extra))
    spec = ManeuverSpec.from_scenario(sc)
    problem = build_ocp(spec)
    guess = Planner().initial_guess(trajectory_meta(sc, spec), spec, 50)
    solutions = {}
    for jit in (False, True):
        settings = SolverSettings("fatrop", 1e-6, 500, 1e-2, jit=jit)
        solver = OcpSolver(MultipleShooting(50, "rk4", 1), settings)
        assert solver.compiled is jit
        solutions[jit] = solver.solve(problem, guess)
        assert solutions[jit].success
    plain, compiled = solutions[False], solutions[True]
    assert compiled.iterations == plain.iterations
    np.testing.assert_allclose(compiled.X, plain.X, rtol=0, atol=1e-9 * np.abs(plain.X).max())
    np.testing.assert_allclose(compiled.U, plain.U, rtol=0, atol=1e-9 * np.abs(plain.U).max())
    assert compiled.cost == pytest.approx(plain.cost, rel=1e-12)


@needs_compiler
def test_plan_equals_the_plan_of_casadis_functions_and_chains(monkeypatch):
    """The landing plan as the planner now makes it (compiled NLP functions, compiled
    re-simulation) against the same plan with CasADi's own NLP functions and the CasADi
    RK4 chains for the re-simulation (the evaluation before this change): the same
    iterations, nodes, dense trajectory and check to rounding."""
    sc = load_scenario("slope50")
    fast = Planner()
    plan = fast.plan(sc)
    monkeypatch.setattr(stagewise, "available", lambda: False)
    reference = Planner()
    reference.simulator = HeldInputSimulator(parametric_rk4_step())  # type: ignore[assignment]
    before = reference.plan(sc)
    assert plan.success and before.success
    assert plan.iterations == before.iterations
    for a, b in ((plan.solution.X, before.solution.X), (plan.solution.U, before.solution.U)):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9 * np.abs(b).max())
    t = np.linspace(0.0, plan.spec.duration, 801)
    np.testing.assert_allclose(plan.trajectory.states_at(t), before.trajectory.states_at(t),
                               rtol=1e-9, atol=1e-9)  # fmt: skip
    v, w = plan.verification, before.verification
    assert v.ok and w.ok
    for name in ("min_tension", "tension_margin", "min_rotor_thrust", "max_rotor_thrust",
                 "surface_margin"):  # fmt: skip
        assert getattr(v, name) == pytest.approx(getattr(w, name), abs=1e-9)


def test_landing_plan_equals_an_ipopt_solve_of_the_plain_statement():
    """The planner's plan (fatrop, compiled functions, compiled re-simulation check) and
    IPOPT on CasADi's own NLP functions reach the same optimum to the solver tolerance;
    both pass the same dense check."""
    sc = load_scenario("slope50")
    planner = Planner()
    plan = planner.plan(sc)
    reference = planner.plan(sc, solver="ipopt")
    assert plan.success and reference.success
    assert plan.solver == "fatrop" and reference.solver == "ipopt"
    a, b = plan.solution, reference.solution
    assert a.cost == pytest.approx(b.cost, rel=1e-6)
    np.testing.assert_allclose(a.X[:, :4], b.X[:, :4], atol=1e-5)  # rad, rad/s
    np.testing.assert_allclose(a.X[:, 4:], b.X[:, 4:], atol=1e-4)  # N, N m, N/s, N m/s
    np.testing.assert_allclose(a.U, b.U, atol=1e-3 * np.abs(b.U).max())
    again = verify(reference.trajectory, reference.spec)
    assert again.ok
    assert plan.verification.min_tension == pytest.approx(again.min_tension, abs=1e-4)


def test_an_unwritable_cache_falls_back_to_casadis_functions(tmp_path, monkeypatch):
    """A cache directory that cannot be created (here: below a file) costs a warning, not
    the plan."""
    blocker = tmp_path / "file"
    blocker.write_text("")
    monkeypatch.setenv(stagewise.CACHE_ENV, str(blocker / "cache"))
    solver = OcpSolver(MultipleShooting(7, "rk4", 1), SolverSettings("fatrop"))
    with pytest.warns(UserWarning, match="compiled NLP functions unavailable"):
        sol = solver.solve(_double_integrator())
    assert sol.success
    np.testing.assert_allclose(sol.X[-1], [1.0, 0.0], atol=1e-8)


def test_without_the_compiler_the_solver_evaluates_casadis_functions(monkeypatch):
    monkeypatch.setattr(stagewise, "available", lambda: False)
    solver = OcpSolver(MultipleShooting(20, "rk4", 1), SolverSettings("fatrop"))
    assert not solver.compiled
    sol = solver.solve(_double_integrator())
    assert sol.success
    # the optimum of min int u^2 from rest to rest: x = 3 t^2 - 2 t^3 (cubic), u = 6 - 12 t
    t = sol.times
    np.testing.assert_allclose(sol.X[:, 0], 3 * t**2 - 2 * t**3, atol=1e-3)
