"""UKF consistency (NEES / NIS within chi-square bounds), dropout recovery, delayed fusion."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from tetherland.estimation import NavState, Ukf, UkfNoise, initial_covariance
from ukf_sim import SyntheticRun, simulate

NOISE = UkfNoise(0.005, 0.05, 1e-4, 1e-3, 0.001, math.radians(0.3))


def make_filter(run: SyntheticRun) -> Ukf:
    P0 = initial_covariance(1e-3, 1e-3, 1e-3, gyro_bias=0.005, accel_bias=0.05)
    return Ukf(NOISE, run.x0, P0, t0=0.0)


def replay(ukf: Ukf, run: SyntheticRun, every: int, skip: float = 2.0):
    """Run the filter over ``run``; return NEES every ``every`` samples after ``skip`` s,
    the NIS of every fused measurement, and the position error/sigma per sample."""
    nees, nis, pos = [], [], []
    m = 0
    for k in range(len(run.t)):
        ukf.predict(run.t[k], run.f_m[k], run.w_m[k])
        while m < len(run.mocap) and run.mocap[m][1] <= run.t[k] + 1e-12:
            t_meas, _, p, q = run.mocap[m]
            nis.append(ukf.update_pose(t_meas, p, q))
            m += 1
        e = ukf.error(run.truth[k])
        pos.append((np.linalg.norm(e[:3]), math.sqrt(np.trace(ukf.covariance[:3, :3]))))
        if k % every == every - 1 and run.t[k] > skip:
            nees.append(ukf.nees(run.truth[k]))
    return np.array(nees), np.array(nis), np.array(pos)


@pytest.fixture(scope="module")
def consistency():
    runs = [simulate(np.random.default_rng(seed), 20.0) for seed in (11, 12, 13)]
    out = [replay(make_filter(run), run, every=1000) for run in runs]
    return np.concatenate([o[0] for o in out]), np.concatenate([o[1] for o in out])


def test_nees_within_chi_square_bounds(consistency):
    nees, _ = consistency
    n = len(nees)
    lo, hi = stats.chi2.ppf([0.005, 0.995], 15 * n) / n
    assert lo <= nees.mean() <= hi, (nees.mean(), lo, hi)
    assert np.mean(nees < stats.chi2.ppf(0.99, 15)) >= 0.95


def test_nis_within_chi_square_bounds(consistency):
    _, nis = consistency
    n = len(nis)
    lo, hi = stats.chi2.ppf([0.005, 0.995], 6 * n) / n
    assert lo <= nis.mean() <= hi, (nis.mean(), lo, hi)


def test_recovers_from_half_second_dropout():
    run = simulate(np.random.default_rng(5), 8.0, dropout=(5.0, 5.5))
    _, _, pos = replay(make_filter(run), run, every=10**9)
    t = run.t
    before = (t > 4.5) & (t < 5.0)
    during_end = np.argmin(np.abs(t - 5.5 - 0.004))
    after = (t > 5.8) & (t < 8.0)
    sigma_before = pos[before, 1].mean()
    assert pos[during_end, 1] > 3 * sigma_before  # uncertainty grows without mocap ...
    assert pos[during_end, 0] < 4 * pos[during_end, 1]  # ... and covers the error
    assert pos[after, 0].max() < 3e-3  # back to millimetres 0.3 s after mocap returns
    assert pos[after, 1].mean() < 1.5 * sigma_before


def test_predict_many_equals_per_sample_predict_for_the_mean():
    run = simulate(np.random.default_rng(2), 0.2)
    a, b = make_filter(run), make_filter(run)
    for k in range(len(run.t)):
        a.predict(run.t[k], run.f_m[k], run.w_m[k])
    for k in range(0, len(run.t), 4):
        b.predict_many(run.t[k : k + 4], run.f_m[k : k + 4], run.w_m[k : k + 4])
    np.testing.assert_allclose(a.state.p_W, b.state.p_W, atol=1e-9)
    np.testing.assert_allclose(a.state.q_WB, b.state.q_WB, atol=1e-9)
    np.testing.assert_allclose(a.covariance, b.covariance, rtol=1e-2, atol=1e-12)


def test_too_old_measurement_is_rejected_not_fused():
    run = simulate(np.random.default_rng(3), 0.3)
    ukf = make_filter(run)
    for k in range(len(run.t)):
        ukf.predict(run.t[k], run.f_m[k], run.w_m[k])
    before = ukf.state
    assert math.isnan(ukf.update_pose(0.3 - 0.5, np.ones(3), np.array([1.0, 0, 0, 0])))
    assert ukf.rejected_late == 1
    np.testing.assert_array_equal(ukf.state.p_W, before.p_W)


def test_time_must_increase():
    ukf = Ukf(
        NOISE,
        NavState(np.zeros(3), np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(3), np.zeros(3)),
        initial_covariance(),
    )
    ukf.predict(0.001, [0, 0, 9.81], [0, 0, 0])
    with pytest.raises(ValueError, match="must increase"):
        ukf.predict(0.001, [0, 0, 9.81], [0, 0, 0])
