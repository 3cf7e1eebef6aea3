"""Flatness map y^b -> nominal state and input, checked against the forward models."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.errors import SingularityError
from tetherland.geometry import link_direction, theta_A_from_z_B
from tetherland.models.flatness import FlatnessMap, OutputDerivatives
from tetherland.models.planar import PlanarParams, planar_flat_inputs, planar_terms
from tetherland.models.tethered import (
    link_dynamics,
    tension_coordinate_free,
    thrust_in_link_frame,
)
from tetherland.rotations import quat_multiply, quat_to_rotmat, rotmat_to_quat

SCENARIO = load_scenario("slope50")
FLAT = FlatnessMap.from_scenario(SCENARIO)
PARAMS = dataclasses.replace(PlanarParams.from_scenario(SCENARIO), offset=(0.0, 0.0))
"""The flatness map is the chapter's model (cable at the centre of mass): compare it with
the planar model without the offset."""


def _sin_derivs(a: float, w: float, phase: float, offset: float, n: int) -> np.ndarray:
    """Value and n-1 derivatives of offset + a sin(w t + phase), as a function of t."""
    return lambda t: np.array(
        [offset * (k == 0) + a * w**k * math.sin(w * t + phase + k * math.pi / 2) for k in range(n)]
    )


PHI = _sin_derivs(0.15, 2.0, 0.3, -0.4, 5)
DELTA = _sin_derivs(0.2, 1.5, 0.0, 0.0, 5)
THETA = _sin_derivs(0.1, 2.5, 1.0, 0.5, 3)
PSI = _sin_derivs(0.3, 1.0, 0.0, 0.0, 3)


def output_at(t: float) -> OutputDerivatives:
    return OutputDerivatives(phi=PHI(t), delta=DELTA(t), theta_A=THETA(t), psi=PSI(t))


def _euler_psi(R_AB: np.ndarray) -> float:
    """psi of R_AB = R_y(theta_e) R_x(roll) R_z(psi)."""
    z = R_AB[:, 2]
    th, roll = math.atan2(z[0], z[2]), math.atan2(-z[1], math.hypot(z[0], z[2]))
    cy, sy, cr, sr = math.cos(th), math.sin(th), math.cos(roll), math.sin(roll)
    Ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    Rz = (Ry @ Rx).T @ R_AB
    return math.atan2(Rz[1, 0], Rz[0, 0])


def test_planar_outputs_match_the_planar_model():
    phi = np.array([-0.6, 0.3, -0.5, 0.8, 2.0])
    theta = np.array([0.7, -0.2, 0.4, 0.0, 0.0])
    n = FLAT.evaluate(OutputDerivatives.planar(phi, theta))
    w = planar_flat_inputs(phi, theta, PARAMS)
    assert n.f_R == pytest.approx(w["f_R"], rel=1e-12)
    assert n.f_R_dot == pytest.approx(w["f_R_dot"], rel=1e-10)
    assert n.f_R_ddot == pytest.approx(w["f_R_ddot"], rel=1e-10)
    np.testing.assert_allclose(n.tau_B, [0.0, w["tau"], 0.0], atol=1e-12)
    np.testing.assert_allclose(n.rotor_thrusts, PARAMS.G @ [w["f_R"], w["tau"]], atol=1e-12)
    assert n.roll == pytest.approx(0.0, abs=1e-12)
    t = planar_terms(
        phi[0], theta[0], phi[1], theta[1], w["f_R"], w["tau"], 0, 0, None, None, PARAMS, np
    )
    assert n.tension == pytest.approx(t["tension"], rel=1e-12)
    # world quantities: the link end on the cable sphere, thrust axis tilted by theta_A
    geo_d = FLAT.R_WA @ link_direction(phi[0], 0.0)
    np.testing.assert_allclose(n.p_W, FLAT.p_A + FLAT.length * geo_d, atol=1e-12)
    z_B_A = FLAT.R_WA.T @ n.z_B
    assert theta_A_from_z_B(z_B_A, phi[0], 0.0) == pytest.approx(theta[0], abs=1e-12)
    np.testing.assert_allclose(n.R_WB.T @ n.R_WB, np.eye(3), atol=1e-12)


def test_tension_is_the_coordinate_free_tension():
    n = FLAT.evaluate(output_at(0.7))
    d = FLAT.R_WA @ link_direction(PHI(0.7)[0], DELTA(0.7)[0])
    d_dot = n.v_W / FLAT.length
    assert n.tension == pytest.approx(
        tension_coordinate_free(d, d_dot, n.f_R * n.z_B, FLAT.mass, FLAT.length), rel=1e-10
    )


def test_flatness_round_trip_through_the_3d_model():
    """Nominal rotor thrusts integrated through the taut 3D model and the rigid-body
    rotation reproduce the output y^b(t) = [phi, delta, theta_A, psi]."""
    h, T = 1e-3, 1.5
    grid = np.arange(0.0, T + h / 4, h / 2)  # RK4 stage times
    nominal = FLAT.evaluate_many(np.array([output_at(t).as_vector() for t in grid]))
    thrusts = nominal["rotor_thrusts"]
    Gamma = FLAT.allocation
    J, Jinv = FLAT.inertia, np.linalg.inv(FLAT.inertia)
    R_WA = FLAT.R_WA

    def rhs(y, f):
        phi, delta, dphi, ddelta = y[:4]
        q, w = y[4:8] / np.linalg.norm(y[4:8]), y[8:11]
        wrench = Gamma @ f
        z_B_A = R_WA.T @ quat_to_rotmat(q)[:, 2]
        acc = link_dynamics(
            phi,
            delta,
            dphi,
            ddelta,
            thrust_in_link_frame(wrench[0] * z_B_A, phi, delta),
            FLAT.mass,
            FLAT.length,
        )
        w_dot = Jinv @ (wrench[1:] - np.cross(w, J @ w))
        q_dot = 0.5 * quat_multiply(q, np.concatenate(([0.0], w)))
        return np.concatenate(([dphi, ddelta, acc.phi_ddot, acc.delta_ddot], q_dot, w_dot))

    n0 = FLAT.evaluate(output_at(0.0))
    y = np.concatenate((PHI(0)[:2], DELTA(0)[:2]))[[0, 2, 1, 3]]
    y = np.concatenate((y, rotmat_to_quat(n0.R_WB), n0.omega_B))
    for k in range(round(T / h)):
        f0, fm, f1 = thrusts[2 * k], thrusts[2 * k + 1], thrusts[2 * k + 2]
        k1 = rhs(y, f0)
        k2 = rhs(y + 0.5 * h * k1, fm)
        k3 = rhs(y + 0.5 * h * k2, fm)
        k4 = rhs(y + h * k3, f1)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        y[4:8] /= np.linalg.norm(y[4:8])
    phi, delta = y[0], y[1]
    R_AB = R_WA.T @ quat_to_rotmat(y[4:8])
    assert phi == pytest.approx(PHI(T)[0], abs=1e-7)
    assert delta == pytest.approx(DELTA(T)[0], abs=1e-7)
    assert theta_A_from_z_B(R_AB[:, 2], phi, delta) == pytest.approx(THETA(T)[0], abs=1e-7)
    assert _euler_psi(R_AB) == pytest.approx(PSI(T)[0], abs=1e-7)
    assert abs(DELTA(T)[0]) > 0.05 and abs(PSI(T)[0]) > 0.05  # a genuinely 3D motion


def test_singular_outputs_raise():
    # a link accelerating down faster than gravity allows: no thrust towards z_L
    with pytest.raises(SingularityError, match="u_z"):
        FLAT.evaluate(OutputDerivatives.planar([-0.5, 0.0, -30.0, 0.0, 0.0], [0.3, 0.0, 0.0]))
    # thrust axis along the link: cos(phi + theta_A) = 0
    with pytest.raises(SingularityError):
        FLAT.evaluate(OutputDerivatives.planar([0.2, 0, 0, 0, 0], [math.pi / 2 - 0.2, 0, 0]))


def test_cable_offset_torque_is_compensated():
    with_offset = FlatnessMap.from_scenario(SCENARIO, with_cable_offset=True)
    y = output_at(0.4)
    a, b = FLAT.evaluate(y), with_offset.evaluate(y)
    r_att = np.asarray(SCENARIO.vehicle.cable_attachment)
    d_B = b.R_WB.T @ (FLAT.R_WA @ link_direction(y.phi[0], y.delta[0]))
    tau_L = np.cross(r_att, -b.tension * d_B)
    np.testing.assert_allclose(b.tau_B, a.tau_B - tau_L, atol=1e-12)
    assert np.linalg.norm(tau_L) > 0.01  # about 0.03 m x a few N
    assert b.f_R == pytest.approx(a.f_R)


def test_output_derivatives_pad_and_truncate():
    y = OutputDerivatives(phi=[1.0, 2.0], delta=[0.0], theta_A=[0.1, 0.2, 0.3, 0.4, 0.5], psi=[0.2])
    np.testing.assert_allclose(y.phi, [1.0, 2.0, 0, 0, 0])
    np.testing.assert_allclose(y.theta_A, [0.1, 0.2, 0.3])
    assert y.as_vector().shape == (16,)
    np.testing.assert_allclose(y.value, [1.0, 0.0, 0.1, 0.2])


# ------------------------------------------------------------------ the compiled map (issue 25)
def _samples(n: int) -> np.ndarray:
    """(n, 16) output rows along the sine outputs above."""
    return np.array([output_at(0.01 * k).as_vector() for k in range(n)])


def _same_bits(flat: FlatnessMap, Y: np.ndarray) -> bool:
    """``flat.evaluate_many``'s raw values equal the plain function's (numbers built in)."""
    from tetherland.models import flatness as module

    plain = flat.function.map(len(Y))(Y.T)
    fn = module._compiled(flat._structure) or module._parametric(flat._structure)
    fast = fn.map("m", "serial", len(Y), [1], [])(Y.T, flat.parameters)
    return all(
        np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)
        for a, b in zip(plain, fast, strict=True)
    )


@pytest.fixture
def fresh_flatness_cache(tmp_path, monkeypatch):
    """The flatness map's compiled and parametric forms built anew, into ``tmp_path``."""
    from tetherland import ccode
    from tetherland.models import flatness as module

    monkeypatch.setenv(ccode.CACHE_ENV, str(tmp_path))
    module._compiled.cache_clear()
    module._parametric.cache_clear()
    yield tmp_path
    module._compiled.cache_clear()
    module._parametric.cache_clear()


