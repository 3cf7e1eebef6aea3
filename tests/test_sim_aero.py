"""``[aero]`` in the MuJoCo plant: thrust measured from MuJoCo's accelerations near surfaces."""

from __future__ import annotations

import copy
import math

import mujoco
import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.config import load_scenario, with_overrides
from tetherland.models.airframe import PROP_HEIGHT, PROP_RADIUS_FRACTION
from tetherland.rotations import rotmat_to_quat
from tetherland.sim.mjcf import SENSOR_SLICES
from tetherland.sim.plant import Plant
from tetherland.state import RigidBodyState

OFF = ["aero.ground_effect=false", "aero.rotor_drag=[0, 0]"]


def hover_speed(sc) -> float:
    return math.sqrt(sc.vehicle.mass * GRAVITY / 4 / sc.vehicle.thrust_coefficient)


def free_plant(sc) -> Plant:
    """A plant whose vehicle touches nothing (contacts off): only rotors and gravity act."""
    plant = Plant(sc)
    plant.model.opt.disableflags |= int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
    return plant


def measured_force_B(plant: Plant, state: RigidBodyState, w: float) -> np.ndarray:
    """m times the accelerometer's specific force over one step from ``state`` [N]."""
    plant.reset(state, rotor_speeds=np.full(4, w))
    plant.step(1)
    return plant.scenario.vehicle.mass * plant.sensordata[SENSOR_SLICES["accelerometer"]].copy()


def cb(z_over_R: float) -> float:
    return 1.0 / (1.0 - (1.0 / (4.0 * z_over_R)) ** 2)


def test_thrust_over_a_flat_surface_follows_cheeseman_bennett():
    sc = load_scenario("flat")
    plant = free_plant(sc)
    R = PROP_RADIUS_FRACTION * sc.vehicle.arm_length
    w = hover_speed(sc)
    f_oge = 4 * sc.vehicle.thrust_coefficient * w * w
    for z_over_R in (0.6, 0.8, 1.0, 1.5, 2.0, 3.0, 5.0, 10.0, 15.0):
        # rotor disks (PROP_HEIGHT above the centre of mass) at z above the surface
        p = np.array([0.0, 0.0, z_over_R * R - PROP_HEIGHT])
        thrust = measured_force_B(plant, RigidBodyState.at_rest(p), w)[2]
        if z_over_R <= 5.0:
            assert thrust / f_oge == pytest.approx(cb(z_over_R), rel=0.02)
            assert thrust / f_oge - 1.0 == pytest.approx(cb(z_over_R) - 1.0, rel=0.02)
        else:
            assert 0.0 < thrust / f_oge - 1.0 < 1e-3


def test_a_tilted_vehicle_over_a_surface_gets_a_moment_from_its_lower_rotors():
    sc = load_scenario("flat")
    plant = free_plant(sc)
    R = PROP_RADIUS_FRACTION * sc.vehicle.arm_length
    w = hover_speed(sc)
    c_f, L = sc.vehicle.thrust_coefficient, sc.vehicle.arm_length
    roll = 0.2
    c, s = math.cos(roll), math.sin(roll)
    R_WB = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    p = np.array([0.0, 0.0, 1.2 * R])
    plant.reset(RigidBodyState.at_rest(p, rotmat_to_quat(R_WB)), rotor_speeds=np.full(4, w))
    plant.step(1)
    J = np.asarray(sc.vehicle.inertia)
    tau_x = J[0] * plant.data.qacc[3]  # from MuJoCo's angular acceleration, at rest
    # by hand: rotors at y_B = +-L/sqrt(2); rotor i's disk centre r_i + PROP_HEIGHT e3 and
    # its axis z_B; over the plane z = 0 a level-distance ray from each disk point along
    # -z_B travels (height) / cos(roll); the lower rotors (y_B < 0 with roll > 0) push harder
    from tetherland.models.aero import disk_samples, ground_factor

    samples = disk_samples(3, 8) * R
    tau = 0.0
    for y_B in (L / math.sqrt(2), -L / math.sqrt(2)):
        for x_B in (L / math.sqrt(2), -L / math.sqrt(2)):
            pts_B = np.column_stack(
                (x_B + samples[:, 0], y_B + samples[:, 1], np.full(len(samples), PROP_HEIGHT))
            )
            heights = (p + pts_B @ R_WB.T)[:, 2]
            k = float(np.mean(ground_factor(heights / c, R)))
            tau += y_B * c_f * w * w * k
    # (the spins' yaw torques do not act about x_B)
    assert tau_x == pytest.approx(tau, rel=1e-6)
    assert tau_x < 0.0  # rolling back toward level: the low side (y_B < 0) pushes harder


