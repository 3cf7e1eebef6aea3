"""The multi-rate runner: schedule, interfaces, determinism, log round trip."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.config import load_scenario
from tetherland.control import FreeFlightController
from tetherland.errors import ConfigError
from tetherland.estimation import UkfEstimator
from tetherland.interfaces import (
    Command,
    Controller,
    ControlMode,
    Estimator,
    EventRecord,
    ImuBatchAware,
    ImuSample,
    MocapSample,
    Reference,
    ReferenceSource,
    StateEstimate,
)
from tetherland.randomness import RandomSource
from tetherland.sim.baselines import ConstantReference, ConstantSpeedController, TruthEstimator
from tetherland.sim.log import RunStatus, SimLog
from tetherland.sim.plant import Plant
from tetherland.sim.runner import Runner, Schedule
from tetherland.state import RigidBodyState


@pytest.fixture(scope="module")
def scenario():
    # out of ground effect and without rotor drag: hovering settled rotors hold still
    # (the aero effects are tested in test_sim_aero.py)
    return load_scenario(
        "slope50",
        [
            "sensors.mocap.dropout_rate=1.0",
            "sensors.mocap.dropout_duration=0.05",
            "aero.ground_effect=false",
            "aero.rotor_drag=[0, 0]",
        ],
    )


def airborne(runner: Runner) -> RigidBodyState:
    s = runner.plant.start_state()
    return RigidBodyState.at_rest(s.p_W + np.array([0.0, 0.0, 1.0]), s.q_WB)


class Recorder:
    """Estimator that records what it is given and echoes the mocap pose."""

    def __init__(self) -> None:
        self.imu: list[ImuSample] = []
        self.mocap: list[tuple[float, MocapSample]] = []
        self.commands: list[tuple[float, Command]] = []
        self.last = RigidBodyState.at_rest(np.zeros(3))

    def predict(self, imu: ImuSample) -> None:
        self.imu.append(imu)

    def update(self, mocap: MocapSample) -> None:
        self.mocap.append((self.imu[-1].t, mocap))

    def command_sent(self, t: float, command: Command) -> None:
        self.commands.append((t, command))

    def estimate(self) -> StateEstimate:
        return StateEstimate(t=self.imu[-1].t, body=self.last)


def test_baselines_implement_the_interfaces():
    assert isinstance(TruthEstimator(lambda: None), Estimator)  # type: ignore[arg-type]
    assert isinstance(ConstantSpeedController(np.zeros(4)), Controller)
    assert isinstance(ConstantReference(), ReferenceSource)
    assert isinstance(Recorder(), Estimator)
    with pytest.raises(TypeError, match="Controller"):
        Runner(load_scenario("flat"), object())  # type: ignore[arg-type]


def test_schedule_is_integer_and_exact(scenario):
    sched = Schedule.from_scenario(scenario)
    assert (sched.steps_per_second, sched.imu_every, sched.control_every) == (1000, 1, 2)
    ticks = [sched.mocap_tick(j) for j in range(121)]
    assert ticks[0] == 0 and ticks[120] == 1000  # exactly 120 samples per second
    assert set(np.diff(ticks)) == {8, 9}
    assert sched.mocap_latency_ticks == 5
    with pytest.raises(ConfigError, match=r"controller\.rate_hz"):
        Schedule.from_scenario(load_scenario("flat", ["controller.rate_hz=300"]))


def test_rates_latency_and_command_delivery(scenario):
    ctrl = ConstantSpeedController.hover(scenario.vehicle)
    est = Recorder()
    runner = Runner(scenario, ctrl, estimator=est, seed=3)
    log = runner.run(
        1.0, initial_state=airborne(runner), rotor_speeds=ctrl.update(0, None, None).rotor_speeds
    )  # type: ignore[arg-type]
    assert log.status is RunStatus.COMPLETED
    assert len(log) == 500 and np.allclose(np.diff(log.t), 0.002)
    assert len(est.imu) == 1000
    np.testing.assert_allclose([s.t for s in est.imu], np.arange(1000) * 0.001)
    assert len(est.mocap) == 120  # taken at ticks 0, 9, 17, ..., 992; the last delivered at 997
    for t_received, m in est.mocap:
        assert m.t_delivered == pytest.approx(m.t_measured + 0.005)
        assert t_received == pytest.approx(m.t_delivered)  # handed over on its tick
    assert len(est.commands) == 500 and est.commands[0][0] == pytest.approx(0.001)
    # truth columns: hover with settled rotors does not move
    np.testing.assert_allclose(log["p_W"] - log["p_W"][0], 0.0, atol=1e-9)
    np.testing.assert_allclose(log["specific_force_B"], [[0, 0, GRAVITY]] * 500, atol=1e-9)
    assert np.all(log["mode"] == int(ControlMode.FREE_FLIGHT))
    assert np.isnan(log["est_gyro_bias_B"]).all()


def test_runs_are_deterministic_for_a_seed_and_round_trip(scenario, tmp_path):
    ctrl = ConstantSpeedController.hover(scenario.vehicle, thrust=1.02 * GRAVITY)
    runner = Runner(scenario, ctrl, seed=11)
    start = airborne(runner)
    a = runner.run(0.6, initial_state=start)
    b = Runner(scenario, ctrl, seed=11).run(0.6, initial_state=start)
    c = runner.run(0.6, initial_state=start, random=RandomSource(12))
    assert np.array_equal(a.matrix, b.matrix, equal_nan=True)
    assert not np.array_equal(a["imu_omega_B"], c["imu_omega_B"], equal_nan=True)
    assert np.isfinite(a["mocap_p_W"][-1]).all() or a["mocap_valid"][-1] == 0
    path = a.save(tmp_path / "run.npz")
    loaded = SimLog.load(path)
    assert loaded.names == a.names
    # the file holds every column at its stated precision, nothing less
    assert np.array_equal(loaded.matrix, a.at_storage_precision().matrix, equal_nan=True)
    np.testing.assert_array_equal(loaded.t, a.t)  # times are exact
    assert np.array_equal(loaded["hook"], a["hook"]) and np.array_equal(
        loaded["phase"], a["phase"]
    )
    for col in a.columns:
        finite = np.isfinite(a[col.name])
        err = np.abs(loaded[col.name][finite] - a[col.name][finite])
        assert np.all(err <= col.storage.relative_error * np.abs(a[col.name][finite])), col.name
    assert loaded.metadata["provenance"]["seed"] == 11
    assert c.metadata["provenance"]["seed"] == 12  # the seed of the source it drew from
    assert loaded.metadata["provenance"]["scenario"]["name"] == "slope50"
    assert loaded.status is RunStatus.COMPLETED


def test_truth_estimator_and_log_agree_with_the_plant():
    sc = load_scenario("slope50")
    runner = Runner(sc, ConstantSpeedController.motors_off(), seed=0)
    log = runner.run(0.5, initial_state=runner.plant.landed_state(), cable_engaged=True)
    np.testing.assert_allclose(log["est_p_W"], log["p_W"])
    np.testing.assert_allclose(log["est_tension"], log["tension"])
    np.testing.assert_allclose(log["est_link"][:, 0], log["link_phi"], atol=1e-12)
    np.testing.assert_allclose(
        log["link_phi"][-1], runner.plant.layout.geometry.phi_star, atol=2e-3
    )
    assert np.all(log["hook"] == 1)


class Terminator:
    def __init__(self) -> None:
        self.events: list[EventRecord] = []

    def reference(self, t: float, estimate: StateEstimate) -> Reference:
        done = t >= 0.1
        if done and not self.events:
            self.events.append(EventRecord(t, "mission", "done", "test over"))
        return Reference(t=t, mode=ControlMode.MOTORS_OFF, phase=7, terminate=done)


class Exploding:
    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        from tetherland.errors import SingularityError

        if t > 0.05:
            raise SingularityError("cos(delta) = 0")
        return Command(rotor_speeds=np.zeros(4))


def test_termination_failure_and_events_end_the_run_cleanly():
    sc = load_scenario("flat")
    log = Runner(sc, ConstantSpeedController.motors_off(), reference=Terminator()).run(1.0)
    assert log.status is RunStatus.TERMINATED and log.t[-1] == pytest.approx(0.1)
    assert np.all(log["phase"] == 7)
    assert [e["kind"] for e in log.events] == ["done"]
    log = Runner(sc, Exploding()).run(1.0)
    assert log.status is RunStatus.FAILED and "cos(delta)" in log.metadata["message"]
    assert len(log) == 26


def test_diagnostics_are_logged():
    class Diag:
        def update(self, t, estimate, reference):
            return Command(rotor_speeds=np.zeros(4), diagnostics={"err": t})

    log = Runner(load_scenario("flat"), Diag(), diagnostic_keys=("err", "absent")).run(0.02)
    np.testing.assert_allclose(log["diag.err"], log.t)
    assert np.isnan(log["diag.absent"]).all()
    assert math.isnan(log["cmd_thrust"][0])


class _OneByOne:
    """Wraps an estimator and hides its ``predict_rows``: the runner hands it one
    ``ImuSample`` per IMU tick (the plain path)."""

    def __init__(self, inner: UkfEstimator) -> None:
        self.inner, self.samples = inner, 0

    def predict(self, imu: ImuSample) -> None:
        self.samples += 1
        self.inner.predict(imu)

    def update(self, mocap: MocapSample) -> None:
        self.inner.update(mocap)

    def estimate(self) -> StateEstimate:
        return self.inner.estimate()

    def command_sent(self, t: float, command: Command) -> None:
        self.inner.command_sent(t, command)


class _Rows(UkfEstimator):
    """The estimator, counting the rows handed over."""

    rows = 0

    def predict_rows(self, rows: np.ndarray) -> None:
        self.rows += len(rows)
        super().predict_rows(rows)


def test_imu_rows_and_one_sample_at_a_time_fly_the_same_bits():
    # the runner's hand-over of the IMU samples as rows (an ImuBatchAware estimator) and one
    # ImuSample per IMU tick give the same run, bit for bit: a hover under the free-flight
    # controller with the estimate in the loop, motion capture with dropouts fused
    sc = load_scenario(
        "slope50", ["sensors.mocap.dropout_rate=5.0", "sensors.mocap.dropout_duration=0.05"]
    )
    start = Plant(sc).start_state()
    hover = RigidBodyState.at_rest(start.p_W + np.array([0.0, 0.0, 1.0]), start.q_WB)
    logs, estimators = [], []
    for wrap in (False, True):
        ukf = _Rows(sc, hover, 0.0) if not wrap else UkfEstimator(sc, hover, 0.0)
        est = _OneByOne(ukf) if wrap else ukf
        assert isinstance(est, ImuBatchAware) is not wrap
        ref = ConstantReference(p_W=hover.p_W + np.array([0.2, 0.0, 0.1]))
        runner = Runner(sc, FreeFlightController(sc), estimator=est, reference=ref, seed=4)
        logs.append(runner.run(2.0, initial_state=hover))
        estimators.append(est)
    assert np.array_equal(logs[0].matrix, logs[1].matrix, equal_nan=True)
    n_imu = round(2.0 * sc.sensors.imu.rate_hz)
    assert estimators[0].rows == estimators[1].samples == n_imu
    assert np.any(logs[0]["mocap_valid"] == 0) and np.any(logs[0]["mocap_valid"] == 1)
