"""The generated DFL kernel and the compiled DFL law against CasADi and the plain reference."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherland.config import load_scenario
from tetherland.control import DflController
from tetherland.control.kernels import dfl as dfl_kernels
from tetherland.control.kernels.dfl_model import dfl_function
from tetherland.control.kernels.dfl_terms import dfl_terms_into
from tetherland.rotations import exp_so3, rotmat_to_quat

SEEDS = st.integers(0, 2**32 - 1)


@pytest.fixture(scope="module")
def controller():
    return DflController(load_scenario("slope50"))


def _state_vector(rng: np.random.Generator) -> np.ndarray:
    """[phi, delta, phi', delta', theta_e, roll, psi, omega (3), f_R, f_R'] away from the
    model's singularities (cos(delta) = 0, roll = 90 deg)."""
    link = [rng.uniform(-1.5, 1.5), rng.uniform(-1.2, 1.2), *rng.normal(0, 1, 2)]
    attitude = [rng.uniform(-1.5, 1.5), rng.uniform(-1.2, 1.2), rng.uniform(-3, 3)]
    thrust = [rng.uniform(1, 25), rng.normal(0, 10)]
    return np.array([*link, *attitude, *rng.normal(0, 2, 3), *thrust])


@settings(max_examples=100, deadline=None)
@given(SEEDS)
def test_generated_terms_match_the_casadi_expression(seed):
    rng = np.random.default_rng(seed)
    x = _state_vector(rng)
    p = np.array([rng.uniform(0.3, 5), rng.uniform(0.3, 3), *rng.uniform(0.002, 0.1, 3),
                  rng.uniform(9, 10)])  # fmt: skip
    expected = np.asarray(dfl_function()(x, p)).ravel()
    out = np.empty(32)
    dfl_terms_into(x, p, out)
    np.testing.assert_allclose(out, expected, rtol=1e-9, atol=1e-9 * np.abs(expected).max())
    # the first rows are the outputs themselves: phi, phi', ..., delta, ..., psi, psi'
    assert out[0] == x[0] and out[1] == x[2] and out[4] == x[1] and out[10] == x[6]


@settings(max_examples=150, deadline=None)
@given(SEEDS, st.booleans(), st.booleans())
def test_compiled_dfl_matches_the_reference(controller, seed, first, taut):
    rng = np.random.default_rng(seed)
    x = _state_vector(rng)
    link = x[0:4]
    R_AB = exp_so3([0.0, x[4], 0.0]) @ exp_so3([x[5], 0.0, 0.0]) @ exp_so3([0.0, 0.0, x[6]])
    if rng.uniform() < 0.1:  # roll = 90 deg: A is singular
        R_AB = exp_so3([0.0, x[4], 0.0]) @ exp_so3([math.pi / 2, 0.0, 0.0])
    q = rotmat_to_quat(controller.R_WA @ R_AB)
    Y = np.vstack((x[[0, 1, 4, 6]] + rng.normal(0, 0.1, 4), rng.normal(0, 1, (4, 4))))
    state = dfl_kernels.dfl_state()
    state[dfl_kernels.STATE_THRUST], state[dfl_kernels.STATE_THRUST_RATE] = x[10], x[11]
    if not first:  # an earlier update: its time, input and integrals
        state[dfl_kernels.STATE_T_LAST] = 0.998
        state[dfl_kernels.STATE_U] = rng.normal(0, 1, 4)
        state[dfl_kernels.STATE_INTEGRAL] = rng.normal(0, 0.1, 4)
    tension = rng.uniform(0, 8) if taut else 0.0
    s_ref = state.copy()
    mixer = controller.mixer
    expected = dfl_kernels.dfl_reference(1.0, link, q, x[7:10], Y, tension, s_ref,
                                     controller._par, mixer.layout, mixer.rotors)  # fmt: skip
    out = np.empty(dfl_kernels.OUT_WIDTH)
    dfl_kernels.dfl_into(
        1.0, link, q, x[7:10], Y, tension, state, controller._par, mixer.packed, out
    )
    ratio = dfl_kernels.OUT_RATIO
    np.testing.assert_allclose(out[ratio], expected[ratio], rtol=1e-9, atol=1e-12)
    assert out[dfl_kernels.OUT_SINGULAR] == expected[dfl_kernels.OUT_SINGULAR]
    np.testing.assert_allclose(out, expected, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(state, s_ref, rtol=1e-9, atol=1e-9)
