"""The compiled believed aerodynamics of the controllers and the estimator against their
plain forms (issue 25): the believed ground effect exactly against the plant's kernel
``aero_into`` (the same operations), everything to 1e-9 against the numpy references,
and exactly against numpy where this machine's BLAS rounds as the kernels assume."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rounding import BLAS_AS_KERNELS
from tetherland.config import load_scenario
from tetherland.control.kernels import aero as K
from tetherland.control.rotor_drag import RotorDragCompensation, replaced
from tetherland.estimation.ground_effect import BelievedGroundEffect
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import Command, ControlMode, Feedforward, Reference, StateEstimate
from tetherland.models.aero import aero_into, aero_reference
from tetherland.rotations import quat_to_rotmat
from tetherland.state import RigidBodyState

SEEDS = st.integers(0, 2**32 - 1)
SCENARIOS = ("slope50", "pipe60", "wall90")  # a tilted patch, a pipe, a vertical wall


@pytest.fixture(scope="module")
def beliefs():
    out = {}
    for name in SCENARIOS:
        sc = load_scenario(name)
        out[name] = (sc, LandingGeometry.from_scenario(sc), BelievedGroundEffect(sc))
    return out


def _quat(rng: np.random.Generator, tilt: float) -> np.ndarray:
    """A unit quaternion: near level for a small ``tilt``, any attitude for a large one."""
    q = np.concatenate(([1.0], rng.normal(0.0, tilt, 3)))
    return q / np.linalg.norm(q)


def _pose_near(rng: np.random.Generator, geo: LandingGeometry) -> tuple[np.ndarray, np.ndarray]:
    """A pose from touching the believed surface to beyond the rotors' reach, over it and
    off its edges, level with it or tumbling."""
    surf = geo.surface
    across = rng.uniform(-1.5, 1.5) * surf.x_S + rng.uniform(-1.5, 1.5) * surf.R_WS[:, 1]
    p = geo.p_L + rng.uniform(0.0, 3.0) * surf.z_S + across
    return p, _quat(rng, float(rng.choice([0.05, 0.5, 5.0])))


def _aero_into(belief: BelievedGroundEffect, p, q, thrusts) -> tuple[np.ndarray, np.ndarray]:
    """Factors and acting thrusts of the plant's kernel on the believed model."""
    m = belief.model
    factors, acting, wrench = np.empty(4), np.empty(4), np.empty(6)
    f = np.asarray(thrusts, dtype=float)
    args = (m.rotor_centres_B, m.samples, m.shapes, m.params)
    aero_into(np.concatenate((p, q)), np.zeros(3), f, *args, factors, acting, wrench)
    return factors, acting




