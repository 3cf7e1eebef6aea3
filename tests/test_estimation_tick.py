"""The estimator's compiled steps against its plain pieces, bit for bit (issue 25).

:class:`~tetherland.estimation.UkfEstimator` runs each step (an IMU sample, an estimate, a
motion-capture pose, a command) as one compiled call on packed state. The plain pieces it
compiles are the motor lag (:class:`MotorLagThrust`), the tension filter and taut rule
(:class:`TensionEstimator`), the filter's prediction and update (:class:`Ukf`) and the
believed ground effect (:class:`BelievedGroundEffect`): composed as the estimator did
before its tick was compiled (:class:`_PlainEstimator`), they must give the same bits.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherland.config import load_scenario, with_overrides
from tetherland.estimation import (
    MotorLagThrust,
    NavState,
    TensionEstimator,
    Ukf,
    UkfEstimator,
    UkfNoise,
    initial_covariance,
    kernels,
)
from tetherland.estimation import tension as tension_laws
from tetherland.estimation.ground_effect import BelievedGroundEffect
from tetherland.estimation.tension import tension_filter_time_constant
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import Command, ImuSample, MocapSample
from tetherland.rotations import exp_so3, rotmat_to_quat
from tetherland.state import RigidBodyState

SEEDS = st.integers(0, 2**32 - 1)


@settings(max_examples=50, deadline=None)
@given(SEEDS, st.sampled_from([0.03, 0.0]))
def test_compiled_motor_lag_is_the_plain_class(seed, tau):
    rng = np.random.default_rng(seed)
    w0 = rng.uniform(0, 900, 4)
    plain = MotorLagThrust(1e-5, tau, w0)
    m = tension_laws.pack_motor_lag(1e-5, tau, w0)
    for _ in range(60):
        dt = 0.002 if rng.random() < 0.6 else float(rng.uniform(1e-4, 5e-3))  # cached, new
        m[tension_laws.M_COMMAND] = w_cmd = rng.uniform(0, 900, 4)
        expected = plain.advance(w_cmd.tolist(), dt)
        assert tension_laws.motor_lag_advance(m, dt) == expected
        assert m[tension_laws.M_SPEEDS].tolist() == plain.speeds
        assert tension_laws.motor_lag_total_thrust(m) == plain.total_thrust


@settings(max_examples=50, deadline=None)
@given(SEEDS, st.sampled_from([0.02, 0.0]))
def test_compiled_tension_filter_is_the_plain_class(seed, time_constant):
    rng = np.random.default_rng(seed)
    threshold, dwell = 1.0, 0.01
    plain = TensionEstimator(1.0, threshold, dwell, time_constant)
    f = tension_laws.pack_tension_filter(threshold, dwell, time_constant)
    t, seen = 0.0, set()
    for k in range(200):
        t += 0.002 if rng.random() < 0.7 else float(rng.choice([0.0, rng.uniform(0, 0.01)]))
        # above the threshold at first (taut after the dwell), then around it (restarts)
        raw = float(rng.normal(2.0, 0.1) if k < 30 else rng.normal(1.0, 0.5))
        expected = plain.filter_value(t, raw)
        assert tension_laws.tension_filter_step(f, t, raw) == expected
        assert f[tension_laws.F_TAUT] == float(plain.taut)
        seen.add(plain.taut)
    assert seen == {True, False}


class _PlainEstimator:
    """The estimator's tick from the plain pieces, as it was composed before the tick
    was compiled (the same buffering of at most 16 IMU samples per integration)."""

    def __init__(self, scenario, initial: RigidBodyState, t0: float, w0: np.ndarray) -> None:
        v = scenario.vehicle
        self.mass = v.mass
        self.ukf = Ukf(
            UkfNoise.from_config(scenario.sensors),
            NavState(initial.p_W, initial.v_W, initial.q_WB, np.zeros(3), np.zeros(3)),
            initial_covariance(),
            t0,
            imu_rate_hz=scenario.sensors.imu.rate_hz,
        )
        geo = LandingGeometry.from_scenario(scenario)
        self.geo = kernels.pack_geometry(np.asarray(v.cable_attachment, float), geo.p_A, geo.R_WA)
        stretch = scenario.mission.stretch
        self.tension = TensionEstimator(
            v.mass, stretch.tension_threshold, stretch.tension_dwell,
            tension_filter_time_constant(scenario.tether.stiffness, v.mass),
        )  # fmt: skip
        self.motors = MotorLagThrust(v.thrust_coefficient, v.motor_time_constant, w0)
        belief = scenario.estimator.ground_effect_belief
        self.ground_effect = BelievedGroundEffect(scenario) if belief else None
        self.motor_t, self.w_cmd, self.rows = t0, w0.tolist(), []
        self.raw = math.nan

    def predict(self, s: ImuSample) -> None:
        if s.t <= self.ukf.t:
            return
        if len(self.rows) == kernels.BUFFER:
            self.flush()
        self.rows.append([s.t, *s.specific_force_B, *s.omega_B])

    def flush(self) -> None:
        if self.rows:
            self.ukf.predict_rows(np.array(self.rows), len(self.rows))
            self.rows = []

    def update(self, m: MocapSample) -> float:
        self.flush()
        return self.ukf.update_pose(m.t_measured, m.p_W, m.q_WB)

    def thrust_at(self, t: float) -> float:
        dt = t - self.motor_t
        if dt > 0.0:
            self.motor_t = t
            return self.motors.advance(self.w_cmd, dt)
        return self.motors.total_thrust

    def command_sent(self, t: float, w: np.ndarray) -> None:
        self.thrust_at(t)
        self.w_cmd = w.tolist()

    def estimate(self) -> tuple[np.ndarray, float, float]:
        self.flush()
        x, imu, t = self.ukf.x_view, self.ukf.imu_view, self.ukf.t
        thrust = self.thrust_at(t)
        if self.ground_effect is not None:
            c_f = self.motors.c_f
            thrusts = [c_f * (w * w) for w in self.motors.speeds]
            thrust = self.ground_effect.total_thrust(x[0:3], x[6:10], thrusts)
        out = np.empty(kernels.WIDTH)
        kernels.estimate_into(x, imu, thrust, self.mass, self.geo, out)
        self.raw = float(out[kernels.TENSION])
        return out, self.tension.filter_value(t, self.raw), t


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.mark.parametrize("belief", [True, False])
@pytest.mark.parametrize("seed", [0, 1])
def test_compiled_estimator_steps_are_the_plain_pieces(belief, seed):
    """A tick-rate run near the slope (the believed ground effect evaluated): IMU samples
    (some at or before the estimate's time, runs of more than 16 between estimates),
    late and dropped motion-capture poses, commands; every estimate the same bits."""
    belief_set = f"estimator.ground_effect_belief={str(belief).lower()}"
    sc = with_overrides(load_scenario("slope50"), [belief_set])
    rng = np.random.default_rng(seed)
    q0 = rotmat_to_quat(exp_so3(rng.normal(0, 0.1, 3)))
    start = RigidBodyState(np.array([0.05, 0.0, 0.3]), np.zeros(3), q0, np.zeros(3))
    w0 = rng.uniform(400, 600, 4)
    est, plain = UkfEstimator(sc, start, 0.0, rotor_speeds0=w0), _PlainEstimator(sc, start, 0.0, w0)
    n_estimates = n_rejected = 0
    for k in range(1, 1500):
        t = k * 1e-3
        f_B = rng.normal([0.0, 0.0, 9.81], 0.5, 3)
        s = ImuSample(t if rng.random() > 0.02 else est.ukf.t, f_B, rng.normal(0, 0.05, 3))
        est.predict(s)
        plain.predict(s)
        if k % 8 == 0:  # a pose measured 5 ms ago (now and then 0.5 s ago: rejected)
            late = 0.5 if rng.random() < 0.05 else 0.005
            valid = rng.random() > 0.1
            p = start.p_W + rng.normal(0, 0.01, 3) if valid else np.full(3, np.nan)
            q = q0 if valid else np.full(4, np.nan)
            m = MocapSample(t - late, t, p, q, valid)
            est.update(m)
            if valid:
                nis = plain.update(m)
                assert est.last_nis == nis or (math.isnan(nis) and math.isnan(est.last_nis))
                n_rejected += math.isnan(nis)
        if k % 2 == 0 and not (300 < k < 340):  # (a gap: more than 16 samples buffered)
            e = est.estimate()
            out, filtered, t_e = plain.estimate()
            n_estimates += 1
            assert e.t == t_e and e.tension == filtered
            for got, i in ((e.body.p_W, kernels.P_W), (e.body.v_W, kernels.V_W),
                           (e.body.q_WB, kernels.Q_WB), (e.body.omega_B, kernels.OMEGA_B),
                           (e.accel_bias_B, kernels.ACCEL_BIAS),
                           (e.gyro_bias_B, kernels.GYRO_BIAS),
                           (e.external_force_B, kernels.EXTERNAL)):  # fmt: skip
                assert _same(got, out[i])
            assert [e.link.phi, e.link.delta, e.link.phi_dot, e.link.delta_dot] == out[
                kernels.LINK
            ].tolist()
            assert _same(e.covariance, plain.ukf.covariance)
            assert est.last_tension.raw == plain.raw
            assert est.last_tension.taut == plain.tension.taut
            w = rng.uniform(300, 800, 4)
            est.command_sent(t + 1e-3, Command(w, 0.0, np.zeros(3)))
            plain.command_sent(t + 1e-3, w)
    assert n_estimates > 600 and n_rejected > 0
    assert est.ukf.rejected_late == plain.ukf.rejected_late == n_rejected


def test_imu_rows_are_the_same_as_one_predict_per_sample():
    """``predict_rows`` (``ImuBatchAware``: the runner's hand-over) against ``predict`` of
    each sample: batches of 1 to 20 rows (more than the 16 buffered), a sample at the
    estimate's own time (ignored by both), poses and estimates between the batches; every
    estimate the same bits."""
    sc = load_scenario("slope50")
    rng = np.random.default_rng(5)
    start = RigidBodyState(np.array([0.05, 0.0, 0.3]), np.zeros(3), np.array([1.0, 0, 0, 0]),
                           np.zeros(3))  # fmt: skip
    rows_est, one_est = UkfEstimator(sc, start, 0.0), UkfEstimator(sc, start, 0.0)
    t, checked = 0.0, 0
    for batch in range(120):
        n = int(rng.integers(1, 21))
        rows = np.empty((n, 7))
        for j in range(n):
            t += 1e-3
            rows[j] = [t, *rng.normal([0.0, 0.0, 9.81], 0.5, 3), *rng.normal(0, 0.05, 3)]
        if batch % 10 == 3:
            rows[0, 0] = rows_est.ukf.t  # at the estimate's time: spans no interval
        rows_est.predict_rows(rows)
        for r in rows:
            one_est.predict(ImuSample(float(r[0]), r[1:4].copy(), r[4:7].copy()))
        if batch % 3 == 0:
            p = start.p_W + rng.normal(0, 0.01, 3)
            m = MocapSample(t - 0.004, t, p, start.q_WB, True)
            rows_est.update(m)
            one_est.update(m)
            assert rows_est.last_nis == one_est.last_nis
        a, b = rows_est.estimate(), one_est.estimate()
        assert a.t == b.t and a.tension == b.tension
        for x, y in ((a.body.p_W, b.body.p_W), (a.body.q_WB, b.body.q_WB),
                     (a.body.v_W, b.body.v_W), (a.covariance, b.covariance)):  # fmt: skip
            assert _same(x, y)
        checked += 1
    assert checked == 120 and rows_est.ukf.t == pytest.approx(t)