def test_a_rotor_half_over_the_edge_gets_the_mean_of_both_halves():
    # flat surface patch |x|, |y| <= e at z = 0, ground plane H below: a level vehicle with
    # the disk centres of rotors 0 and 3 over the edge x = e
    H = 1.5
    sc = load_scenario("flat", [f"sim.ground_z={-H}"])
    plant = free_plant(sc)
    R = PROP_RADIUS_FRACTION * sc.vehicle.arm_length
    e, L = sc.surface.extent, sc.vehicle.arm_length
    z = 1.0 * R
    p = np.array([e - L / math.sqrt(2), 0.0, z - PROP_HEIGHT])
    w = hover_speed(sc)
    plant.reset(RigidBodyState.at_rest(p), rotor_speeds=np.full(4, w))
    plant.step(1)
    acting = plant.data.actuator_force[0:4] / plant.model.actuator_gear[0:4, 2]
    f0 = sc.vehicle.thrust_coefficient * w * w
    half = 0.5 * (cb(z / R) + cb((H + z) / R))  # half over the patch, half over the ground
    np.testing.assert_allclose(acting / f0, [half, cb(z / R), cb(z / R), half], rtol=1e-12)
    # and MuJoCo's total thrust is their sum
    total = measured_force_B(plant, RigidBodyState.at_rest(p), w)[2]
    assert total == pytest.approx(f0 * (2 * half + 2 * cb(z / R)), rel=1e-9)


def test_over_a_pipe_the_thrust_follows_the_covered_part_of_each_disk():
    # a horizontal pipe (slope 0) of radius r along x_S with its top line through the
    # origin; a level vehicle with x_B along the pipe, centred over the top line: rotors at
    # y = +-L/sqrt(2) lie beside the line, partly over the pipe's flank
    sc = load_scenario("pipe60", ["surface.slope_deg=0", "sim.ground_z=-3"])
    plant = free_plant(sc)
    geo = plant.layout.geometry.surface
    R_WB = geo.R_WS  # x_B along the pipe axis, z_B up
    r = sc.surface.pipe_radius
    R = PROP_RADIUS_FRACTION * sc.vehicle.arm_length
    L = sc.vehicle.arm_length
    h = 0.08  # disks 8 cm above the top line
    p = geo.origin + np.array([0.0, 0.0, h - PROP_HEIGHT])
    w = hover_speed(sc)
    total = measured_force_B(plant, RigidBodyState.at_rest(p, rotmat_to_quat(R_WB)), w)[2]
    f0 = sc.vehicle.thrust_coefficient * w * w
    # by hand: the area average over each disk of the factor at that point's depth to the
    # cylinder, h + r - sqrt(r^2 - y^2) for |y| < r, else to the ground (3 m + h below)
    n = 600
    rho = (np.arange(n) + 0.5) / n * R
    th = (np.arange(n) + 0.5) / n * 2 * math.pi
    RR, TT = np.meshgrid(rho, th, indexing="ij")
    y = L / math.sqrt(2) + RR * np.sin(TT)
    z_top = geo.origin[2]
    depth = np.where(
        np.abs(y) < r, h + r - np.sqrt(np.maximum(r * r - y * y, 0.0)), z_top + 3.0 + h
    )
    k_exact = float(np.sum(cb(depth / R) * RR) / np.sum(RR))
    k = total / (4 * f0)  # the four rotors are alike by symmetry
    assert 1.0 < k < cb(h / R)  # less than a full plane at the top line's height
    assert abs(k - k_exact) < 0.1 * (k_exact - 1.0)  # 24 samples per disk: within 10 %


