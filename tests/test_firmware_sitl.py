"""Betaflight SITL in the loop: built (or found) in the cache, read back over MSP,
deterministic in lockstep, on the loopback, and a lost firmware ends a run promptly."""

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
from tetherland.firmware.msp import (
    MSP_ATTITUDE,
    MSP_RAW_IMU,
    MspClient,
    attitude,
    raw_imu,
)
from tetherland.firmware.process import SitlProcess
from tetherland.interfaces import Command, ControlMode, ImuSample, Reference, StateEstimate
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


def _listening(port: int, table: str) -> list[str]:
    """Local addresses (hex) bound to ``port`` in /proc/net/<table>."""
    out = []
    with open(f"/proc/net/{table}") as f:
        next(f)
        for line in f:
            local = line.split()[1]
            addr, p = local.split(":")
            if int(p, 16) == port:
                out.append(addr)
    return out


def test_parallel_instances_bind_distinct_loopback_ports(build):
    with SitlProcess(build.executable, lockstep=True) as a, SitlProcess(build.executable,
                                                                        lockstep=True) as b:
        assert a.state_port != b.state_port and a.cli_port != b.cli_port
        for sitl in (a, b):
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
        assert acc[0] == 0 and acc[1] == 0 and acc[2] > 0  # +1 g up
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


@pytest.mark.xfail(strict=True, reason="open: the SITL's gyro reads 16.4x the packet's rate "
                   "(sitl.c packs 16.4 LSB per deg/s, the virtual gyro scales by 1)")
def test_the_firmware_gyro_reads_the_packet_rate_in_deg_per_s(scenario, build):
    fw = FirmwareInnerLoop(scenario, scenario, build=build)
    fw.start()
    try:
        msp = MspClient(fw.sitl.cli_port)
        imu = ImuSample(0.0, np.array([0.0, 0.0, GRAVITY]), np.array([1.0, 0.0, 0.0]))
        _, gyro = raw_imu(_query(fw, msp, MSP_RAW_IMU, imu))
        msp.close()
    finally:
        fw.stop()
    assert gyro[0] == pytest.approx(math.degrees(1.0), abs=1.0)


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


def test_the_same_seed_gives_the_same_verdict_through_the_firmware(scenario):
    def verdict():
        s = run_mission(scenario, seed=3, inner_loop=BetaflightSitl()).summary
        return {k: v for k, v in s.items() if "wall" not in k and "real_time" not in k
                and k != "provenance"}  # fmt: skip

    assert verdict() == verdict()
