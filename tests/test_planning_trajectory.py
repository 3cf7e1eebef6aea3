"""Trajectory sampling, derivatives, nominal values, spline references and CSV files."""

from __future__ import annotations

import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.errors import ConfigError
from tetherland.models.integrators import rk4
from tetherland.models.planar import ExtendedPlanarModel, offset_derivatives, parametric_rk4_step
from tetherland.planning import (
    ManeuverSpec,
    Planner,
    PlanStatus,
    PolynomialTrajectory,
    ShootingTrajectory,
    load_trajectory,
    trajectory_from_csv,
)
from tetherland.planning.plot import save_plan_figure
from tetherland.planning.shooting import HeldInputSimulator
from tetherland.planning.spline import rest_to_rest, smoothstep9
from tetherland.planning.trajectory import PlanarSimulator

SCENARIO = load_scenario("slope50")


@pytest.fixture(scope="module")
def planner() -> Planner:
    return Planner()


@pytest.fixture(scope="module")
def ocp(planner):
    return planner.plan(SCENARIO)


@pytest.fixture(scope="module")
def spline(planner):
    return planner.plan(SCENARIO, method="spline")


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(11)


def test_smoothstep_is_rest_to_rest_to_the_fourth_derivative():
    s = smoothstep9(np.array([0.0, 1.0]), order=5)
    np.testing.assert_allclose(s[0], [0.0, 1.0])
    np.testing.assert_allclose(s[1:5], 0.0, atol=1e-12)
    assert np.all(
        np.abs(s[5]) > 1.0
    )  # C^4, not C^5: the least it takes for a rest-to-rest 9th order
    tau = np.linspace(0, 1, 101)
    assert np.all(np.diff(smoothstep9(tau)[0]) >= 0)  # monotone
    y = rest_to_rest(2.0, -1.0, 4.0, np.array([-1.0, 2.0, 5.0]))
    np.testing.assert_allclose(y[0], [2.0, 0.5, -1.0])
    np.testing.assert_allclose(y[1:, [0, 2]], 0.0)


def test_spline_meets_its_boundary_conditions(spline):
    assert spline.status is PlanStatus.SOLVED
    traj, spec = spline.trajectory, spline.spec
    assert isinstance(traj, PolynomialTrajectory)
    ends = (
        (0.0, spec.phi_start, spec.theta_start, "start"),
        (traj.duration, spec.phi_final, spec.theta_final, "final"),
    )
    for t, phi, theta, which in ends:
        s = traj.sample([t])
        assert s.phi[0, 0] == pytest.approx(phi, abs=1e-12)
        assert s.theta_A[0, 0] == pytest.approx(theta, abs=1e-12)
        np.testing.assert_allclose(s.phi[0, 1:], 0.0, atol=1e-12)
        np.testing.assert_allclose(s.theta_A[0, 1:], 0.0, atol=1e-12)
        # at rest in the inclined hover: its thrusts and tension, no thrust rate
        f_R, f_L = spec.hover(which)
        assert s.f_R[0] == pytest.approx(f_R, rel=1e-12)
        assert s.tension[0] == pytest.approx(f_L, rel=1e-9)
        np.testing.assert_allclose(s.thrust_rates[0], 0.0, atol=1e-12)


def test_spline_thrusts_drive_the_model_along_the_spline(spline):
    """Planar flatness round trip: the spline's f'' integrated through (6.20) reproduces it."""
    traj = spline.trajectory
    h = 2e-3
    n = round(traj.duration / h)
    u = traj.sample(np.linspace(0.0, traj.duration, 2 * n + 1)).thrust_accels  # RK4 stage times
    x = traj.state(0.0)
    for k in range(n):
        u0, um, u1 = u[2 * k], u[2 * k + 1], u[2 * k + 2]
        k1 = traj.model.rhs(x, u0)
        k2 = traj.model.rhs(x + h / 2 * k1, um)
        k3 = traj.model.rhs(x + h / 2 * k2, um)
        k4 = traj.model.rhs(x + h * k3, u1)
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    np.testing.assert_allclose(x, traj.state(traj.duration), atol=1e-7)


