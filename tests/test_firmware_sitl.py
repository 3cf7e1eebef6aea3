"""Betaflight SITL in the loop: built (or found) in the cache, read back over MSP, its rate
loop measured on the plant, full missions flown through it (deterministic in lockstep), on
the loopback, and a lost firmware ends a run promptly."""

from __future__ import annotations

import math
import os
import signal
import time

import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.config import load_scenario
from tetherland.firmware import BetaflightSitl, FirmwareInnerLoop, ensure_firmware
from tetherland.firmware.handover import RateLoopGain
from tetherland.firmware.msp import (
    MSP_ATTITUDE,
    MSP_DEBUG,
    MSP_RAW_IMU,
    MspClient,
    attitude,
    debug_values,
    raw_imu,
)
from tetherland.firmware.process import SitlProcess
from tetherland.firmware.step_response import RateStep, rate_step_response
from tetherland.interfaces import Command, ControlMode, ImuSample, Reference, StateEstimate
from tetherland.models.quadrotor import RotorLayout
from tetherland.rotations import rotvec_to_quat
from tetherland.runs import run_mission
from tetherland.state import RigidBodyState

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def scenario():
    return load_scenario("slope50")


@pytest.fixture(scope="module")
def build():
    return ensure_firmware()


def _estimate(q=(1.0, 0.0, 0.0, 0.0)):
    return StateEstimate(0.0, RigidBodyState(np.zeros(3), np.zeros(3), np.array(q, float),
                                             np.zeros(3)))  # fmt: skip


def _query(fw: FirmwareInnerLoop, msp: MspClient, command: int, imu: ImuSample) -> bytes:
    """Send an MSP query and keep stepping (the serial task runs on simulated time)."""
    msp.send(command)
    msp.sock.settimeout(0.002)
    for _ in range(2000):
        fw.step(imu)
        try:
            return msp.receive(command)
        except (TimeoutError, OSError):
            continue
        except Exception as err:  # FirmwareError on the per-read deadline: keep stepping
            if "no MSP answer" not in str(err):
                raise
    raise AssertionError("no MSP answer within 2 s of firmware time")


def _listening(port: int, table: str, within_s: float = 2.0) -> list[str]:
    """Local addresses (hex) bound to ``port`` in /proc/net/<table>.

    The kernel lists its sockets in chunks, not atomically: while other processes open and
    close sockets (the parallel test workers do) one read can skip an entry. Read again until
    the port shows up or ``within_s`` has passed.
    """
    deadline = time.monotonic() + within_s
    while True:
        out = []
        with open(f"/proc/net/{table}") as f:
            next(f)
            for line in f:
                local = line.split()[1]
                addr, p = local.split(":")
                if int(p, 16) == port:
                    out.append(addr)
        if out or time.monotonic() > deadline:
            return out
        time.sleep(0.05)


def test_parallel_instances_bind_distinct_loopback_ports(build):
    with SitlProcess(build.executable, lockstep=True) as a, SitlProcess(build.executable,
                                                                        lockstep=True) as b:
        assert a.state_port != b.state_port and a.cli_port != b.cli_port
        for sitl in (a, b):
            assert sitl.alive()
            assert _listening(sitl.state_port, "udp") == ["0100007F"]  # 127.0.0.1
            assert _listening(sitl.cli_port, "tcp") == ["0100007F"]


def test_the_firmware_reads_the_imu_and_attitude_in_its_own_axes(scenario, build):
    fw = FirmwareInnerLoop(scenario, scenario, build=build)
    fw.start()
    try:
        msp = MspClient(fw.sitl.cli_port)
        # a pure roll rate of 1 rad/s with gravity along z_B, pitched nose down 0.3 rad
        fw.estimate = _estimate(q=rotvec_to_quat(np.array([0.0, 0.3, 0.0])))
        imu = ImuSample(0.0, np.array([0.0, 0.0, GRAVITY]), np.array([1.0, 0.0, 0.0]))
        acc, gyro = raw_imu(_query(fw, msp, MSP_RAW_IMU, imu))
        assert gyro[0] > 0 and gyro[1] == 0 and gyro[2] == 0  # roll only, positive
        assert acc == (0, 0, 256)  # +1 g up, at the virtual accelerometer's 256 per g
        roll, pitch, _ = attitude(_query(fw, msp, MSP_ATTITUDE, imu))
        assert roll == pytest.approx(0.0, abs=0.2)
        assert pitch == pytest.approx(math.degrees(0.3), abs=0.2)  # Betaflight: nose down +
        # pitch and yaw rates come out with their own signs
        imu = ImuSample(0.0, np.array([0.0, 0.0, GRAVITY]), np.array([0.0, 0.5, -0.25]))
        for _ in range(200):  # let the gyro filters settle on the new rate
            fw.step(imu)
        _, gyro2 = raw_imu(_query(fw, msp, MSP_RAW_IMU, imu))
        assert gyro2[0] == 0 and gyro2[1] > 0 and gyro2[2] < 0
        assert gyro2[1] == pytest.approx(-2 * gyro2[2], abs=2)  # 0.5 : -0.25
        msp.close()
    finally:
        fw.stop()


