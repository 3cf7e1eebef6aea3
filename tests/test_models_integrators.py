"""The one RK4 of the project: numpy and CasADi agree, and it is 4th order."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from tetherland.models.integrators import euler, rk4, step


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20)


def pendulum(ops):
    """x = [angle, rate], u = torque: x' = [rate, -sin(angle) - 0.3 rate + u]."""

    def f(x, u):
        return ops.vstack((x[1], -ops.sin(x[0]) - 0.3 * x[1] + u[0]))

    return f


class NP:
    sin = staticmethod(np.sin)
    vstack = staticmethod(np.vstack)


class CA:
    sin = staticmethod(ca.sin)
    vstack = staticmethod(lambda items: ca.vertcat(*items))


def test_numpy_and_casadi_steps_agree(rng):
    x, u, h = ca.SX.sym("x", 2), ca.SX.sym("u", 1), ca.SX.sym("h")
    f_ca = ca.Function("rk4", [x, u, h], [rk4(pendulum(CA), x, u, h)])
    X = rng.uniform(-3.0, 3.0, (2, 40))
    U = rng.uniform(-1.0, 1.0, (1, 40))
    H = rng.uniform(0.0, 0.2, 40)
    numpy_steps = rk4(pendulum(NP), X, U, H)  # vectorised: one step length per column
    for k in range(40):
        symbolic = np.asarray(f_ca(X[:, k], U[:, k], H[k])).ravel()
        np.testing.assert_allclose(numpy_steps[:, k], symbolic, rtol=0, atol=1e-13)
        # the vectorised call equals the scalar one
        one = rk4(pendulum(NP), X[:, k : k + 1], U[:, k : k + 1], H[k])
        np.testing.assert_allclose(numpy_steps[:, k], one[:, 0], rtol=0, atol=1e-15)


def _oscillator_error(method, n: int, T: float = 2.0) -> float:
    """Global error at T of x'' = -w^2 x + c (u = c held), x(0) = [1, 0], in n steps.

    Exact: x(t) = c/w^2 + (1 - c/w^2) cos(w t)."""
    w, c = 3.0, 0.5

    def f(x, u):
        return np.array([x[1], -(w**2) * x[0] + u])

    x = np.array([1.0, 0.0])
    for _ in range(n):
        x = method(f, x, c, T / n)
    exact = c / w**2 + (1 - c / w**2) * np.cos(w * T)
    return abs(x[0] - exact)


def test_rk4_is_fourth_order():
    # halving h divides the global error by 2^4 (once h is small: w h <= 0.03)
    ratios = [_oscillator_error(rk4, n) / _oscillator_error(rk4, 2 * n) for n in (200, 400)]
    for r in ratios:
        assert r == pytest.approx(16.0, rel=0.05)
    assert ratios[1] < ratios[0]  # approaching 16 from above as h -> 0


def test_euler_is_first_order_and_step_dispatches():
    r = _oscillator_error(euler, 4000) / _oscillator_error(euler, 8000)
    assert r == pytest.approx(2.0, rel=0.05)
    f = pendulum(NP)
    x, u = np.array([[0.4], [0.1]]), np.array([[0.2]])
    np.testing.assert_array_equal(step("rk4", f, x, u, 0.1), rk4(f, x, u, 0.1))
    np.testing.assert_array_equal(step("euler", f, x, u, 0.1), euler(f, x, u, 0.1))
    with pytest.raises(ValueError, match="integrator"):
        step("midpoint", f, x, u, 0.1)  # type: ignore[arg-type]


def test_casadi_rk4_is_fourth_order_too():
    """The same function on symbols: the transcription's interval map converges at h^4."""
    x, u, h = ca.SX.sym("x", 2), ca.SX.sym("u"), ca.SX.sym("h")
    w, c = 3.0, 0.5

    def f(z, v):
        return ca.vertcat(z[1], -(w**2) * z[0] + v)

    F = ca.Function("F", [x, u, h], [rk4(f, x, u, h)])

    def error(n: int) -> float:
        z = np.array([1.0, 0.0])
        for _ in range(n):
            z = np.asarray(F(z, c, 2.0 / n)).ravel()
        return abs(z[0] - (c / w**2 + (1 - c / w**2) * np.cos(2.0 * w)))

    assert error(200) / error(400) == pytest.approx(16.0, rel=0.05)
