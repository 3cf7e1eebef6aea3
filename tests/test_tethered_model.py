"""The numpy taut-link model (docs/theory.md section 4) against Newton's law (6.4)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherland import GRAVITY as g
from tetherland.errors import SingularityError
from tetherland.geometry import link_direction, link_jacobian
from tetherland.models.tethered import (
    link_dynamics,
    tension_coordinate_free,
    thrust_in_link_frame,
)


@settings(max_examples=100, deadline=None)
@given(
    st.floats(-1.5, 1.5),
    st.floats(-1.2, 1.2),
    st.floats(-3, 3),
    st.floats(-3, 3),
    st.lists(st.floats(-15, 15), min_size=3, max_size=3),
)
def test_link_model_satisfies_newton(phi, delta, phi_dot, delta_dot, thrust):
    m, l = 1.3, 0.9
    F = np.array(thrust)
    acc = link_dynamics(phi, delta, phi_dot, delta_dot, thrust_in_link_frame(F, phi, delta), m, l)
    # p'' of p = l d(q(t)) with q(t) = q + q' t + q'' t^2/2, by central differences
    qd, qdd = np.array([phi_dot, delta_dot]), np.array([acc.phi_ddot, acc.delta_ddot])

    def p(t: float) -> np.ndarray:
        q = np.array([phi, delta]) + qd * t + 0.5 * qdd * t * t
        return l * link_direction(*q)

    h = 1e-4
    p_dd = (p(h) - 2 * p(0.0) + p(-h)) / h**2
    d = link_direction(phi, delta)
    residual = m * p_dd - (F - np.array([0, 0, m * g]) - acc.tension * d)
    assert np.abs(residual).max() < 1e-4 * (1 + np.abs(F).max() + abs(acc.tension))
    # the coordinate-free tension agrees
    d_dot = link_jacobian(phi, delta, l) @ qd / l
    assert tension_coordinate_free(d, d_dot, F, m, l) == pytest.approx(acc.tension, abs=1e-9)


def test_hanging_at_rest_has_weight_as_tension():
    acc = link_dynamics(-math.pi / 2, 0.0, 0.0, 0.0, np.zeros(3), 2.0, 1.0)
    assert acc.tension == pytest.approx(2.0 * g)
    assert acc.phi_ddot == pytest.approx(0.0, abs=1e-12)


def test_singular_azimuth_is_reported():
    with pytest.raises(SingularityError, match="cos\\(delta\\)"):
        link_dynamics(0.0, math.pi / 2, 0.0, 0.0, np.zeros(3), 1.0, 1.0)
