"""Compiled estimation kernels against their plain references (random inputs, 1e-9)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherland.estimation import UkfNoise, kernels
from tetherland.estimation import ukf_kernels as uk
from tetherland.estimation.ukf import Ukf
from tetherland.rotations import exp_so3, rotmat_to_quat
from tetherland.state import link_into, link_state_reference

SEEDS = st.integers(0, 2**32 - 1)
NOISE = UkfNoise(0.005, 0.05, 1e-4, 1e-3, 0.001, math.radians(0.3))


def _filter_constants() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    ukf = Ukf(NOISE, _nav(np.random.default_rng(0)), np.eye(15))
    return ukf._wm, ukf._wc, ukf._par


def _nav(rng: np.random.Generator):
    from tetherland.estimation import NavState

    return NavState(
        rng.normal(0, 1, 3), rng.normal(0, 1, 3), _quat(rng), rng.normal(0, 0.01, 3),
        rng.normal(0, 0.1, 3),
    )  # fmt: skip


def _quat(rng: np.random.Generator) -> np.ndarray:
    return rotmat_to_quat(exp_so3(rng.normal(0, 1.0, 3)))


def _state(rng: np.random.Generator) -> np.ndarray:
    n = _nav(rng)
    return np.concatenate((n.p_W, n.v_W, n.q_WB, n.b_g, n.b_a))


def _covariance(rng: np.random.Generator, definite: bool = True) -> np.ndarray:
    """A random SPD covariance; attitude standard deviations from 1e-4 to 0.3 rad (the
    compiled exp map switches from its series to sin/cos within that range)."""
    scale = np.repeat([rng.uniform(1e-3, 0.1), 0.05, 10 ** rng.uniform(-4, -0.5), 0.01, 0.1], 3)
    A = rng.normal(size=(15, 15)) / 4.0
    P = scale[:, None] * (A @ A.T + 0.05 * np.eye(15)) * scale[None, :]
    if not definite:  # one negative eigenvalue: both take the eigen-decomposition branch
        w, V = np.linalg.eigh(P)
        w[0] = -abs(w[0])
        P = (V * w) @ V.T
    return P


def _imu(rng: np.random.Generator, t0: float, k: int) -> np.ndarray:
    t = t0 + np.cumsum(rng.uniform(0.5e-3, 2e-3, k))
    f = rng.normal([0.0, 0.0, 9.81], 3.0, (k, 3))
    w = rng.normal(0.0, 1.0, (k, 3))
    return np.column_stack((t, f, w))


def _ring(capacity: int) -> tuple[np.ndarray, np.ndarray]:
    return np.zeros((capacity, uk.HIST_WIDTH)), np.zeros(2, dtype=np.int64)


@settings(max_examples=60, deadline=None)
@given(SEEDS, st.integers(1, 4), st.booleans())
def test_compiled_predict_matches_the_reference(seed, k, definite):
    rng = np.random.default_rng(seed)
    wm, wc, par = _filter_constants()
    x, P = _state(rng), _covariance(rng, definite)
    imu = _imu(rng, 1.0, k)
    x_ref, P_ref, hist_ref, clock_ref = uk.predict_reference(x, P, 1.0, imu, wm, wc, par)
    hist, ring = _ring(3)  # smaller than k + 1 rows: the ring overwrites its oldest
    ring[:] = [0, 1]
    x_c, P_c = x.copy(), P.copy()
    buf = np.zeros((16, 7))
    buf[:k] = imu
    clock = np.concatenate(([1.0], rng.normal(size=9)))
    uk.predict_into(x_c, P_c, clock, buf, k, wm, wc, par, hist, ring)
    np.testing.assert_allclose(clock, clock_ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(x_c, x_ref, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(P_c, P_ref, rtol=0, atol=1e-9 * np.abs(P_ref).max())
    assert np.array_equal(P_c, P_c.T)
    newest = [(ring[0] + ring[1] - 1 - j) % 3 for j in range(min(k, 2))]
    np.testing.assert_allclose(hist[newest], hist_ref[::-1][: len(newest)], rtol=1e-9, atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(SEEDS, st.floats(0.0, 0.02))
def test_compiled_pose_update_matches_the_reference(seed, latency):
    rng = np.random.default_rng(seed)
    wm, wc, par = _filter_constants()
    x, P = _state(rng), _covariance(rng)
    hist, ring = _ring(40)
    t_now = 1.0
    times = t_now - 1e-3 * np.arange(30)[::-1]
    for t in times:  # a history of 30 rows, 1 ms apart, ending now
        uk._ring_push(hist, ring, t, *rng.normal(0, 1, 3), *_quat(rng))
    t_meas = t_now - latency
    k = uk.history_index(hist, ring, t_meas)
    assert hist[k, 0] <= t_meas + uk.TIME_TOL and (hist[k, 0] > t_meas - 1e-3 - 1e-12)
    p_meas = hist[k, 1:4] + rng.normal(0, 0.01, 3)
    q_meas = rotmat_to_quat(exp_so3(rng.normal(0, 0.01, 3)) @ _rot(hist[k, 4:8]))
    x_ref, P_ref, nis_ref = uk.update_pose_reference(
        x, P, hist[k, 1:4], hist[k, 4:8], p_meas, q_meas, wm, wc, par
    )
    x_c, P_c = x.copy(), P.copy()
    nis = uk.update_pose_into(x_c, P_c, t_meas, p_meas, q_meas, wm, wc, par, hist, ring)
    np.testing.assert_allclose(x_c, x_ref, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(P_c, P_ref, rtol=0, atol=1e-9 * np.abs(P_ref).max())
    assert math.isclose(nis, nis_ref, rel_tol=1e-9)
    # older than the history: nothing fused
    x_before, P_before = x_c.copy(), P_c.copy()
    nis = uk.update_pose_into(x_c, P_c, times[0] - 0.01, p_meas, q_meas, wm, wc, par, hist, ring)
    assert nis == uk.REJECTED
    np.testing.assert_array_equal(x_c, x_before)
    np.testing.assert_array_equal(P_c, P_before)


def _rot(q: np.ndarray) -> np.ndarray:
    from tetherland.rotations import quat_to_rotmat

    return quat_to_rotmat(q)


@settings(max_examples=100, deadline=None)
@given(SEEDS, st.floats(0.0, 1e-8), st.booleans())
def test_compiled_exp_log_match_the_reference(seed, tiny, series):
    rng = np.random.default_rng(seed)
    phi = rng.normal(size=3)
    phi *= (tiny if tiny > 0 else rng.uniform(0, uk.SERIES_ANGLE if series else 3.0)) / max(
        np.linalg.norm(phi), 1e-300
    )
    np.testing.assert_allclose(uk.qexp(*phi), uk.qexp_reference(phi), rtol=1e-12, atol=1e-16)
    q = _quat(rng) * (1 if rng.uniform() < 0.5 else -1)
    np.testing.assert_allclose(uk.qlog(q), uk.qlog_reference(q), rtol=1e-12, atol=1e-15)


@settings(max_examples=100, deadline=None)
@given(SEEDS, st.booleans())
def test_compiled_link_state_matches_the_reference(seed, at_anchor):
    rng = np.random.default_rng(seed)
    r_att, p_A, R_WA = rng.normal(0, 0.05, 3), rng.normal(0, 1, 3), exp_so3(rng.normal(size=3))
    q = _quat(rng)
    p = p_A - _rot(q) @ r_att if at_anchor else rng.normal(0, 1, 3)
    x = np.concatenate((p, q, rng.normal(0, 1, 3), rng.normal(0, 2, 3)))
    ref, d_ref = link_state_reference(x, r_att, p_A, R_WA)
    out, d_B = np.empty(4), np.empty(3)
    link_into(x[0:3], x[3:7], x[7:10], x[10:13], r_att, p_A, R_WA, out, d_B)
    np.testing.assert_allclose(out, ref, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(d_B, d_ref, rtol=1e-9, atol=1e-12)
    if not at_anchor:  # the angles invert the link direction: d_A(phi, delta) = u
        from tetherland.geometry import link_direction

        u = R_WA.T @ (p + _rot(q) @ r_att - p_A)
        np.testing.assert_allclose(link_direction(out[0], out[1]), u / np.linalg.norm(u),
                                   atol=1e-12)  # fmt: skip


@settings(max_examples=100, deadline=None)
@given(SEEDS, st.booleans())
def test_compiled_estimate_matches_the_reference(seed, at_anchor):
    rng = np.random.default_rng(seed)
    x = _state(rng)
    r_att, p_A, R_WA = rng.normal(0, 0.05, 3), rng.normal(0, 1, 3), exp_so3(rng.normal(size=3))
    if at_anchor:  # no link direction: the tension is the norm of the residual force
        x[0:3] = p_A - _rot(x[6:10]) @ r_att
    geo = kernels.pack_geometry(r_att, p_A, R_WA)
    imu = np.concatenate(([1.0], rng.normal(0, 3, 3), rng.normal(0, 1, 3),
                          rng.normal([0, 0, 9.81], 2, 3)))  # fmt: skip
    thrust, mass = rng.uniform(0, 30), rng.uniform(0.5, 3)
    ref = kernels.estimate_reference(x, imu, thrust, mass, geo)
    out = np.empty(kernels.WIDTH)
    kernels.estimate_into(x, imu, thrust, mass, geo, out)
    np.testing.assert_allclose(out, ref, rtol=1e-9, atol=1e-12, equal_nan=True)