def test_rotor_drag_opposes_the_air_velocity_in_the_rotor_plane():
    sc = load_scenario("flat", ["aero.ground_effect=false", "aero.rotor_drag=[0.4, 0.3]"])
    plant = free_plant(sc)
    w = hover_speed(sc)
    c, s = math.cos(0.3), math.sin(0.3)
    R_WB = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])  # pitched
    v_W = np.array([1.0, -0.5, 0.4])
    state = RigidBodyState(
        p_W=np.array([0.0, 0.0, 50.0]), v_W=v_W, q_WB=rotmat_to_quat(R_WB), omega_B=np.zeros(3)
    )
    F_B = measured_force_B(plant, state, w)
    f_R = 4 * sc.vehicle.thrust_coefficient * w * w
    v_B = R_WB.T @ v_W
    np.testing.assert_allclose(F_B, [-0.4 * v_B[0], -0.3 * v_B[1], f_R], rtol=1e-9, atol=1e-12)
    assert (R_WB @ (F_B - [0, 0, f_R])) @ v_W < 0.0
    plant.reset(state, rotor_speeds=np.full(4, w))  # the logged force at the same state
    np.testing.assert_allclose(plant.aero_force, R_WB @ (F_B - [0, 0, f_R]), atol=1e-12)


def test_aero_off_is_the_plain_plant_bit_for_bit():
    # the plain plant: ctrl = c_f wbar^2 from the exact motor lag, nothing else applied;
    # drive bare MuJoCo that way and compare every step bit for bit
    sc = load_scenario("slope50", OFF)
    plant = Plant(sc)
    assert plant.aero is None
    fresh = mujoco.MjModel.from_xml_string(plant.xml)
    np.testing.assert_array_equal(fresh.actuator_ctrlrange, plant.model.actuator_ctrlrange)
    plant.reset(plant.start_state())
    ref_model = copy.deepcopy(plant.model)  # the cable disengaged as the plant has it
    ref = mujoco.MjData(ref_model)
    ref.qpos[:] = plant.data.qpos
    v = sc.vehicle
    tau, dt = v.motor_time_constant, plant.dt
    a = math.exp(-dt / tau)
    b = tau * (1 - a) / dt
    w = np.zeros(4)
    rng = np.random.default_rng(0)
    for k in range(400):
        if k % 2 == 0:
            cmd = rng.uniform(0.9, 1.1, 4) * hover_speed(sc) * 1.1
            plant.command(cmd)
        mean = cmd + (w - cmd) * b
        ref.ctrl[0:4] = v.thrust_coefficient * mean * mean
        mujoco.mj_step(ref_model, ref)
        w = cmd + (w - cmd) * a
        plant.step(1)
        np.testing.assert_array_equal(plant.data.qpos[:7], ref.qpos[:7])
        np.testing.assert_array_equal(plant.data.qvel[:6], ref.qvel[:6])
    np.testing.assert_array_equal(plant.data.qfrc_applied, 0.0)
    np.testing.assert_array_equal(plant.surface_factors, 1.0)
    np.testing.assert_array_equal(plant.aero_force, 0.0)


def test_aero_on_raises_the_actuator_range_by_the_bound():
    on, off = Plant(load_scenario("slope50")), Plant(load_scenario("slope50", OFF))
    f_max = load_scenario("slope50").vehicle.f_max
    assert off.model.actuator_ctrlrange[0, 1] == f_max
    assert on.model.actuator_ctrlrange[0, 1] == pytest.approx(f_max * 4 / 3 * 4 / 3)


def test_logged_thrusts_are_the_acting_thrusts():
    sc = with_overrides(load_scenario("slope50"), ["aero.rotor_drag=[0, 0]"])
    plant = Plant(sc)
    w = hover_speed(sc)
    plant.reset(plant.landed_state(), rotor_speeds=np.full(4, w))
    row = np.empty(15)
    plant.rotor_state_into(row)
    f0 = sc.vehicle.thrust_coefficient * w * w
    np.testing.assert_allclose(row[4:8], f0 * row[8:12], rtol=1e-15)
    assert np.all(row[8:12] > 1.0)
    plant.step(1)  # the thrust that acted over the step is the logged one
    acting = plant.data.actuator_force[0:4] / plant.model.actuator_gear[0:4, 2]
    np.testing.assert_allclose(acting, row[4:8], rtol=1e-12)


