"""The tethered planner's believed ground effect (``planner.model_ground_effect``, issue 23).

The rotor bounds hold the commands f_i / k_i, k_i the believed factor along the planned
path. Every factor expected here is the estimator's own kernel
(:class:`~tetherland.estimation.ground_effect.BelievedGroundEffect`) at the pose the
flatness map gives for the planar state, an independent path from the planner's CasADi
expression.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.estimation.ground_effect import BelievedGroundEffect
from tetherland.models.flatness import FlatnessMap, OutputDerivatives
from tetherland.planning import ManeuverSpec, build_ocp, precheck
from tetherland.planning.ocp import OcpProblem
from tetherland.planning.solvers import OcpSolver, SolverSettings
from tetherland.planning.transcription import MultipleShooting
from tetherland.rotations import rotmat_to_quat

ON = "planner.model_ground_effect=true"


def belief_factors(scenario, spec: ManeuverSpec, phi, theta) -> np.ndarray:
    """The estimator's factors (n, 4) at the poses of the planar states (phi, theta_A):
    the flatness map's link end less the attachment offset, its attitude."""
    flat = FlatnessMap.from_scenario(scenario)
    belief = BelievedGroundEffect(scenario)
    r_att = np.asarray(scenario.vehicle.cable_attachment, dtype=float)
    rows = [
        OutputDerivatives.planar([a], [b], spec.params.heading).as_vector()
        for a, b in zip(np.atleast_1d(phi), np.atleast_1d(theta), strict=True)
    ]
    nominal = flat.evaluate_many(np.array(rows), check=False)
    out = []
    for p_W, R_WB in zip(nominal["p_W"], nominal["R_WB"], strict=True):
        out.append(belief.factors_at(p_W - R_WB @ r_att, rotmat_to_quat(R_WB)).copy())
    return np.array(out)


def path_values(problem: OcpProblem, x: np.ndarray) -> np.ndarray:
    """The statement's path constraints at the state ``x`` (input, time 0, h = 0)."""
    g = problem.functions()["path"](x=x, u=np.zeros(2), t=0.0, p=problem.p_value, T=4.0, h=0.0)
    return np.asarray(g["g"], dtype=float).ravel()


@pytest.mark.parametrize("name", ["slope50", "pipe60", "wall90"])
def test_planned_factors_are_the_beliefs(name):
    """Along the straight line from the start hover to the landed hover (phi, theta_A),
    the planner's factors are the estimator's at the same poses (a plane, a pipe, a wall):
    the same disk samples, the same rays, the same bound, a different code path."""
    scenario = load_scenario(name, [ON])
    spec = ManeuverSpec.from_scenario(scenario)
    s = np.linspace(0.0, 1.0, 7)
    phi = spec.phi_start + s * (spec.phi_final - spec.phi_start)
    theta = spec.theta_start + s * (spec.theta_final - spec.theta_start)
    expected = belief_factors(scenario, spec, phi, theta)
    assert expected[-1].min() > 1.02  # the landed rotors are in ground effect
    np.testing.assert_allclose(spec.ground_effect.factors(phi, theta), expected, rtol=1e-12)


def test_rotor_bounds_hold_the_commands():
    """At a state near the surface, the statement's rotor rows are (f_i + share_i) / k_i
    (the command) with the option, f_i + share_i (the acting thrust) without it."""
    scenario = load_scenario("slope50", [ON])
    spec = ManeuverSpec.from_scenario(scenario)
    x = spec.x_final + np.r_[0.02, -0.03, 0.1, -0.2, 0.3, -0.1, 0.2, 0.05, 0.4, -0.3, 0.1, 0.2]
    tension = float(spec.model.tension(x))
    acting = spec.model.rotor_thrusts(x[:, None], np.array([tension]))[:, 0]  # f + share
    k = belief_factors(scenario, spec, x[0], x[1])[0]
    on = path_values(build_ocp(spec, "rotor"), x)
    off = path_values(build_ocp(replace(spec, ground_effect=None), "rotor"), x)
    np.testing.assert_allclose(on[5:9], acting / k, rtol=1e-12)
    np.testing.assert_allclose(off[5:9], acting, rtol=1e-12)
    assert on[0] == off[0]  # the tension row does not change


def test_option_off_is_todays_statement():
    """Off by default; off, the spec carries no ground effect, the parameters are today's
    and the rotor rows are the acting thrusts exactly; on, the statement is another one
    (its own structure key and solver) and the planner keeps both."""
    from tetherland.planning import Planner

    assert load_scenario("slope50").planner.model_ground_effect is False
    off = ManeuverSpec.from_scenario(load_scenario("slope50"))
    on = ManeuverSpec.from_scenario(load_scenario("slope50", [ON]))
    assert off.ground_effect is None
    p_off, p_on = build_ocp(off, "rotor"), build_ocp(on, "rotor")
    assert p_on.p_value.size == p_off.p_value.size + on.ground_effect.values.size
    np.testing.assert_array_equal(p_on.p_value[: p_off.p_value.size], p_off.p_value)
    assert p_on.structure_key != p_off.structure_key
    x = off.x_final
    acting = off.model.rotor_thrusts(x[:, None], off.model.tension(x[:, None]))[:, 0]
    np.testing.assert_array_equal(path_values(p_off, x)[5:9], acting)
    planner = Planner()
    a = planner.problem(load_scenario("slope50"))
    b = planner.problem(load_scenario("slope50", [ON]))
    c = planner.problem(load_scenario("slope50"))
    assert a.structure_key == c.structure_key == build_ocp(off).structure_key
    assert b.structure_key == build_ocp(on).structure_key != a.structure_key
    with pytest.raises(ValueError, match="ground-effect"):
        build_ocp(on, "wrench", template=a)


