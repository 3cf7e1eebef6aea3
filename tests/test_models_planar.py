"""Planar model (6.18), its extension (6.20), and the 3D taut-tether model it reduces."""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tetherland import GRAVITY
from tetherland.analysis.statics import inclined_hover
from tetherland.config import VehicleConfig, load_scenario
from tetherland.errors import ConfigError
from tetherland.geometry import link_direction
from tetherland.models.planar import (
    NUMPY,
    ExtendedPlanarModel,
    PlanarParams,
    offset_arms,
    planar_flat_inputs,
    planar_terms,
)
from tetherland.models.quadrotor import RotorLayout
from tetherland.models.tethered import link_dynamics, tethered_rhs, thrust_in_link_frame

SCENARIO = load_scenario("slope50")
PARAMS = PlanarParams.from_scenario(load_scenario("slope50", ["vehicle.cable_attachment=[0,0,0]"]))
"""The chapter's model (cable at the centre of mass): the closed forms of (6.18)."""
MODEL = ExtendedPlanarModel(PARAMS)
M, L = PARAMS.mass, PARAMS.length


def _random_state(rng: np.random.Generator) -> np.ndarray:
    return np.concatenate(
        (
            rng.uniform(-1.2, 1.0, 2),
            rng.normal(0, 1, 2),
            rng.uniform(0.5, 4, 4),
            rng.normal(0, 2, 4),
        )
    )


def test_planar_model_equals_3d_model_at_zero_azimuth(rng):
    for _ in range(50):
        phi, theta = rng.uniform(-1.4, 1.4, 2)
        dphi, tau = rng.normal(0, 2), rng.normal(0, 0.1)
        f_R = rng.uniform(0.5, 20)
        planar = planar_terms(phi, theta, dphi, 0.0, f_R, tau, 0.0, 0.0, None, None, PARAMS, NUMPY)
        z_B = np.array([math.sin(theta), 0.0, math.cos(theta)])  # F_A, theta_A tilt towards x_A
        u_L = thrust_in_link_frame(f_R * z_B, phi, 0.0)
        full = link_dynamics(phi, 0.0, dphi, 0.0, u_L, M, L)
        assert planar["phi_ddot"] == pytest.approx(full.phi_ddot, abs=1e-12)
        assert planar["tension"] == pytest.approx(full.tension, abs=1e-12)
        assert full.delta_ddot == pytest.approx(0.0, abs=1e-12)  # the motion stays planar
        assert planar["theta_ddot"] == pytest.approx(tau / PARAMS.inertia)


def test_offset_arms_are_those_of_the_rotated_offset(rng):
    """(4.13): a = t.w, b = d.w with w = y_A x r, r = R_y(theta_A) r0 (the link direction d
    and t = dd/dphi in the plane), which the models evaluate from s = phi + theta_A alone."""
    for _ in range(20):
        phi, theta = rng.uniform(-math.pi, math.pi, 2)
        r0 = rng.normal(scale=0.05, size=2)  # (r_x, r_z)
        c_t, s_t = math.cos(theta), math.sin(theta)
        r = np.array([[c_t, 0, s_t], [0, 1, 0], [-s_t, 0, c_t]]) @ np.array([r0[0], 0, r0[1]])
        w = np.cross([0.0, 1.0, 0.0], r)
        d = np.array([math.cos(phi), 0.0, math.sin(phi)])
        t = np.array([-math.sin(phi), 0.0, math.cos(phi)])
        a, b = offset_arms(phi, theta, (r0[0], r0[1]), NUMPY)
        assert a == pytest.approx(t @ w, abs=1e-15)
        assert b == pytest.approx(d @ w, abs=1e-15)
        assert b == pytest.approx(t @ r, abs=1e-15) and a == pytest.approx(-(d @ r), abs=1e-15)


def test_inclined_hover_is_an_equilibrium():
    for phi, theta in ((-0.8, 0.87), (0.3, 0.1), (-0.2, 0.4)):
        x = MODEL.hover_state(phi, theta)
        xdot = MODEL.rhs(x, np.zeros(4))
        np.testing.assert_allclose(xdot, 0.0, atol=1e-12)
        assert MODEL.derivatives(x)["tension"] == pytest.approx(inclined_hover(phi, theta, M)[1])


def test_energy_is_conserved_with_thrust_along_the_link(rng):
    """Thrust along d does no work: the taut pendulum keeps m g z + kinetic energy."""

    def f_R(t):
        return 3.0 + 2.0 * math.sin(5.0 * t)  # any thrust, as long as it is along the link

    def energy3d(y):
        phi, delta, dphi, ddelta = y
        kin = 0.5 * M * L**2 * (math.cos(delta) ** 2 * dphi**2 + ddelta**2)
        return kin + M * GRAVITY * L * math.cos(delta) * math.sin(phi)

    def rhs3d(t, y):
        return tethered_rhs(y, f_R(t) * link_direction(y[0], y[1]), M, L)

    y0 = np.array([0.3, 0.4, 1.2, -0.8])
    sol = solve_ivp(rhs3d, (0, 3), y0, method="DOP853", rtol=1e-11, atol=1e-12, dense_output=True)
    energies = [energy3d(sol.sol(t)) for t in np.linspace(0, 3, 61)]
    assert np.ptp(energies) < 1e-8 * abs(energies[0]) + 1e-9
    assert np.ptp(sol.y[1]) > 0.1  # it really swung in 3D

    def rhs_planar(t, y):  # planar model with theta_A = pi/2 - phi: z_B = d
        phi, dphi = y
        terms = planar_terms(
            phi, math.pi / 2 - phi, dphi, -dphi, f_R(t), 0.0, 0.0, 0.0, None, None, PARAMS, NUMPY
        )
        return [dphi, terms["phi_ddot"]]

    sol = solve_ivp(rhs_planar, (0, 3), [0.2, 2.0], method="DOP853", rtol=1e-11, atol=1e-12)
    e = 0.5 * M * L**2 * sol.y[1] ** 2 + M * GRAVITY * L * np.sin(sol.y[0])
    assert np.ptp(e) < 1e-8 * abs(e[0]) + 1e-9