def test_the_map_with_its_numbers_as_inputs_gives_the_plain_maps_bits(fresh_flatness_cache):
    """A full inertia matrix, a cable offset, the default vehicle: compiled to C (or in
    CasADi's machine without a compiler) the same bits as the map with its numbers built
    in, and the nominal values through ``evaluate_many`` are those of ``evaluate``."""
    Y = _samples(300)
    J = np.array([[0.010, 0.001, 0.0], [0.001, 0.012, -0.0005], [0.0, -0.0005, 0.020]])
    offset = dataclasses.replace(FLAT, inertia=J, r_att_B=np.array([0.01, 0.0, -0.05]))
    for flat in (FLAT, offset):
        assert _same_bits(flat, Y)
        many = flat.evaluate_many(Y[:3])
        one = flat.evaluate(output_at(0.01))
        assert np.array_equal(many["rotor_thrusts"][1], one.rotor_thrusts)
        assert np.array_equal(many["omega_dot_B"][1], one.omega_dot_B)
    # one library per structure (where the numbers are not zero), whatever the values
    from tetherland import ccode

    built = sorted(fresh_flatness_cache.glob("flatness_*.so"))
    assert len(built) == (2 if ccode.available() else 0)
    heavier = dataclasses.replace(FLAT, mass=1.3 * FLAT.mass)
    heavier.evaluate_many(Y)
    assert sorted(fresh_flatness_cache.glob("flatness_*.so")) == built
    assert heavier.parameters[0] == pytest.approx(1.3 * FLAT.parameters[0])
    assert not np.array_equal(heavier.evaluate_many(Y)["f_R"], FLAT.evaluate_many(Y)["f_R"])