def test_the_firmware_gyro_reads_the_packet_rate(scenario, build):
    # the rate loop's gyro (debug_mode GYRO_FILTERED: deg/s after the filters, steady here)
    # reads the packet's rate; packed at 16.4 LSB per deg/s against the driver's 16.384 it
    # read 0.1 % high (1721 deg/s for 30 rad/s). MSP_RAW_IMU gives the driver's LSB.
    fw = FirmwareInnerLoop(scenario, scenario, build=build)
    fw.start()
    try:
        msp = MspClient(fw.sitl.cli_port)
        omega = np.array([30.0, -12.0, 4.0])  # within the 2000 deg/s range
        imu = ImuSample(0.0, np.array([0.0, 0.0, GRAVITY]), omega)
        for _ in range(100):  # the gyro low-pass settles
            fw.step(imu)
        debug = debug_values(_query(fw, msp, MSP_DEBUG, imu))
        _, raw = raw_imu(_query(fw, msp, MSP_RAW_IMU, imu))
        msp.close()
    finally:
        fw.stop()
    deg = np.degrees(omega)
    assert np.abs(np.array(debug[0:3]) - deg).max() <= 0.5 + 1e-9  # rounded to 1 deg/s
    assert np.abs(np.array(raw) - deg * 2**15 / 2000).max() <= 1.0  # LSB


def test_the_firmware_p_term_is_the_rate_loop_gain_of_the_handover(scenario, build):
    # at the hover throttle, a gyro rate with a zero setpoint: the motor outputs' torque
    # (through the believed rotors) over J is -K e, K the hand-over's model, per axis
    fw = FirmwareInnerLoop(scenario, scenario, build=build)
    fw.start()
    v = scenario.vehicle
    layout = RotorLayout.from_config(v)
    hover = v.mass * GRAVITY
    gain = RateLoopGain.from_config(fw.config, v, fw.throttle_map).at(hover)
    g = np.array([0.0, 0.0, GRAVITY])
    try:
        fw.channels = fw.rc.arming()
        for _ in range(50):
            fw.step(ImuSample(0.0, g, np.zeros(3)))
        assert fw.armed
        fw.channels = fw.rc.channels(np.zeros(3), fw.throttle_map.throttle(hover), True)
        for _ in range(50):
            w = fw.step(ImuSample(0.0, g, np.zeros(3)))
        wrench = layout.wrench(v.thrust_coefficient * w * w)
        # the throttle map through the firmware: the collective within the output's 1 us
        assert wrench[0] == pytest.approx(hover, rel=0.01)
        for axis, e in ((0, 1.0), (1, -1.0), (2, 0.5)):
            omega = np.zeros(3)
            omega[axis] = e
            for _ in range(50):  # the gyro low-pass settles
                w = fw.step(ImuSample(0.0, g, omega))
            alpha = layout.wrench(v.thrust_coefficient * w * w)[1:] / np.asarray(v.inertia)
            assert -alpha[axis] / e == pytest.approx(gain[axis], rel=0.02)
            others = [a for a in range(3) if a != axis]
            assert np.abs(alpha[others]).max() < 0.02 * abs(alpha[axis])
    finally:
        fw.stop()


def test_the_firmware_rate_loop_follows_a_step_like_tetherlands_own(scenario, build):
    # a roll-rate step 2 ms before a radio frame: Betaflight's proportional loop at K = k_w
    # behind the same motors answers like tetherland's own inner loop, later by the radio's
    # wait (2 ms) and at most one more loop (1 ms)
    step = RateStep(start=1.008)
    own = rate_step_response(scenario, step)
    firmware = FirmwareInnerLoop(scenario, scenario, build=build)
    fw = rate_step_response(scenario, step, inner_loop=firmware)
    lag = fw.time_to(0.5) - own.time_to(0.5)
    assert 0.0 < lag <= 0.002 + 0.001
    assert fw.overshoot == pytest.approx(own.overshoot, abs=0.02)  # same gain, same motors
    assert fw.final == pytest.approx(own.final, abs=0.01)
    assert own.overshoot < 0.2 and own.final == pytest.approx(1.0, abs=0.03)


