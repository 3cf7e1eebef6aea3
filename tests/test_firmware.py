"""The firmware bridge's pure parts: packets, frames, motor order, throttle path, sticks,
and the rate hand-over (no firmware process)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.config import load_scenario
from tetherland.control.free_flight import FreeFlightController
from tetherland.firmware.configure import FirmwareConfig
from tetherland.firmware.frames import (
    fdm_packet,
    firmware_accelerometer,
    firmware_euler,
    firmware_gyro,
)
from tetherland.firmware.handover import RateHandover, RateLoopGain
from tetherland.firmware.motors import Esc, MotorOrder, ThrottleMap
from tetherland.firmware.packets import FDM, RC, SERVO, FdmPacket, RcPacket, unpack_servo
from tetherland.firmware.rc import RcMap
from tetherland.interfaces import ImuSample, Reference, StateEstimate
from tetherland.models.quadrotor import RotorLayout
from tetherland.rotations import rotvec_to_quat
from tetherland.state import RigidBodyState


@pytest.fixture(scope="module")
def scenario():
    return load_scenario("slope50")


def _estimate(q=(1.0, 0.0, 0.0, 0.0), w=(0.0, 0.0, 0.0), p=(0.0, 0.0, 0.0), v=(0.0, 0.0, 0.0)):
    body = RigidBodyState(np.array(p, float), np.array(v, float), np.array(q, float),
                          np.array(w, float))  # fmt: skip
    return StateEstimate(0.0, body)


def test_packet_sizes_match_the_sitl_structs():
    # fdm_packet: 18 doubles; rc_packet: a double and 16 uint16; servo_packet: 4 floats
    assert (FDM.size, RC.size, SERVO.size) == (18 * 8, 8 + 16 * 2, 4 * 4)
    pkt = FdmPacket(1.5, np.array([1.0, 2, 3]), np.array([4.0, 5, 6]), np.array([1.0, 0, 0, 0]),
                    np.array([7.0, 8, 9]), np.array([10.0, 11, 12]), 101325.0)  # fmt: skip
    back = FdmPacket.unpack(pkt.pack())
    assert back.timestamp == 1.5 and back.pressure == 101325.0
    assert np.array_equal(back.accel_xyz, [4.0, 5, 6])
    assert np.array_equal(back.position_xyz, [10.0, 11, 12])
    rc = RcPacket(0.01, tuple(range(1000, 1016)))
    assert RcPacket.unpack(rc.pack()) == rc
    assert np.allclose(unpack_servo(SERVO.pack(0.1, 0.2, 0.3, 0.4)), [0.1, 0.2, 0.3, 0.4])
    with pytest.raises(ValueError):
        RcPacket(0.0, (1500,) * 15)


def test_a_pure_roll_rate_reaches_the_firmware_gyro_as_its_roll_axis():
    # FLU body: +omega_x rolls right wing down, Betaflight's positive roll.
    imu = ImuSample(0.0, np.array([0.0, 0.0, GRAVITY]), np.array([0.7, 0.0, 0.0]))
    pkt = fdm_packet(0.0, imu, None)
    assert np.allclose(pkt.omega_rpy, [0.7, 0.0, 0.0])  # FRD keeps x
    assert np.allclose(firmware_gyro(pkt), [0.7, 0.0, 0.0])


def test_pitch_and_yaw_rates_flip_into_frd_and_back():
    imu = ImuSample(0.0, np.zeros(3), np.array([0.0, 0.3, -0.2]))
    pkt = fdm_packet(0.0, imu, None)
    assert np.allclose(pkt.omega_rpy, [0.0, -0.3, 0.2])  # FRD: y right, z down
    assert np.allclose(firmware_gyro(pkt), imu.omega_B)  # the SITL flips them back


def test_gravity_on_a_level_vehicle_reads_plus_one_g_up():
    imu = ImuSample(0.0, np.array([0.0, 0.0, GRAVITY]), np.zeros(3))
    pkt = fdm_packet(0.0, imu, None)
    assert np.allclose(firmware_accelerometer(pkt), [0.0, 0.0, GRAVITY])
    # Betaflight's int16 scale: 256 per g (ACC_SCALE), z positive
    assert round(firmware_accelerometer(pkt)[2] * 256 / 9.80665) == 256


@pytest.mark.parametrize(
    ("axis", "angle", "expected"),
    [
        ((1.0, 0.0, 0.0), 0.3, (0.3, 0.0, 0.0)),  # right wing down: roll +
        ((0.0, 1.0, 0.0), 0.2, (0.0, 0.2, 0.0)),  # about y_left: nose down, pitch +
        ((0.0, 0.0, 1.0), -0.5, (0.0, 0.0, 0.5)),  # clockwise from above: yaw +
    ],
)
def test_attitude_comes_out_in_betaflight_euler_conventions(axis, angle, expected):
    q = rotvec_to_quat(angle * np.array(axis))
    pkt = fdm_packet(0.0, ImuSample(0.0, np.zeros(3), np.zeros(3)), _estimate(q=q))
    euler = firmware_euler(pkt)
    euler[2] = math.remainder(euler[2], 2 * math.pi)
    assert np.allclose(euler, expected, atol=1e-12)


def test_motor_order_maps_betaflight_quadx_onto_the_rotor_layout(scenario):
    order = MotorOrder.from_vehicle(scenario.vehicle)
    layout = RotorLayout.from_config(scenario.vehicle)
    # slot s carries Betaflight motor m with SITL_SLOT_OF_MOTOR[m] = s: RR, FR, RL, FL
    expected_xy = {3: (-1, -1), 0: (1, -1), 1: (-1, 1), 2: (1, 1)}
    for slot, rotor in enumerate(order.rotor_of_slot):
        assert tuple(np.sign(layout.positions_B[rotor, :2])) == expected_xy[slot]
    # default props: motor 1 (rear right) turns clockwise, its drag yaws the body +z
    assert layout.spins[order.rotor_of_slot[3]] == 1.0 and not order.yaw_motors_reversed
    esc = Esc.from_vehicle(scenario.vehicle)
    w = esc.rotor_speeds(np.array([0.1, 0.2, 0.3, 0.4]))
    assert np.allclose(w[list(order.rotor_of_slot)], esc.w_max * np.array([0.1, 0.2, 0.3, 0.4]))


def test_throttle_map_inverts_the_firmware_throttle_path(scenario):
    v = scenario.vehicle
    cfg = FirmwareConfig.load()
    tm = ThrottleMap(v.f_max, cfg.number("motor_idle") / 1e4, cfg.number("thrust_linear") / 100)
    # idle is the rotor model's f_min; full throttle is f_max on every rotor
    assert tm.collective(0.0) == pytest.approx(4 * v.f_min, rel=1e-3)
    assert tm.collective(1.0) == pytest.approx(4 * v.f_max)
    hover = v.mass * GRAVITY
    t = tm.throttle(hover)
    # Betaflight's chain by hand at that stick: compensation, linearisation, endpoints
    k = 0.8
    t_c = t / (1 + (k - k * k / 2) * (1 - t) ** 2)
    u = tm.idle + (1 - tm.idle) * t_c * (1 + k * (1 - t_c) ** 2)
    assert 4 * v.f_max * u**2 == pytest.approx(hover, rel=1e-4)
    # without linearisation the same output needs a higher stick (thrust is quadratic)
    assert ThrottleMap(v.f_max, tm.idle, 0.0).throttle(hover) > t


def test_sticks_are_linear_in_rate_and_yaw_is_inverted():
    rc = RcMap.from_config(FirmwareConfig.load())
    assert np.allclose(np.degrees(rc.max_rate), [300.0, 300.0, 200.0])
    ch = rc.channels(np.array([math.radians(150), -math.radians(30), math.radians(100)]), 0.5,
                     True)  # fmt: skip
    assert ch[0:5] == (1750, 1450, 1500, 1250, 1800)
    assert np.allclose(rc.rates(ch), [math.radians(150), -math.radians(30), math.radians(100)])
    assert rc.channels(np.full(3, 100.0), 2.0, False)[0:5] == (2000, 2000, 2000, 1000, 1000)


def _throttle_map(vehicle, config):
    return ThrottleMap(vehicle.f_max, config.number("motor_idle") / 1e4,
                       config.number("thrust_linear") / 100)  # fmt: skip


def test_mix_slope_is_the_derivative_of_the_throttle_path(scenario):
    v = scenario.vehicle
    tm = _throttle_map(v, FirmwareConfig.load())
    k, idle = tm.thrust_linear, tm.idle
    for thrust in (4.0, v.mass * GRAVITY, 16.0):
        t = tm.throttle(thrust)
        x = t / (1 + (k - k * k / 2) * (1 - t) ** 2)  # compensated throttle: the mix adds here

        def rotor_thrust(m, x=x):
            y = x + m
            return v.f_max * (idle + (1 - idle) * y * (1 + k * (1 - y) ** 2)) ** 2

        h = 1e-6
        numeric = (rotor_thrust(h) - rotor_thrust(-h)) / (2 * h)
        assert tm.mix_slope(thrust) == pytest.approx(numeric, rel=1e-6)


def test_rate_loop_gain_of_the_default_p_terms_is_the_attitude_law_rate_gain(scenario):
    # K = 0.032029 P (180/pi)/1000 (df/dm) sum|lever| / J, by hand for the x layout
    v = scenario.vehicle
    cfg = FirmwareConfig.load()
    tm = _throttle_map(v, cfg)
    hover = v.mass * GRAVITY
    gain = RateLoopGain.from_config(cfg, v, tm).at(hover)
    slope = tm.mix_slope(hover)
    arm = 4 * v.arm_length / math.sqrt(2)
    per_p = 0.032029 * math.degrees(1.0) / 1000 * slope
    assert gain[0] == pytest.approx(per_p * 60 * arm / v.inertia[0], rel=1e-12)
    assert gain[2] == pytest.approx(per_p * 250 * 4 * v.drag_coefficient / v.inertia[2],
                                    rel=1e-12)  # fmt: skip
    # the default P puts K at k_w of the attitude law on roll and pitch, within 1 %
    g = scenario.controller.free_flight
    k_w = 2 * g.attitude_damping * g.attitude_frequency
    assert gain[0] == gain[1] == pytest.approx(k_w, rel=0.01)


def test_rate_handover_sends_the_rate_whose_error_is_the_commanded_acceleration(scenario):
    # free flight, tilted 0.2 rad about x, turning: the P loop's alpha = K (w_cmd - w_gyro)
    # must be the controller's alpha, the gyro reading w plus the gyro bias
    cfg = FirmwareConfig.load()
    ctrl = FreeFlightController(scenario)
    q = rotvec_to_quat(np.array([0.2, 0.0, 0.0]))
    est = _estimate(q=q, w=(0.3, -0.1, 0.05))
    bias = np.array([0.01, -0.02, 0.005])
    est = StateEstimate(0.0, est.body, gyro_bias_B=bias)
    cmd = ctrl.update(0.0, est, Reference(0.0, p_W=np.zeros((3, 3))))
    tm = _throttle_map(scenario.vehicle, cfg)
    rates = RateHandover(scenario, cfg, tm).rates(est, cmd)
    J = np.asarray(scenario.vehicle.inertia)
    w = est.body.omega_B
    alpha = (cmd.torque_B - np.cross(w, J * w)) / J
    K = RateLoopGain.from_config(cfg, scenario.vehicle, tm).at(cmd.thrust)
    assert np.allclose(K * (rates - (w + bias)), alpha, rtol=1e-12, atol=1e-12)
    # the measured rate cancels: the roll rate sent is the attitude law's -(k_R/K) e_R,x
    g = scenario.controller.free_flight
    assert cmd.diagnostics["saturation"] == 0.0
    assert rates[0] - bias[0] == pytest.approx(
        -g.attitude_frequency**2 / K[0] * math.sin(0.2), rel=0.05
    )


@pytest.mark.parametrize("setting", ["i_roll", "d_pitch", "f_yaw", "d_max_roll"])
def test_rate_handover_refuses_a_rate_loop_with_more_than_a_p_term(scenario, setting):
    cfg = FirmwareConfig.load().with_settings(**{setting: 10})
    with pytest.raises(ValueError, match=f"set {setting} = 0"):
        RateHandover(scenario, cfg, _throttle_map(scenario.vehicle, cfg))


def test_config_with_settings_replaces_and_appends_set_commands():
    cfg = FirmwareConfig.load()
    changed = cfg.with_settings(p_roll=70, rc_smoothing="ON")
    assert changed.number("p_roll") == 70 and changed.settings["rc_smoothing"] == "ON"
    assert "set p_roll = 70" in changed.commands and "set p_roll = 60" not in changed.commands
    assert len(changed.commands) == len(cfg.commands)  # both existed: replaced in place
    assert changed.with_settings(yaw_lowpass_hz=50).commands[-1] == "set yaw_lowpass_hz = 50"
    assert changed.key() != cfg.key()