# ------------------------------------------------------------------ the believed ground effect
@settings(max_examples=300, deadline=None)
@given(SEEDS, st.sampled_from(SCENARIOS))
def test_believed_kernel_has_the_bits_of_the_plant_kernel(beliefs, seed, name):
    """Near the surface the compiled belief gives the factors and the summed acting thrust
    of ``aero_into`` on the same model bit for bit, and those of the numpy reference to
    1e-9; beyond the reach, factors 1 and the thrusts summed."""
    _, geo, belief = beliefs[name]
    rng = np.random.default_rng(seed)
    p, q = _pose_near(rng, geo)
    thrusts = rng.uniform(0.0, 6.0, 4)
    total = belief.total_thrust(p, q, thrusts)
    if belief.beyond_reach(p):
        np.testing.assert_array_equal(belief.factors, np.ones(4))
        assert total == float(np.sum(thrusts))
        return
    factors, acting = _aero_into(belief, p, q, thrusts)
    np.testing.assert_array_equal(belief.factors, factors)
    assert total == float(np.sum(acting))
    ref = aero_reference(belief.model, np.concatenate((p, q)), np.zeros(3), thrusts)
    np.testing.assert_allclose(belief.factors, ref.factors, rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("name", SCENARIOS)
def test_believed_kernel_inputs_cover_its_branches(beliefs, name):
    """The draws above reach every branch: beyond the reach, every rotor over the surface,
    and some rotors over it with others wholly off its edge (factor exactly 1)."""
    _, geo, belief = beliefs[name]
    rng = np.random.default_rng(1)
    seen = {"far": 0, "all": 0, "some": 0}
    for _ in range(600):
        p, q = _pose_near(rng, geo)
        if belief.beyond_reach(p):
            seen["far"] += 1
            continue
        k = belief.factors_at(p, q, near=True)
        np.testing.assert_array_equal(k, _aero_into(belief, p, q, np.ones(4))[0])
        ones = int(np.sum(k == 1.0))
        if ones == 0:
            seen["all"] += 1
        elif ones < 4:
            seen["some"] += 1
    assert min(seen.values()) > 5, seen


@settings(max_examples=200, deadline=None)
@given(SEEDS, st.sampled_from(SCENARIOS))
def test_believed_distance_is_its_reference(beliefs, seed, name):
    _, geo, belief = beliefs[name]
    p, _ = _pose_near(np.random.default_rng(seed), geo)
    assert belief._distance(p) == pytest.approx(belief.distance_reference(p), abs=1e-12)


# ------------------------------------------------------------------ the ground-effect command
@settings(max_examples=300, deadline=None)
@given(SEEDS, st.sampled_from(SCENARIOS), st.booleans())
def test_compensated_speeds_match_the_reference(beliefs, seed, name, motors_on):
    """The compiled command (pose one lag ahead, factors there, w / sqrt(k)) is the plain
    one to 1e-9, left as it is exactly where the reference leaves it (motors off, beyond
    the reach)."""
    sc, geo, belief = beliefs[name]
    rng = np.random.default_rng(seed)
    p, q = _pose_near(rng, geo)
    v, omega = rng.normal(0.0, 1.0, 3), rng.normal(0.0, 3.0, 3)
    w = rng.uniform(100.0, 900.0, 4) if motors_on else np.zeros(4)
    tau = sc.vehicle.motor_time_constant
    ref = K.ground_effect_speeds_reference(p, v, q, omega, w, tau, belief)
    out = np.full(4, np.nan)
    changed = K.ground_effect_speeds_into(p, v, q, omega, w, tau, belief.packed, out)
    assert changed == (ref is not None)
    if ref is None:
        assert np.isnan(out).all()  # not written
        return
    assert np.all(out <= w)  # a surface only adds thrust: the speeds only come down
    np.testing.assert_allclose(out, ref, rtol=1e-9, atol=0.0)


# ------------------------------------------------------------------ the rotor drag
@settings(max_examples=300, deadline=None)
@given(SEEDS, st.integers(2, 5))
def test_drag_rows_match_the_reference(seed, n_rows):
    """The compiled feed-forward rows are the plain ones, to 1e-12 of the largest row
    value, and bit for bit where this machine's BLAS rounds as the kernel assumes."""
    rng = np.random.default_rng(seed)
    q = _quat(rng, 5.0)
    rows = rng.normal(0.0, 3.0, (n_rows, 3))
    d_xy, mass = rng.uniform(0.0, 0.6, 2), float(rng.uniform(0.5, 3.0))
    ref = K.drag_rows_reference(quat_to_rotmat(q), rows, d_xy, mass)
    out = np.empty((max(n_rows, 3), 3))
    K.drag_rows_into(q, rows, K.pack_drag(d_xy, mass, 1.0, np.eye(3)), out)
    assert out.shape == ref.shape
    np.testing.assert_allclose(out, ref, rtol=0.0, atol=1e-12 * np.abs(ref).max())
    if BLAS_AS_KERNELS:
        np.testing.assert_array_equal(out, ref)


@settings(max_examples=300, deadline=None)
@given(SEEDS, st.sampled_from(SCENARIOS))
def test_link_drag_matches_the_reference(beliefs, seed, name):
    _, geo, _ = beliefs[name]
    rng = np.random.default_rng(seed)
    q = _quat(rng, 5.0)
    Y = rng.normal(0.0, 1.0, (5, 4))
    thrust = float(rng.choice([0.0, rng.uniform(1.0, 30.0)]))
    d_xy, mass, length = rng.uniform(0.0, 0.6, 2), float(rng.uniform(0.5, 3.0)), geo.link_length
    # the scenario's anchor frame (axis-aligned rows) or any
    R_WA = geo.R_WA if rng.random() < 0.5 else quat_to_rotmat(_quat(rng, 5.0))
    ref = K.link_drag_acceleration(quat_to_rotmat(q), R_WA, Y, thrust, d_xy, mass, length)
    got = K.link_drag_into(q, Y, thrust, K.pack_drag(d_xy, mass, length, R_WA))
    np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-12)
    if BLAS_AS_KERNELS:
        assert got == ref