def test_outputs_are_held_outside_the_maneuver(ocp):
    traj = ocp.trajectory
    before, after = traj.sample([-1.0]), traj.sample([traj.duration + 2.0])
    start, end = traj.sample([0.0]), traj.sample([traj.duration])
    assert before.phi[0, 0] == start.phi[0, 0] and after.phi[0, 0] == end.phi[0, 0]
    np.testing.assert_array_equal(after.thrusts, end.thrusts)
    for s in (before, after):
        np.testing.assert_array_equal(s.phi[0, 1:], 0.0)
        np.testing.assert_array_equal(s.thrust_rates, 0.0)
        np.testing.assert_array_equal(s.thrust_accels, 0.0)
    y = traj.output(traj.duration + 1.0)
    np.testing.assert_allclose(
        y.value, [ocp.spec.phi_final, 0.0, ocp.spec.theta_final, 0.0], atol=1e-4
    )


def test_ocp_trajectory_is_smooth_across_nodes(ocp):
    traj = ocp.trajectory
    eps = 1e-9
    nodes = traj.times[1:-1]
    left, right = traj.sample(nodes - eps), traj.sample(nodes + eps)
    # phi is C^3 and the thrusts C^1 with piecewise-constant f''
    np.testing.assert_allclose(left.phi[:, :4], right.phi[:, :4], atol=1e-6)
    np.testing.assert_allclose(left.thrusts, right.thrusts, atol=1e-6)
    np.testing.assert_allclose(left.thrust_rates, right.thrust_rates, atol=1e-6)
    assert np.abs(left.thrust_accels - right.thrust_accels).max() > 1e-3  # f'' does jump


def test_derivatives_are_consistent_with_finite_differences(ocp, spline, rng):
    for result in (ocp, spline):
        traj = result.trajectory
        h = 1e-5
        for t in rng.uniform(0.1, traj.duration - 0.1, 10):
            s = traj.sample([t - h, t, t + h])
            for q in (s.phi, s.theta_A):
                for k in range(4):
                    fd = (q[2, k] - q[0, k]) / (2 * h)
                    assert fd == pytest.approx(q[1, k + 1], rel=1e-4, abs=1e-5)
            fd = (s.thrusts[2] - s.thrusts[0]) / (2 * h)
            np.testing.assert_allclose(fd, s.thrust_rates[1], rtol=1e-5, atol=1e-6)


def test_compiled_resimulation_equals_the_casadi_chains(rng):
    """The planner's re-simulation kernels (through all intervals, and restarted at every
    node) follow the CasADi RK4 chains of the same model step by step, and its compiled
    single steps are the generic RK4 on the model's numpy right-hand side (offset
    included)."""
    params = ManeuverSpec.from_scenario(SCENARIO).params
    assert params.has_offset
    model = ExtendedPlanarModel(params)
    c = params.coefficients
    fast, reference = PlanarSimulator(), HeldInputSimulator(parametric_rk4_step())
    N, sub = 12, 7
    times = np.cumsum(np.concatenate(([0.0], rng.uniform(0.02, 0.1, N))))
    x0 = model.hover_state(0.9, 0.3) + rng.normal(scale=0.05, size=12)
    U = rng.normal(scale=5.0, size=(N, 4))
    X = x0 + rng.normal(scale=0.05, size=(N + 1, 12))
    for a, b in (
        (fast.run(c, times, x0, U, sub), reference.run(c, times, x0, U, sub)),
        (fast.restart(c, times, X, U, sub), reference.restart(c, times, X, U, sub)),
    ):
        assert a.shape == (N, sub, 12)
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12)
    x, u, h = X.T, rng.normal(scale=5.0, size=(4, N + 1)), rng.uniform(0.0, 2e-3, N + 1)
    np.testing.assert_allclose(fast.advance(c, model.rhs, x, u, h), rk4(model.rhs, x, u, h),
                               rtol=1e-13, atol=1e-13)  # fmt: skip