def test_the_runner_logs_factors_thrusts_and_drag():
    from tetherland.sim.baselines import ConstantSpeedController
    from tetherland.sim.runner import Runner

    sc = load_scenario("slope50")
    ctrl = ConstantSpeedController.hover(sc.vehicle)
    runner = Runner(sc, ctrl, seed=1)
    start = runner.plant.landed_state()
    log = runner.run(0.1, initial_state=start, rotor_speeds=ctrl.update(0, None, None).rotor_speeds)
    k = log["ground_effect"]
    assert np.all(k > 1.0) and np.all(k < 4 / 3)
    f0 = sc.vehicle.thrust_coefficient * log["rotor_speeds"] ** 2
    np.testing.assert_allclose(log["rotor_thrusts"], f0 * k, rtol=1e-12)
    assert log["drag_force_W"].shape == (len(log), 3)


def test_the_believed_ground_effect_matches_the_plant_over_the_believed_surface():
    from tetherland.estimation.ground_effect import BelievedGroundEffect

    for name in ("slope50", "pipe60", "wall90"):
        sc = load_scenario(name, ["aero.rotor_drag=[0, 0]"])
        plant = Plant(sc)
        w = hover_speed(sc)
        landed = plant.landed_state()
        belief = BelievedGroundEffect(sc)  # the belief equal to the truth here
        for lift in (0.0, 0.05, 0.15):  # landed, and lifted along the surface normal
            n = plant.layout.geometry.surface.z_S
            state = RigidBodyState.at_rest(landed.p_W + lift * n, landed.q_WB)
            plant.reset(state, rotor_speeds=np.full(4, w))
            truth = float(plant.rotor_thrusts.sum())
            f0 = np.full(4, sc.vehicle.thrust_coefficient * w * w)
            believed = belief.total_thrust(state.p_W, state.q_WB, f0)
            # the plant also feels the far ground (under 0.1 % of the thrust here)
            assert believed == pytest.approx(truth, rel=1e-3)
            assert believed > 4 * f0[0]


def test_compensation_makes_the_believed_acting_thrust_the_wanted_one():
    from tetherland.control.ground_effect import GroundEffectCompensation
    from tetherland.interfaces import Command, Reference, StateEstimate

    sc = load_scenario("slope50", ["aero.rotor_drag=[0, 0]"])
    plant = Plant(sc)
    w = hover_speed(sc) * np.array([1.0, 1.02, 0.98, 1.01])

    class Fixed:
        def update(self, t, estimate, reference):
            return Command(rotor_speeds=w.copy(), thrust=1.0)

    wrapped = GroundEffectCompensation(Fixed(), sc)
    n = plant.layout.geometry.surface.z_S
    landed = plant.landed_state()
    state = RigidBodyState.at_rest(landed.p_W + 0.02 * n, landed.q_WB)
    cmd = wrapped.update(0.0, StateEstimate(t=0.0, body=state), Reference(t=0.0))
    assert cmd.thrust == 1.0  # everything but the speeds passes through
    k = wrapped.ground_effect.factors_at(state.p_W, state.q_WB)
    R = PROP_RADIUS_FRACTION * sc.vehicle.arm_length
    z = sc.vehicle.h_R + PROP_HEIGHT + 0.02  # rotor disks above the slope, along z_S
    np.testing.assert_allclose(k, cb(z / R), rtol=1e-12)
    np.testing.assert_allclose(cmd.rotor_speeds**2 * k, w**2, rtol=1e-12)
    # the plant (the truth, with the far ground too) then gives the wanted thrusts
    plant.reset(state, rotor_speeds=cmd.rotor_speeds)
    c_f = sc.vehicle.thrust_coefficient
    np.testing.assert_allclose(plant.rotor_thrusts, c_f * w**2, rtol=1e-3)
