"""Compiled control kernels against their plain references (random inputs, 1e-9)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherland.config import load_scenario
from tetherland.control import FreeFlightController, HierarchicalController
from tetherland.control.kernels import (
    dfl,
    dfl_model,
    free_flight,
    hierarchical,
    mixer,
    so3,
    tracker,
)
from tetherland.control.kernels.packing import Fields
from tetherland.control.tracking import FreeFlightTracker
from tetherland.geometry import link_frame
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
    m = FreeFlightController(scenario).mixer
    rng = np.random.default_rng(seed)
    w = _wrench(rng, m.layout.f_max)
    rates = rng.normal(0, 20, 4) if with_rates else None
    ref = mixer.mix_reference(w, rates, m.layout, m.rotors)
    out = np.empty(mixer.OUT_WIDTH)
    mixer.mix_into(*w, rates if with_rates else np.zeros(4), with_rates, m.packed, out)
    assert out[mixer.OUT_SATURATION] == ref[mixer.OUT_SATURATION]  # same saturation level
    np.testing.assert_allclose(out, ref, rtol=1e-9, atol=1e-9)


def test_mixer_inputs_cover_every_saturation_level(scenario):
    m = FreeFlightController(scenario).mixer
    levels = set()
    for seed in range(400):
        rng = np.random.default_rng(seed)
        out = np.empty(mixer.OUT_WIDTH)
        mixer.mix_into(*_wrench(rng, m.layout.f_max), np.zeros(4), False, m.packed, out)
        levels.add(out[mixer.OUT_SATURATION])
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
    expected = free_flight.free_flight_reference(p, v, q, w, ref, yaw, dt, i_ref, ctrl._par,
                                             ctrl.mixer.layout, ctrl.mixer.rotors)  # fmt: skip
    out = np.empty(free_flight.OUT_WIDTH)
    free_flight.free_flight_into(p, v, q, w, ref, yaw, dt, integral, ctrl._par,
                                 ctrl.mixer.packed, out)  # fmt: skip
    np.testing.assert_allclose(out, expected, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(integral, i_ref, rtol=1e-12, atol=1e-15)


@settings(max_examples=150, deadline=None)
@given(SEEDS, st.integers(1, 5), st.booleans(), st.booleans())
def test_compiled_tracker_matches_the_reference(scenario, seed, rows, lag, at_rest):
    """Three ticks of the contact-free tracker (integral, feed-forward rates, lag
    compensation across ticks 2 ms, 2 ms and 9 ms apart, the last beyond the lag window),
    compiled against plain: the same out, integral and state after every tick, to 1e-12
    (relative; rotor speeds are hundreds of rad/s)."""
    ctrl = FreeFlightTracker(scenario, lag_compensation=lag)
    layout, rotors = ctrl.mixer.layout, ctrl.mixer.rotors
    rng = np.random.default_rng(seed)
    integral, state = rng.normal(0, 0.1, 3), tracker.tracker_state()
    i_ref, s_ref = integral.copy(), state.copy()
    ref = rng.normal(0, 1, (rows, 3)) * np.array([1.0, 2.0, 5.0, 20.0, 100.0])[:rows, None]
    if at_rest and rows > 1:
        ref[1] *= 0.04 / np.linalg.norm(ref[1])  # below the hold speed: the integral runs
    yaw = rng.uniform(-math.pi, math.pi)
    for t in (1.0, 1.002, 1.004, 1.013):
        p, v, q, w = rng.normal(0, 1, 3), rng.normal(0, 1, 3), _quat(rng), rng.normal(0, 2, 3)
        ref = ref + rng.normal(0, 0.01, ref.shape)
        expected = tracker.tracker_reference(t, p, v, q, w, ref, yaw, i_ref, s_ref, ctrl._par,
                                             layout, rotors)  # fmt: skip
        out = np.empty(tracker.OUT_WIDTH)
        tracker.tracker_into(t, p, v, q, w, ref, yaw, integral, state, ctrl._par,
                             ctrl.mixer.packed, out)  # fmt: skip
        np.testing.assert_allclose(out, expected, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(integral, i_ref, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(state, s_ref, rtol=1e-12, atol=1e-12, equal_nan=True)


def test_compiled_tracker_reports_the_singularities_of_the_reference(scenario):
    """Zero nominal force and its thrust axis along the heading (the feed-forward's
    singularities; F_d itself cannot turn horizontal under the tilt limit): the same
    status from both; a hover reference is regular."""
    ctrl = FreeFlightTracker(scenario)
    g = ctrl.position.g
    q, zero = np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3)
    heading = np.array([[0, 0, 0], [0, 0, 0], [g, 0, -g], [0, 0, 1], [0, 0, 0.0]])
    cases = [
        (np.array([[0, 0, 0], [0, 0, 0], [0, 0, -g], [0, 0, 1.0]]), 2.0),  # F_n = 0
        (heading, 3.0),  # F_n along x_C
        (np.zeros((1, 3)), 0.0),  # hover
    ]  # fmt: skip
    for rows, status in cases:
        outs = []
        plain, compiled = tracker.tracker_reference, tracker.tracker_into
        for fn, mix in ((plain, None), (compiled, ctrl.mixer.packed)):
            out, state = np.empty(tracker.OUT_WIDTH), tracker.tracker_state()
            args = (1.0, zero, zero, q, zero, rows, 0.0, np.zeros(3), state, ctrl._par)
            if mix is None:
                out = fn(*args, ctrl.mixer.layout, ctrl.mixer.rotors)
            else:
                fn(*args, mix, out)
            outs.append(out[tracker.OUT_SINGULAR])
        assert outs == [status, status]


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
@given(SEEDS, st.booleans(), st.booleans(), st.booleans(), st.booleans())
def test_compiled_hierarchical_matches_the_reference(scenario, seed, feedforward, fresh, taut,
                                                     lean):  # fmt: skip
    ctrl = HierarchicalController(scenario)
    rng = np.random.default_rng(seed)
    link, q, w, Y, ff_w, ff_wd = _hierarchical_inputs(rng, ctrl)
    state = hierarchical.hierarchical_state(ctrl.mass, ctrl.g)
    if lean:  # a lean limit of 0.3-6 deg (Reference.lean_limit)
        state[hierarchical.STATE_LEAN_TAN] = math.tan(rng.uniform(0.005, 0.1))
    if not fresh:  # an earlier update: integral, time and a regular attitude to hold
        state[hierarchical.STATE_INTEGRAL] = rng.normal(0, 0.05, 2)
        state[hierarchical.STATE_T_LAST] = 0.998
        state[hierarchical.STATE_THRUST] = rng.uniform(5, 20)
        state[hierarchical.STATE_HAS_R_D] = 1.0
        state[hierarchical.STATE_R_D] = exp_so3(rng.normal(0, 1, 3)).reshape(9)
    tension = rng.uniform(0, 8) if taut else 0.0
    s_ref = state.copy()
    expected = hierarchical.hierarchical_reference(1.0, link, q, w, Y, ff_w, ff_wd, feedforward,
                                              tension, s_ref, ctrl._par, ctrl.mixer.layout,
                                              ctrl.mixer.rotors)  # fmt: skip
    out = np.empty(hierarchical.OUT_WIDTH)
    hierarchical.hierarchical_into(1.0, link, q, w, Y, ff_w, ff_wd, feedforward, tension, state,
                              ctrl._par, ctrl.mixer.packed, out)  # fmt: skip
    np.testing.assert_allclose(out, expected, rtol=1e-9, atol=1e-9, equal_nan=True)
    np.testing.assert_allclose(state, s_ref, rtol=1e-9, atol=1e-12)


def _desired_lean(ctrl: HierarchicalController, link: np.ndarray, state: np.ndarray) -> float:
    """Lean of the desired thrust axis z_B,d (``state``'s last regular attitude) out of the
    link plane: asin(z_B,d . y_L), y_L = R_WA link_frame(phi, delta) e_y [rad]."""
    z_d = state[hierarchical.STATE_R_D].reshape(3, 3)[:, 2]
    y_L = ctrl.R_WA @ link_frame(link[0], link[1])[:, 1]
    return math.asin(float(z_d @ y_L))


@pytest.mark.parametrize("sign", [-1.0, 1.0])
def test_the_lean_limit_cuts_the_sideways_force_to_the_limit_and_holds_the_delta_integral(
    scenario, sign
):
    """A link 0.15 rad off its azimuth reference asks for a sideways force that leans the
    thrust axis by more than 2 deg out of the link plane: with a 2 deg limit the desired
    axis leans exactly 2 deg, to the same side; the phi integral advances, the delta
    integral keeps its value (no wind-up against the limit). With the error small, the
    limit changes nothing."""
    ctrl = HierarchicalController(scenario)
    limit = math.radians(2.0)
    link = np.array([0.8, sign * 0.15, 0.0, 0.0])
    q = rotmat_to_quat(ctrl.R_WA @ exp_so3([0.0, math.pi / 2 - link[0], 0.0]))
    Y = np.zeros((3, 4))
    Y[0, 0] = 0.75  # phi_d: 0.05 rad below, so the phi integral moves
    s0 = hierarchical.hierarchical_state(ctrl.mass, ctrl.g)
    s0[hierarchical.STATE_T_LAST] = 0.998
    s0[hierarchical.STATE_INTEGRAL] = [0.01, -0.02]

    def update(state, link):
        out = np.empty(hierarchical.OUT_WIDTH)
        zero = np.zeros(3)
        hierarchical.hierarchical_into(1.0, link, q, zero, Y, zero, zero, False, 5.0, state,
                                       ctrl._par, ctrl.mixer.packed, out)  # fmt: skip
        return out

    free, held = s0.copy(), s0.copy()
    held[hierarchical.STATE_LEAN_TAN] = math.tan(limit)
    update(free, link)
    update(held, link)
    assert abs(_desired_lean(ctrl, link, free)) > 1.5 * limit  # the case asks for more
    assert _desired_lean(ctrl, link, held) == pytest.approx(
        math.copysign(limit, _desired_lean(ctrl, link, free)), abs=1e-12)
    dt = 1.0 - 0.998
    assert held[hierarchical.STATE_INTEGRAL][0] == pytest.approx(0.01 + (0.75 - 0.8) * dt)
    assert held[hierarchical.STATE_INTEGRAL][1] == -0.02
    assert free[hierarchical.STATE_INTEGRAL][1] == pytest.approx(-0.02 - sign * 0.15 * dt)
    # within the limit: the same command, bit for bit
    small = np.array([0.8, sign * 1e-4, 0.0, 0.0])
    free, held = s0.copy(), s0.copy()
    held[hierarchical.STATE_LEAN_TAN] = math.tan(limit)
    np.testing.assert_array_equal(update(free, small), update(held, small))
    assert abs(_desired_lean(ctrl, small, held)) < limit


def test_remainder_matches_math_remainder():
    rng = np.random.default_rng(7)
    for x in np.concatenate((rng.uniform(-20, 20, 2000), np.arange(-7, 8) * math.pi)):
        assert math.isclose(so3.remainder(x, 2 * math.pi), math.remainder(x, 2 * math.pi),
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


# ------------------------------------------------------------------ packed layouts

LAYOUTS = [(mixer, "MIX"), (mixer, "OUT"), (so3, "ATT"), (so3, "CABLE"), (free_flight, "PAR"),
           (free_flight, "OUT"), (hierarchical, "PAR"), (hierarchical, "STATE"),
           (hierarchical, "OUT"), (dfl, "PAR"), (dfl, "STATE"), (dfl, "OUT"),
           (dfl_model, "YAB"), (tracker, "PAR"), (tracker, "STATE"), (tracker, "OUT")]  # fmt: skip


def test_fields_are_laid_out_in_the_order_declared():
    f = Fields(2)
    a, v, b = f.scalar(), f.vector(3), f.scalar()
    assert (a, v, b, f.width) == (2, slice(3, 6), 6, 7)
    with pytest.raises(ValueError, match="at least one value"):
        f.vector(0)


@pytest.mark.parametrize(("module", "prefix"), LAYOUTS)
def test_every_position_of_a_packed_array_has_exactly_one_name(module, prefix):
    width = getattr(module, f"{prefix}_WIDTH")
    positions = []
    for name, value in vars(module).items():
        if not name.startswith(prefix + "_") or name == f"{prefix}_WIDTH":
            continue
        if isinstance(value, slice):
            positions += range(width)[value]
        elif isinstance(value, int):
            positions.append(value)
    if prefix == "OUT" and module is not mixer:  # every law's result begins with the mixer's
        assert module.OUT_WIDTH > mixer.OUT_WIDTH
        positions += range(mixer.OUT_WIDTH)
    assert sorted(positions) == list(range(width))


def test_packers_write_every_field_under_its_name():
    rng = np.random.default_rng(3)
    J, k_R, k_w = rng.uniform(0.01, 0.1, (3, 3))
    att = so3.pack_attitude(J, k_R, k_w)
    np.testing.assert_array_equal(att[so3.ATT_J_K_R], J * k_R)
    G = rng.normal(0, 1, (4, 4))
    mix = mixer.pack_mixer(G, np.linalg.inv(G), 0.1, 7.0, 2e-6, 0.02, 100.0, 2000.0)
    np.testing.assert_array_equal(mix[mixer.MIX_G], G.reshape(16))
    assert (mix[mixer.MIX_F_MAX], mix[mixer.MIX_TAU], mix[mixer.MIX_W_MIN]) == (7.0, 0.02, 100.0)
    ff = free_flight.pack_free_flight(1.2, 9.8, 4.0, 3.0, 0.5, 2.4, 1.0, 0.6, J, k_R, k_w)
    assert ff[free_flight.PAR_INTEGRAL_BOUND] == 2.4 / (1.2 * 0.5)
    assert (ff[free_flight.PAR_K_V], ff[free_flight.PAR_MIN_VERTICAL]) == (3.0, 0.6)
    np.testing.assert_array_equal(ff[free_flight.PAR_ATTITUDE], att)
    R_WA = exp_so3(rng.normal(0, 1, 3))
    hc = hierarchical.pack_hierarchical(1.2, 1.05, 9.8, 9.0, 6.0, 0.5, 0.3, True,
                                        [0.0, 0.0, -0.05], R_WA, J, k_R, k_w)  # fmt: skip
    cable = hc[hierarchical.PAR_CABLE]
    assert (hc[hierarchical.PAR_LENGTH], cable[so3.CABLE_COMPENSATE]) == (1.05, 1.0)
    np.testing.assert_array_equal(cable[so3.CABLE_R_WA].reshape(3, 3), R_WA)
    np.testing.assert_array_equal(cable[so3.CABLE_R_ATT], [0.0, 0.0, -0.05])
    np.testing.assert_array_equal(hc[hierarchical.PAR_ATTITUDE], att)
    gains = [rng.uniform(1, 9, r) for r in dfl_model.DFL_RELATIVE_DEGREES]
    model = dfl_model.model_parameters(1.2, 1.05, tuple(J))
    d = dfl.pack_dfl(1.2, True, 0.2, False, 2e-3, [0.0, 0.0, -0.05], R_WA, gains,
                     [1.0, 2.0, 3.0, 4.0], np.full(4, 0.25), model)  # fmt: skip
    assert (d[dfl.PAR_INTEGRAL], d[dfl.PAR_CABLE][so3.CABLE_COMPENSATE]) == (1.0, 0.0)
    assert d[dfl.PAR_PERIOD] == 2e-3
    offset = dfl.DFL_OFFSETS[2]  # theta_A's gains follow phi's and delta's
    np.testing.assert_array_equal(d[dfl.PAR_GAINS][offset : offset + 2], gains[2])
    np.testing.assert_array_equal(d[dfl.PAR_MODEL], model)
    for packed in (att, mix, ff, hc, d):
        assert np.all(np.isfinite(packed))


# ------------------------------------------------------------------ shared SO(3) pieces


@settings(max_examples=100, deadline=None)
@given(SEEDS, st.booleans())
def test_compiled_attitude_torque_matches_the_reference(seed, feedforward):
    from tetherland.control.attitude import attitude_torque

    rng = np.random.default_rng(seed)
    J, k_R, k_w = rng.uniform(0.005, 0.05, 3), rng.uniform(10, 400, 3), rng.uniform(2, 40, 3)
    att = so3.pack_attitude(J, k_R, k_w)
    R, R_d = exp_so3(rng.normal(0, 2, 3)), exp_so3(rng.normal(0, 2, 3))
    w, w_d, w_dot_d = rng.normal(0, 3, (3, 3))
    ff = (w_d, w_dot_d) if feedforward else (None, None)
    expected = attitude_torque(J, J * k_R, J * k_w, R, w, R_d, *ff)
    got = so3.attitude_torque(R, w, R_d, w_d, w_dot_d, feedforward, att)
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-12)


@settings(max_examples=100, deadline=None)
@given(SEEDS, st.booleans(), st.booleans())
def test_compiled_rotation_and_cable_torque_match_the_reference(seed, compensate, taut):
    from tetherland.control.common import rot_x, rot_y, rot_z
    from tetherland.geometry import link_frame

    rng = np.random.default_rng(seed)
    theta_e, roll, psi = rng.uniform(-math.pi, math.pi, 3)
    np.testing.assert_allclose(so3.rot_y_x_z(theta_e, roll, psi),
                               rot_y(theta_e) @ rot_x(roll) @ rot_z(psi), atol=1e-14)  # fmt: skip
    R, R_WA = exp_so3(rng.normal(0, 2, 3)), exp_so3(rng.normal(0, 2, 3))
    phi, delta = rng.uniform(-1.5, 1.5, 2)
    x_L = link_frame(phi, delta)[:, 0]
    tau, r_att = rng.normal(0, 1, 3), rng.normal(0, 0.05, 3)
    tension = rng.uniform(0.1, 10) if taut else 0.0
    cable = so3.pack_cable(compensate, r_att, R_WA)
    expected = so3.cancel_cable_torque_reference(tau, R, x_L, tension, cable)
    got = so3.cancel_cable_torque(*tau, R, *x_L, tension, cable)
    np.testing.assert_allclose(got, expected, rtol=1e-9, atol=1e-12)
    # the cable pulls the attachment towards the anchor: its moment r_att x (-f_L d_B) is
    # what the compensation removes, and only when asked for and pulling
    d_B = R.T @ R_WA @ x_L
    moment = np.cross(r_att, -tension * d_B) if compensate and taut else np.zeros(3)
    np.testing.assert_allclose(np.asarray(got) + moment, tau, atol=1e-12)