def test_extension_derivatives_are_time_derivatives_along_the_flow(rng):
    """phi''' and phi'''' of the model are the exact time derivatives (checked by CasADi AD)."""
    x, u = ca.SX.sym("x", 12), ca.SX.sym("u", 4)
    f = MODEL.casadi_rhs()(x, u)
    d = MODEL.casadi_derivatives()(x, u)
    names = [
        "phi_ddot",
        "phi_dddot",
        "phi_ddddot",
        "theta_ddot",
        "theta_dddot",
        "theta_ddddot",
        "tension",
    ]
    sym = dict(zip(names, d, strict=True))
    check = ca.Function(
        "check",
        [x, u],
        [
            ca.jtimes(sym["phi_ddot"], x, f) - sym["phi_dddot"],
            ca.jtimes(sym["phi_dddot"], x, f) - sym["phi_ddddot"],
            ca.jtimes(sym["theta_dddot"], x, f) - sym["theta_ddddot"],
            ca.jtimes(x[2], x, f) - sym["phi_ddot"],
        ],
    )
    for _ in range(20):
        xv, uv = _random_state(rng), rng.normal(0, 3, 4)
        for residual in check(xv, uv):
            assert abs(float(residual)) < 1e-10
        # numpy and CasADi evaluate the same formulas
        num = MODEL.derivatives(xv, uv)
        for name, value in zip(names, MODEL.casadi_derivatives()(xv, uv), strict=True):
            assert num[name] == pytest.approx(float(value), rel=1e-12, abs=1e-12)
        np.testing.assert_allclose(
            MODEL.rhs(xv, uv), np.asarray(MODEL.casadi_rhs()(xv, uv)).ravel()
        )


def test_wrench_form_and_allocation_consistency(rng):
    G, GM = PARAMS.G, PARAMS.Gamma_M
    np.testing.assert_allclose(GM @ G, np.eye(2), atol=1e-12)
    # planar-consistent thrusts make no roll and no yaw torque
    w = PARAMS.allocation @ (G @ np.array([9.0, 0.05]))
    assert w[1] == pytest.approx(0.0, abs=1e-12) and w[3] == pytest.approx(0.0, abs=1e-12)
    z = np.concatenate((rng.normal(size=4), [8.0, 0.03, 1.0, -0.2]))
    np.testing.assert_allclose(MODEL.to_wrench_form(MODEL.from_wrench_form(z)), z, atol=1e-12)


def test_planar_flatness_round_trip():
    """Inputs from planar flatness, integrated through (6.20), reproduce the outputs."""
    T = 2.0

    def outputs(t):
        phi = np.array(
            [-0.3 + 0.2 * math.sin(2 * t)]
            + [0.2 * 2**k * math.sin(2 * t + k * math.pi / 2) for k in range(1, 5)]
        )
        th = np.array(
            [0.4 + 0.1 * math.cos(3 * t)]
            + [0.1 * 3**k * math.cos(3 * t + k * math.pi / 2) for k in range(1, 5)]
        )
        return phi, th

    def flat_state(t):
        phi, th = outputs(t)
        w = planar_flat_inputs(phi, th, PARAMS)
        G = PARAMS.G
        x = np.concatenate(
            (
                [phi[0], th[0], phi[1], th[1]],
                G @ [w["f_R"], w["tau"]],
                G @ [w["f_R_dot"], w["tau_dot"]],
            )
        )
        return x, G @ np.array([w["f_R_ddot"], w["tau_ddot"]])

    x, _ = flat_state(0.0)
    h = 1e-3
    t = 0.0
    for _ in range(int(T / h)):
        k1 = MODEL.rhs(x, flat_state(t)[1])
        k2 = MODEL.rhs(x + 0.5 * h * k1, flat_state(t + 0.5 * h)[1])
        k3 = MODEL.rhs(x + 0.5 * h * k2, flat_state(t + 0.5 * h)[1])
        k4 = MODEL.rhs(x + h * k3, flat_state(t + h)[1])
        x = x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        t += h
    np.testing.assert_allclose(x, flat_state(T)[0], atol=1e-8)


def test_heading_must_keep_y_A_a_principal_axis():
    layout = RotorLayout.from_config(VehicleConfig())
    ok = PlanarParams.from_matrices(
        1.0, 1.0, [0.015, 0.015, 0.025], layout.allocation, math.radians(30)
    )
    assert ok.inertia == pytest.approx(0.015)
    with pytest.raises(ConfigError, match="principal axis"):
        PlanarParams.from_matrices(
            1.0, 1.0, [0.01, 0.02, 0.025], layout.allocation, math.radians(30)
        )
    p90 = PlanarParams.from_matrices(1.0, 1.0, [0.01, 0.02, 0.025], layout.allocation, math.pi / 2)
    assert p90.inertia == pytest.approx(0.01)  # rotating about x_B


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(7)
