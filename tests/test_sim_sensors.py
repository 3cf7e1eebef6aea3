"""Sensor noise statistics against their settings (seeded, with stated tolerances)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland.config import ImuConfig, MocapConfig
from tetherland.rotations import quat_conjugate, quat_multiply, quat_to_rotvec
from tetherland.sim.sensors import Imu, Mocap

TRUTH = np.array([0.3, -0.2, 9.81, 0.01, 0.02, -0.03])


def _imu_errors(imu: Imu, n: int) -> np.ndarray:
    out = np.empty((n, 6))
    for k in range(n):
        s = imu.sample(k * imu.period, TRUTH)
        out[k, :3] = s.specific_force_B - TRUTH[:3]
        out[k, 3:] = s.omega_B - TRUTH[3:]
    return out


def test_imu_white_noise_std_matches_settings():
    """No bias walk: per-axis sample std within 5 % of sigma * noise_scale (n = 20000:
    the std of a sample std is 0.5 %)."""
    cfg = ImuConfig(accel_noise=0.05, gyro_noise=0.005, accel_bias_walk=0, gyro_bias_walk=0)
    for scale in (1.0, 3.0):
        err = _imu_errors(Imu(cfg, np.random.default_rng(1), noise_scale=scale), 20000)
        np.testing.assert_allclose(err[:, :3].std(axis=0), 0.05 * scale, rtol=0.05)
        np.testing.assert_allclose(err[:, 3:].std(axis=0), 0.005 * scale, rtol=0.05)
        np.testing.assert_allclose(err.mean(axis=0), 0.0, atol=4 * 0.05 * scale / math.sqrt(20000))


def test_imu_bias_random_walk_variance_grows_linearly():
    """White noise off: y - x = b_k. Var(b_T - b_0) = sigma_b^2 T over 300 seeds (within
    20 %: the variance estimate of 300 x 6 draws has ~3.3 % std) at T = 0.5 s and 1 s."""
    cfg = ImuConfig(accel_noise=0, gyro_noise=0, accel_bias_walk=0.02, gyro_bias_walk=0.002)
    sigma = np.array([0.02] * 3 + [0.002] * 3)
    d_half, d_full = [], []
    for seed in range(300):
        err = _imu_errors(Imu(cfg, np.random.default_rng(seed)), 1001)
        d_half.append(err[500] - err[0])
        d_full.append(err[1000] - err[0])
    for d, T in ((np.array(d_half), 0.5), (np.array(d_full), 1.0)):
        var = (d / sigma) ** 2  # normalised per axis
        assert var.mean() == pytest.approx(T, rel=0.2)


def test_imu_initial_bias_and_reported_bias():
    cfg = ImuConfig(
        accel_noise=0,
        gyro_noise=0,
        accel_bias_walk=0,
        gyro_bias_walk=0,
        accel_bias_initial=0.1,
        gyro_bias_initial=0.01,
    )
    biases = []
    for seed in range(400):
        imu = Imu(cfg, np.random.default_rng(seed))
        err = _imu_errors(imu, 3)
        np.testing.assert_allclose(err[0], err[2])  # constant without a walk
        np.testing.assert_allclose(imu.bias, err[2])  # the reported true bias
        biases.append(err[0])
    std = np.array(biases).std(axis=0)
    np.testing.assert_allclose(std, [0.1] * 3 + [0.01] * 3, rtol=0.15)


def test_zero_noise_scale_gives_perfect_sensors():
    imu = Imu(ImuConfig(accel_bias_initial=1.0), np.random.default_rng(0), noise_scale=0.0)
    np.testing.assert_array_equal(_imu_errors(imu, 5), 0.0)
    mocap = Mocap(MocapConfig(), np.random.default_rng(0), noise_scale=0.0)
    s = mocap.measure(0.0, [1.0, 2.0, 3.0], [1.0, 0.0, 0.0, 0.0])
    np.testing.assert_array_equal(s.p_W, [1.0, 2.0, 3.0])
    np.testing.assert_allclose(s.q_WB, [1.0, 0.0, 0.0, 0.0])


def test_mocap_noise_and_latency_match_settings():
    """Position std per axis and attitude rotation-vector std within 5 % (n = 20000)."""
    cfg = MocapConfig(position_noise=0.002, attitude_noise_deg=0.5, latency=0.007)
    mocap = Mocap(cfg, np.random.default_rng(3))
    q_true = np.array([math.cos(0.3), 0.0, math.sin(0.3), 0.0])
    p_true = np.array([1.0, -2.0, 0.5])
    n = 20000
    dp, dth = np.empty((n, 3)), np.empty((n, 3))
    for k in range(n):
        s = mocap.measure(k / 120.0, p_true, q_true)
        assert s.valid and s.t_delivered == pytest.approx(s.t_measured + 0.007)
        dp[k] = s.p_W - p_true
        dth[k] = quat_to_rotvec(quat_multiply(quat_conjugate(q_true), s.q_WB))
    np.testing.assert_allclose(dp.std(axis=0), 0.002, rtol=0.05)
    np.testing.assert_allclose(dth.std(axis=0), math.radians(0.5), rtol=0.05)


def test_mocap_dropouts_follow_the_poisson_window_coverage():
    """Windows of length D starting at Poisson times (rate lambda) cover a given instant
    with probability 1 - exp(-lambda D); over 200 s at 120 Hz within 10 %."""
    lam, D = 0.5, 0.3
    mocap = Mocap(MocapConfig(dropout_rate=lam, dropout_duration=D), np.random.default_rng(5))
    samples = [mocap.measure(k / 120.0, np.zeros(3), [1.0, 0, 0, 0]) for k in range(120 * 200)]
    lost = np.array([not s.valid for s in samples])
    assert lost.mean() == pytest.approx(1 - math.exp(-lam * D), rel=0.1)
    assert all(np.all(np.isnan(s.p_W)) for s in samples if not s.valid)


def test_dropouts_do_not_change_the_noise_stream():
    base = Mocap(MocapConfig(), np.random.default_rng(9))
    drop = Mocap(MocapConfig(dropout_rate=2.0, dropout_duration=0.1), np.random.default_rng(9))
    a = [base.measure(k / 120, np.zeros(3), [1.0, 0, 0, 0]) for k in range(600)]
    b = [drop.measure(k / 120, np.zeros(3), [1.0, 0, 0, 0]) for k in range(600)]
    valid = [(x, y) for x, y in zip(a, b, strict=True) if y.valid]
    assert 0 < len(valid) < 600
    for x, y in valid:
        np.testing.assert_array_equal(x.p_W, y.p_W)


def test_sample_into_writes_the_row_of_sample():
    """The runner's allocation-free row [t, f_B, omega_B] carries the very values of
    :meth:`Imu.sample` from the same stream, across the noise blocks' refills."""
    cfg = ImuConfig(accel_noise=0.05, gyro_noise=0.005, accel_bias_walk=0.01)
    a = Imu(cfg, np.random.default_rng(9))
    b = Imu(cfg, np.random.default_rng(9))
    row = np.full(8, np.nan)
    for k in range(2500):  # (the noise is drawn in blocks of 1024)
        s = a.sample(k * a.period, TRUTH)
        b.sample_into(k * b.period, TRUTH, row)
        assert row[0] == s.t
        assert row[1:4].tobytes() == s.specific_force_B.tobytes()
        assert row[4:7].tobytes() == s.omega_B.tobytes()
        assert math.isnan(row[7])  # nothing written past the row
        np.testing.assert_array_equal(a.bias, b.bias)
