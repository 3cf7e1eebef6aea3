"""Compiled control kernels against their plain references (random inputs, 1e-9)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherland.config import load_scenario
from tetherland.control import FreeFlightController, HierarchicalController, kernels
from tetherland.rotations import exp_so3, rotmat_to_quat

SEEDS = st.integers(0, 2**32 - 1)


@pytest.fixture(scope="module")
def scenario():
    return load_scenario("slope50")


def _quat(rng: np.random.Generator, spread: float = 1.0) -> np.ndarray:
    return rotmat_to_quat(exp_so3(rng.normal(0, spread, 3)))


def _wrench(rng: np.random.Generator, f_max: float) -> np.ndarray:
    """Thrust from zero to beyond 4 f_max and torques from small to far beyond authority."""
    scale = 10 ** rng.uniform(-3, 0.5)
    return np.concatenate(([rng.uniform(0, 5 * f_max)], rng.normal(0, scale, 3)))


@settings(max_examples=200, deadline=None)
@given(SEEDS, st.booleans())
def test_compiled_mixer_matches_the_reference(scenario, seed, with_rates):
    mixer = FreeFlightController(scenario).mixer
    rng = np.random.default_rng(seed)
    w = _wrench(rng, mixer.layout.f_max)
    rates = rng.normal(0, 20, 4) if with_rates else None
    ref = kernels.mix_reference(w, rates, mixer.layout, mixer.rotors)
    out = np.empty(9)
    kernels.mix_into(*w, rates if with_rates else np.zeros(4), with_rates, mixer.packed, out)
    assert out[8] == ref[8]  # same saturation level
    np.testing.assert_allclose(out, ref, rtol=1e-9, atol=1e-9)


def test_mixer_inputs_cover_every_saturation_level(scenario):
    mixer = FreeFlightController(scenario).mixer
    levels = set()
    for seed in range(400):
        rng = np.random.default_rng(seed)
        out = np.empty(9)
        kernels.mix_into(*_wrench(rng, mixer.layout.f_max), np.zeros(4), False, mixer.packed, out)
        levels.add(out[8])
    assert levels == {0.0, 1.0, 2.0, 3.0}


@settings(max_examples=150, deadline=None)
@given(SEEDS, st.integers(1, 3), st.booleans())
def test_compiled_free_flight_matches_the_reference(scenario, seed, rows, integrate):
    ctrl = FreeFlightController(scenario)
    rng = np.random.default_rng(seed)
    p, v, q, w = rng.normal(0, 1, 3), rng.normal(0, 1, 3), _quat(rng), rng.normal(0, 2, 3)
    ref = rng.normal(0, 1, (rows, 3)) * np.array([1.0, 2.0, 10.0])[:rows, None]
    integral = rng.normal(0, 0.1, 3)
    dt = 2e-3 if integrate else math.nan
    yaw = rng.uniform(-math.pi, math.pi)
    i_ref = integral.copy()
    expected = kernels.free_flight_reference(p, v, q, w, ref, yaw, dt, i_ref, ctrl._par,
                                             ctrl.mixer.layout, ctrl.mixer.rotors)  # fmt: skip
    out = np.empty(kernels.FF_OUT_WIDTH)
    kernels.free_flight_into(p, v, q, w, ref, yaw, dt, integral, ctrl._par, ctrl.mixer.packed, out)
    np.testing.assert_allclose(out, expected, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(integral, i_ref, rtol=1e-12, atol=1e-15)


def _hierarchical_inputs(rng: np.random.Generator, ctrl: HierarchicalController):
    link = np.array([rng.uniform(0.2, 1.4), rng.normal(0, 0.3), rng.normal(0, 1), rng.normal(0, 1)])
    if rng.uniform() < 0.1:  # near the singularities: u_z <= 0 or cos(delta) = 0
        link[1] = math.pi / 2 * rng.choice([-1, 1]) * (1 - 1e-8 * rng.uniform())
    R_WA = ctrl.R_WA
    # attitude near the nominal one of the link, or anywhere
    q = rotmat_to_quat(R_WA @ exp_so3([0, -link[0] + math.pi / 2, 0]) @ exp_so3(
        rng.normal(0, 0.3 if rng.uniform() < 0.8 else 2.0, 3)))  # fmt: skip
    Y = rng.normal(0, 1, (rng.integers(1, 6), 4)) * 0.5
    Y[0, 0] = link[0] + rng.normal(0, 0.1)
    Y[0, 2] = rng.normal(0, 0.5) if rng.uniform() < 0.9 else math.pi / 2 - Y[0, 0]
    return link, q, rng.normal(0, 2, 3), Y, rng.normal(0, 1, 3), rng.normal(0, 3, 3)


@settings(max_examples=200, deadline=None)
@given(SEEDS, st.booleans(), st.booleans(), st.booleans())
def test_compiled_hierarchical_matches_the_reference(scenario, seed, feedforward, fresh, taut):
    ctrl = HierarchicalController(scenario)
    rng = np.random.default_rng(seed)
    link, q, w, Y, ff_w, ff_wd = _hierarchical_inputs(rng, ctrl)
    state = kernels.hierarchical_state(ctrl.mass, ctrl.g)
    if not fresh:  # an earlier update: integral, time and a regular attitude to hold
        state[0:2], state[2], state[3] = rng.normal(0, 0.05, 2), 0.998, rng.uniform(5, 20)
        state[4], state[5:14] = 1.0, exp_so3(rng.normal(0, 1, 3)).reshape(9)
    tension = rng.uniform(0, 8) if taut else 0.0
    s_ref = state.copy()
    expected = kernels.hierarchical_reference(1.0, link, q, w, Y, ff_w, ff_wd, feedforward,
                                              tension, s_ref, ctrl._par, ctrl.mixer.layout,
                                              ctrl.mixer.rotors)  # fmt: skip
    out = np.empty(kernels.HC_OUT_WIDTH)
    kernels.hierarchical_into(1.0, link, q, w, Y, ff_w, ff_wd, feedforward, tension, state,
                              ctrl._par, ctrl.mixer.packed, out)  # fmt: skip
    np.testing.assert_allclose(out, expected, rtol=1e-9, atol=1e-9, equal_nan=True)
    np.testing.assert_allclose(state, s_ref, rtol=1e-9, atol=1e-12)


def test_remainder_matches_math_remainder():
    rng = np.random.default_rng(7)
    for x in np.concatenate((rng.uniform(-20, 20, 2000), np.arange(-7, 8) * math.pi)):
        assert math.isclose(kernels.remainder(x, 2 * math.pi), math.remainder(x, 2 * math.pi),
                            abs_tol=1e-12)  # fmt: skip


@settings(max_examples=200, deadline=None)
@given(SEEDS)
def test_compiled_attitude_feedforward_matches_the_reference(seed):
    from tetherland.control.feedforward import attitude_feedforward, attitude_feedforward_fast

    rng = np.random.default_rng(seed)
    F = rng.normal(0, 10, 3) + np.array([0.0, 0.0, rng.uniform(-5, 20)])
    dF, ddF = rng.normal(0, 10 ** rng.uniform(-3, 2), (2, 3))
    yaw = rng.uniform(-math.pi, math.pi)
    fast = attitude_feedforward_fast(F, dF, ddF, yaw)
    for got, want in zip(fast, attitude_feedforward(F, dF, ddF, yaw), strict=True):
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)


def test_compiled_attitude_feedforward_reports_the_same_singularities():
    from tetherland.control.feedforward import attitude_feedforward, attitude_feedforward_fast
    from tetherland.errors import SingularityError

    zero = np.zeros(3)
    cases = [(zero, 0.3), (np.array([2.0, 0.0, 0.0]), 0.0)]  # no force; thrust along heading
    for F, yaw in cases:
        for fn in (attitude_feedforward, attitude_feedforward_fast):
            with pytest.raises(SingularityError) as err:
                fn(F, np.ones(3), np.ones(3), yaw)
            assert "undefined" in str(err.value)