def test_without_a_compiler_the_map_is_evaluated_by_casadi_with_the_same_bits(
    fresh_flatness_cache, monkeypatch
):
    from tetherland import ccode

    Y = _samples(50)
    compiled = FLAT.evaluate_many(Y)
    from tetherland.models import flatness as module

    module._compiled.cache_clear()
    monkeypatch.setattr(ccode, "available", lambda: False)
    assert module._compiled(FLAT._structure) is None
    machine = FLAT.evaluate_many(Y)
    assert compiled.keys() == machine.keys()
    for key in compiled:
        assert np.array_equal(compiled[key], machine[key]), key


def test_a_library_that_cannot_be_built_warns_and_the_map_still_gives_the_same_bits(
    fresh_flatness_cache, monkeypatch
):
    """A cache directory that cannot be written: one warning, CasADi's machine, same bits."""
    Y = _samples(20)
    want = {k: v.copy() for k, v in FLAT.evaluate_many(Y).items()}
    from tetherland import ccode
    from tetherland.models import flatness as module

    blocker = fresh_flatness_cache / "file"
    blocker.write_text("not a directory")
    monkeypatch.setenv(ccode.CACHE_ENV, str(blocker / "cache"))
    module._compiled.cache_clear()
    if ccode.available():
        with pytest.warns(UserWarning, match="compiled flatness map unavailable"):
            got = FLAT.evaluate_many(Y)
    else:
        got = FLAT.evaluate_many(Y)
    for key in want:
        assert np.array_equal(got[key], want[key]), key