def _drive(scenario, build, seed: int, n: int) -> np.ndarray:
    """Outputs of a fresh firmware over ``n`` noisy samples: arm, hover throttle, a roll
    stick step at 0.3 s."""
    rng = np.random.default_rng(seed)
    fw = FirmwareInnerLoop(scenario, scenario, build=build)
    fw.start()
    outputs = np.empty((n, 4))
    ref = Reference(0.0, mode=ControlMode.FREE_FLIGHT)
    try:
        for k in range(n):
            if k % 2 == 0:
                roll = 0.3 * (k >= 300)
                torque = np.array([roll * 0.015 * 25.2, 0.0, 0.0])  # -> w_cmd = 0.3 rad/s
                fw.setpoint(k * 1e-3, _estimate(), ref,
                            Command(np.zeros(4), thrust=9.81, torque_B=torque))  # fmt: skip
            imu = ImuSample(k * 1e-3, np.array([0.0, 0.0, GRAVITY]) + 0.05 * rng.normal(size=3),
                            0.005 * rng.normal(size=3))  # fmt: skip
            fw.step(imu)
            outputs[k] = fw.outputs
    finally:
        fw.stop()
    return outputs


def test_lockstep_gives_identical_outputs_for_identical_inputs(scenario, build):
    a = _drive(scenario, build, 7, 500)
    b = _drive(scenario, build, 7, 500)
    assert np.array_equal(a, b)
    assert np.any(a[50:] > 0.0)  # armed and flying
    # the roll stick (+x, right wing down) speeds up the left rotors (slots 1, 2: RL, FL)
    left, right = a[350:500, [1, 2]].mean(), a[350:500, [0, 3]].mean()
    assert left > right
    c = _drive(scenario, build, 8, 500)  # other noise, other outputs
    assert not np.array_equal(a, c)


def test_a_killed_firmware_ends_the_mission_within_5_s_with_one_line(scenario):
    holder: dict = {}

    class Watched(BetaflightSitl):
        def __call__(self, truth, belief):
            holder["fw"] = super().__call__(truth, belief)
            return holder["fw"]

    def kill_at_one_second(t, plant):
        if t >= 1.0 and "killed" not in holder:
            os.kill(holder["fw"].sitl.proc.pid, signal.SIGKILL)
            holder["killed"] = time.perf_counter()

    result = run_mission(scenario, seed=0, inner_loop=Watched(),
                         observers=[kill_at_one_second])  # fmt: skip
    elapsed = time.perf_counter() - holder["killed"]
    assert elapsed < 5.0
    summary = result.summary
    assert summary["status"] == "failed" and not summary["success"]
    reason = summary["reason"]
    assert "firmware lost" in reason and "\n" not in reason
    assert result.log.metadata["sim_time_s"] < 1.1


def test_the_full_mission_succeeds_through_the_firmware_and_repeats_exactly(scenario, build):
    # slope50 seed 0 twice, a fresh firmware process each time (one test: under xdist a
    # module fixture would fly them once per worker)
    first, second = (run_mission(scenario, seed=0, inner_loop=BetaflightSitl()) for _ in "ab")
    s = first.summary
    assert s["status"] == "terminated" and s["success"] and not s["aborted"]
    assert all(s["landing"]["conditions"].values()) and len(s["landing"]["conditions"]) == 5
    assert s["takeoff"]["completed"] and s["return"]["completed"] and s["return"]["unhooked"]
    assert [e["kind"] for e in s["hook"]["events"]] == ["ENGAGED", "RELEASED"]
    assert s["provenance"]["inner_loop"]["firmware"] == "betaflight"
    assert first.log.metadata["inner_loop"] == "FirmwareInnerLoop"

    def verdict(result):
        return {k: v for k, v in result.summary.items()
                if "wall" not in k and "real_time" not in k and k != "provenance"}  # fmt: skip

    assert verdict(first) == verdict(second)
    assert np.array_equal(first.log["rotor_speeds"], second.log["rotor_speeds"])