SHALLOW = ("surface.slope_deg=10", "planner.start_tension=0.3", ON)
"""A shallow slope and a slack start: the landed hover needs the most thrust of the maneuver."""


def ceiling_between(scenario) -> tuple[ManeuverSpec, float]:
    """The spec of ``scenario`` and a rotor ceiling above the start hover's thrusts and the
    landed hover's largest command f/k, below the landed hover's largest acting thrust f."""
    spec = ManeuverSpec.from_scenario(scenario)
    f = spec.hover_rotor_thrusts("final")
    k = belief_factors(scenario, spec, spec.phi_final, spec.theta_final)[0]
    below = max(spec.hover_rotor_thrusts("start").max(), (f / k).max())
    assert below < f.max()
    return spec, 0.5 * (below + f.max())


def test_precheck_bounds_the_landed_hover_commands():
    """A rotor ceiling between the landed hover's largest command f/k and its acting thrust
    f: the landed hover is infeasible without the option, feasible with it; a floor between
    its smallest command and its acting thrust: the other way round."""
    scenario = load_scenario("slope50", list(SHALLOW))
    base, ceiling = ceiling_between(scenario)
    f = base.hover_rotor_thrusts("final")
    k = belief_factors(scenario, base, base.phi_final, base.theta_final)[0]
    floor = 0.5 * (f.min() + (f / k).min())  # (f/k).min() < f_lo < f.min()
    landed = "the landed inclined hover needs"
    for option, expect_ceiling, expect_floor in ((False, True, False), (True, False, True)):
        spec = replace(base, ground_effect=base.ground_effect if option else None)
        hi = precheck(replace(spec, f_hi=ceiling))
        lo = precheck(replace(spec, f_lo=floor))
        assert any(landed in r and "f_max too low" in r for r in hi) is expect_ceiling, hi
        assert any(landed in r and "f_min too high" in r for r in lo) is expect_floor, lo
        assert len(hi) == int(expect_ceiling) and len(lo) == int(expect_floor)


def test_plan_lets_the_acting_thrust_exceed_the_ceiling_by_k():
    """A rotor ceiling below the landed hover's acting thrust but above its command: the
    plan (IPOPT, 12 nodes) lands with acting thrusts above f_hi in the last nodes, and
    every command f / k (k of the belief at the node's pose) within f_hi."""
    scenario = load_scenario("slope50", list(SHALLOW))
    base, ceiling = ceiling_between(scenario)
    spec = replace(base, f_hi=ceiling)
    assert not precheck(spec)
    solver = OcpSolver(MultipleShooting(12, "rk4", 2), SolverSettings("ipopt", tol=1e-8))
    solution = solver.solve(build_ocp(spec))
    assert solution.success
    X = spec.model.from_wrench_form(solution.X[1:-1].T).T  # the path: the open interval
    acting = spec.model.rotor_thrusts(X.T, spec.model.tension(X.T)).T
    commands = acting / belief_factors(scenario, spec, X[:, 0], X[:, 1])
    assert acting[-1].max() > spec.f_hi  # the last node: over the ceiling in acting thrust
    assert commands.max() <= spec.f_hi + 1e-6


def test_verification_holds_the_commands():
    """The re-simulation check of a plan (the spline reference, no solver) reports and
    bounds the commands f / k along it with the option, the acting thrusts without."""
    from tetherland.planning import Planner
    from tetherland.planning.checks import check_times

    results = {}
    for option in (False, True):
        scenario = load_scenario("slope50", [ON] if option else [])
        results[option] = Planner().plan(scenario, method="spline")
    traj, spec = results[True].trajectory, results[True].spec
    x = traj.states_at(check_times(traj.duration))
    acting = spec.model.rotor_thrusts(x.T, spec.model.tension(x.T)).T
    k = belief_factors(load_scenario("slope50", [ON]), spec, x[:, 0], x[:, 1])
    on, off = results[True].verification, results[False].verification
    assert on.min_rotor_thrust == pytest.approx((acting / k).min(), rel=1e-12)
    assert on.max_rotor_thrust == pytest.approx((acting / k).max(), rel=1e-12)
    assert off.min_rotor_thrust == pytest.approx(acting.min(), rel=1e-12)
    assert off.min_rotor_thrust - on.min_rotor_thrust > 0.02  # the landed rotors' k > 1.02