def test_check_samples_are_the_trajectorys_samples(ocp, rng):
    """The states the re-simulation check reads (:meth:`Trajectory.states_at`, no higher
    derivatives) are :meth:`Trajectory.sample`'s, and the closed-form tension is the
    automatic differentiation's of the exact offset model."""
    traj = ocp.trajectory
    t = np.concatenate((rng.uniform(-0.5, traj.duration + 0.5, 50), traj.times))
    s = traj.sample(t)
    np.testing.assert_array_equal(traj.states_at(t), s.states())
    ad = offset_derivatives(s.states().T, None, traj.params)["tension"]
    np.testing.assert_allclose(s.tension, ad, rtol=1e-12, atol=1e-12)


def test_nominal_values_from_flatness_agree_with_the_plan(ocp, spline):
    """The flatness map is the chapter's model (cable at the centre of mass): it agrees
    with a plan at the centre of mass to 1e-8, and with the slope50 plans (exact offset)
    to within the coupling force m |alpha x r + omega x (omega x r)| (under 0.06 N)."""
    at_com = Planner().plan(load_scenario("slope50", ["vehicle.cable_attachment=[0,0,0]"]))
    for result, tol in ((at_com, 1e-8), (ocp, 0.06), (spline, 0.06)):
        traj = result.trajectory
        t = np.linspace(0.0, traj.duration, 9)
        s = traj.sample(t)
        nominal = traj.nominal_many(t)
        np.testing.assert_allclose(nominal["rotor_thrusts"], s.thrusts, atol=tol)
        np.testing.assert_allclose(nominal["tension"], s.tension, atol=tol)
        if tol > 1e-8:
            assert np.max(np.abs(nominal["tension"] - s.tension)) > 1e-5  # the offset counts
        rate_tol = 1e-6 if tol == 1e-8 else 0.1
        np.testing.assert_allclose(nominal["f_R_dot"], s.thrust_rates.sum(axis=1), atol=rate_tol)
        np.testing.assert_allclose(nominal["roll"], 0.0, atol=1e-12)
        one = traj.nominal(1.3)
        assert one.f_R == pytest.approx(traj.sample([1.3]).f_R[0], rel=1e-10, abs=tol)
        # the link end lies on the cable sphere around the anchor
        assert np.linalg.norm(one.p_W - traj.meta.p_A) == pytest.approx(traj.meta.length)


@pytest.mark.parametrize("which", ["ocp", "spline"])
def test_csv_round_trip(which, ocp, spline, tmp_path, rng):
    traj = (ocp if which == "ocp" else spline).trajectory
    path = traj.save_csv(tmp_path / "trajectory.csv")
    head = path.read_text().splitlines()[:6]
    assert head[0] == "# tetherland trajectory"
    assert f"# kind: {traj.kind}" in head and "# scenario: slope50" in head
    assert "# maneuver: landing" in head and any(h.startswith("# version: ") for h in head)
    loaded = load_trajectory(path)
    assert type(loaded) is type(traj) and loaded.duration == traj.duration
    t = np.concatenate(([0.0, traj.duration], rng.uniform(-0.5, traj.duration + 0.5, 50)))
    a, b = traj.sample(t), loaded.sample(t)
    for name in ("phi", "theta_A", "thrusts", "thrust_rates", "thrust_accels", "tension"):
        np.testing.assert_allclose(getattr(b, name), getattr(a, name), rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(loaded.meta.R_WA, traj.meta.R_WA)
    if which == "ocp":
        assert isinstance(loaded, ShootingTrajectory)
        np.testing.assert_array_equal(loaded.U, traj.U)


def test_bad_csv_is_a_config_error(tmp_path):
    with pytest.raises(ConfigError, match="column header"):
        trajectory_from_csv("# tetherland trajectory\n# format: 1\nno,columns\n1,2\n")
    with pytest.raises(ConfigError, match="cannot read"):
        load_trajectory(tmp_path / "missing.csv")


def test_plot_is_written(ocp, tmp_path):
    path = save_plan_figure(tmp_path / "plan.png", ocp.trajectory, ocp.spec)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temp file left