class Recorder:
    """A controller that keeps the reference it was given."""

    def __init__(self) -> None:
        self.seen: list[Reference] = []

    def update(self, t, estimate, reference):
        self.seen.append(reference)
        return Command(rotor_speeds=np.full(4, 500.0))


def test_replaced_is_dataclasses_replace():
    """Every field of the reference is carried over, the one named replaced."""
    ff = Feedforward(omega_B=np.ones(3), omega_dot_B=np.zeros(3), f_R=9.0)
    values = dict(
        t=1.5, mode=ControlMode.TETHERED, phase=7, p_W=np.ones((3, 3)), yaw=0.3,
        output=np.ones((5, 4)), thrust_ff=11.0, feedforward=ff, terminate=True,
        lateral_free=True, lean_limit=0.02, thrust_scale=0.5, thrust_shed=0.25,
        drag_in_rows=True, torque_ff_B=np.full(3, 0.01),
    )  # fmt: skip
    names = [f.name for f in dataclasses.fields(Reference)]
    assert sorted(values) == sorted(names)  # every field set to a value not its default
    ref = Reference(**values)
    new = np.zeros((3, 3))
    for i, name in enumerate(names):
        got, expected = replaced(ref, i, new), dataclasses.replace(ref, **{name: new})
        for f in names:
            assert getattr(got, f) is getattr(expected, f)


def test_the_wrapper_hands_on_the_reference_rows_and_link_accelerations():
    """RotorDragCompensation passes the compiled rows (free flight) and link accelerations
    (tethered) on, with every other field of the reference as it was."""
    sc = load_scenario("slope50")
    geo = LandingGeometry.from_scenario(sc)
    inner = Recorder()
    ctrl = RotorDragCompensation(inner, sc)
    q = _quat(np.random.default_rng(2), 0.3)
    body = RigidBodyState(geo.p_L + 0.5 * geo.surface.z_S, np.zeros(3), q, np.zeros(3))
    est = StateEstimate(t=0.0, body=body)
    rows = np.array([[0.0, 0.0, 1.0], [0.8, -0.4, 0.1], [0.2, 0.1, -0.3]])
    ref = Reference(t=0.0, p_W=rows, yaw=0.2, phase=3)
    ctrl.update(0.0, est, ref)
    expected = K.drag_rows_reference(quat_to_rotmat(q), rows, ctrl.d_xy, ctrl.mass)
    np.testing.assert_allclose(inner.seen[-1].p_W, expected, rtol=0.0, atol=1e-14)
    assert np.all(np.abs(inner.seen[-1].p_W[2] - rows[2]) > 0.0)  # the drag went on
    assert inner.seen[-1] == dataclasses.replace(inner.seen[-1], t=0.0, yaw=0.2, phase=3)
    Y = np.array([[0.9, 0.1, 0.0, 0.0], [0.5, -0.3, 0.0, 0.0], [0.0, 0.0, 0.0, 0.0]])
    tethered = Reference(t=0.0, mode=ControlMode.TETHERED, output=Y, thrust_ff=12.0)
    ctrl.update(0.0, est, tethered)
    a_phi, a_delta = K.link_drag_acceleration(
        quat_to_rotmat(q), geo.R_WA, Y, 12.0, ctrl.d_xy, ctrl.mass, ctrl.length
    )
    got = inner.seen[-1].output
    assert got[2, 0] == pytest.approx(a_phi, abs=1e-14)
    assert got[2, 1] == pytest.approx(a_delta, abs=1e-14)
    assert a_phi != 0.0 and a_delta != 0.0
    np.testing.assert_array_equal(got[:2], Y[:2])
    assert inner.seen[-1].thrust_ff == 12.0 and inner.seen[-1].mode is ControlMode.TETHERED
