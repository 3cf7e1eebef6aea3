"""The plant's per-step rotor kernel (sim/step_kernel.py) against its plain reference and
the exact first-order lag."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.models.aero import aero_work_size
from tetherland.sim import step_kernel as sk
from tetherland.sim.plant import Plant
from tetherland.sim.step_kernel import rotor_state, rotor_step, rotor_step_reference


@pytest.fixture(scope="module")
def plant():
    return Plant(load_scenario("slope50"))


def _aero_arrays(plant: Plant, aero: bool):
    if aero:
        a = plant.aero
        return (a.rotor_centres_B, a.samples, a.shapes, a.params), aero_work_size(a.shapes.shape[0])
    return (np.zeros((0, 3)), np.zeros((0, 2)), np.zeros((0, 16)), np.zeros(0)), 0


def _plant_rotor_state(plant: Plant, aero: bool):
    """A rotor state at rest with the plant's lag constants (the plant's own, built
    here from the scenario)."""
    dt, tau = plant.dt, plant.scenario.vehicle.motor_time_constant
    alpha = math.exp(-dt / tau)
    c_f, w_max = plant.scenario.vehicle.thrust_coefficient, plant.speed_limit
    return rotor_state(c_f, tau * (1.0 - alpha) / dt, alpha, 1e-12 * w_max, aero)


@pytest.mark.parametrize("aero", [True, False])
def test_kernel_matches_the_plain_reference_bit_for_bit(plant, aero):
    # random commands held for random spans (some repeated: the speeds settle), poses
    # near the slope (rays hit it and the ground) and random air velocities
    rng = np.random.default_rng(7)
    dt, tau = plant.dt, plant.scenario.vehicle.motor_time_constant
    alpha = math.exp(-dt / tau)
    c_f, w_max = plant.scenario.vehicle.thrust_coefficient, plant.speed_limit
    rot = rotor_state(c_f, tau * (1.0 - alpha) / dt, alpha, 1e-12 * w_max, aero)
    ref = rot.copy()
    arrays, n_work = _aero_arrays(plant, aero)
    work = np.empty(n_work)
    landed = plant.landed_state()
    z_S = plant.layout.geometry.surface.z_S
    ctrl, ctrl_ref = np.zeros(4), np.zeros(4)
    wrench, wrench_ref = np.zeros(6), np.zeros(6)
    settled = spans = 0
    cmd = rng.uniform(0.3, 0.9, 4) * w_max
    while spans < 40:
        if rng.random() < 0.7:  # otherwise the same command again: no spin-up
            cmd = rng.uniform(0.3, 0.9, 4) * w_max
            if rng.random() < 0.1:
                cmd[rng.integers(4)] = 0.0  # a stopped motor
        for r in (rot, ref):
            if not np.array_equal(r[sk.R_CMD : sk.R_CMD + 4], cmd):
                r[sk.R_CMD : sk.R_CMD + 4] = cmd
                r[sk.R_SPINNING] = 1.0
        for _ in range(3000 if spans % 8 == 0 else int(rng.integers(1, 40))):  # 3 s: settles
            q = landed.q_WB + rng.normal(0.0, 0.05, 4)
            qpos = np.concatenate((landed.p_W + rng.uniform(0.0, 0.8) * z_S, q / np.linalg.norm(q)))
            v_W = rng.normal(0.0, 1.0, 6)
            rotor_step(rot, qpos, v_W, *arrays, work, ctrl, wrench)
            rotor_step_reference(ref, qpos, v_W, *arrays, ctrl_ref, wrench_ref)
            assert np.array_equal(rot, ref)
            assert np.array_equal(ctrl, ctrl_ref)
            assert np.array_equal(wrench, wrench_ref)
        settled += rot[sk.R_SPINNING] == 0.0
        spans += 1
    assert settled >= 4  # the settled branch was exercised
    if aero:  # the rotors near the surface: factors above 1 reached the actuators
        factors, base = rot[sk.R_FACTOR : sk.R_FACTOR + 4], rot[sk.R_BASE : sk.R_BASE + 4]
        assert np.all(factors > 1.0)
        np.testing.assert_array_equal(ctrl, base * factors)
    else:
        np.testing.assert_array_equal(rot[sk.R_FACTOR : sk.R_FACTOR + 4], 1.0)
        np.testing.assert_array_equal(ctrl, rot[sk.R_BASE : sk.R_BASE + 4])


def test_speeds_follow_the_exact_lag_and_the_thrust_the_mean_speed(plant):
    # w_n = c + (w_0 - c) alpha^n; the thrust of step n is c_f wbar^2 with wbar the mean
    # of the exact solution over the step: c + (w_n - c) tau (1 - alpha) / dt
    dt, tau = plant.dt, plant.scenario.vehicle.motor_time_constant
    alpha = math.exp(-dt / tau)
    c_f = plant.scenario.vehicle.thrust_coefficient
    rot = rotor_state(c_f, tau * (1.0 - alpha) / dt, alpha, 1e-12 * plant.speed_limit, False)
    arrays, _ = _aero_arrays(plant, False)
    w0, c = 100.0, 400.0
    rot[sk.R_W : sk.R_W + 4] = w0
    rot[sk.R_CMD : sk.R_CMD + 4] = c
    ctrl, wrench = np.zeros(4), np.zeros(6)
    qpos, v_W = np.array([0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0]), np.zeros(6)
    for n in range(1, 60):
        w_before = rot[sk.R_W]
        rotor_step(rot, qpos, v_W, *arrays, np.empty(0), ctrl, wrench)
        t0, t1 = (n - 1) * dt, n * dt
        exact = c + (w0 - c) * math.exp(-t1 / tau)
        assert rot[sk.R_W] == pytest.approx(exact, rel=1e-12)
        # the mean of w(t) = c + (w0 - c) exp(-t/tau) over [t0, t1]
        mean = c + (w0 - c) * tau * (math.exp(-t0 / tau) - math.exp(-t1 / tau)) / dt
        assert ctrl == pytest.approx(c_f * mean * mean, rel=1e-12)
        assert w_before < rot[sk.R_W] < c  # monotone toward the command
    np.testing.assert_array_equal(wrench, 0.0)  # aero off: the wrench is left alone


def test_a_plant_step_applies_the_kernel_thrusts(plant):
    # Plant.step hands MuJoCo the kernel's thrusts: after one step from rest at a new
    # command, the actuators hold c_f wbar^2 times the surface factors
    plant.reset(plant.landed_state(), cable_engaged=True)
    plant.set_state(plant.landed_state())
    w = np.full(4, 0.5 * plant.speed_limit)
    plant.command(w)
    rot = plant._rot.copy()
    arrays = plant._aero_args
    ctrl, wrench = np.zeros(4), np.zeros(6)
    rotor_step_reference(rot, plant.qpos.copy(), plant.qvel.copy(), *arrays, ctrl, wrench)
    plant.step()
    np.testing.assert_array_equal(plant.data.ctrl[0:4], ctrl)
    np.testing.assert_array_equal(plant.data.qfrc_applied[0:6], wrench)
    np.testing.assert_array_equal(plant.rotor_speeds, rot[sk.R_W : sk.R_W + 4])
    assert np.all(plant.surface_factors > 1.0)  # landed: the slope under the rotors


@pytest.mark.parametrize("aero", [True, False])
def test_rotor_row_kernel_matches_its_plain_form_and_the_model(plant, aero):
    # the log's rotor row from the kernel's rotor state after steps near the slope: the
    # compiled row equals the plain one bit for bit, and its parts are the model's
    # (thrusts c_f w^2 k, factors 1 and no force with the aero flag off)
    rng = np.random.default_rng(11)
    c_f, w_max = plant.scenario.vehicle.thrust_coefficient, plant.speed_limit
    rot = _plant_rotor_state(plant, aero)
    arrays, n_work = _aero_arrays(plant, aero)
    work, ctrl = np.empty(n_work), np.zeros(4)
    wrench = rng.normal(0.0, 1.0, 6)  # (aero off: a wrench the row must not report)
    landed = plant.landed_state()
    z_S = plant.layout.geometry.surface.z_S
    for _ in range(200):
        rot[sk.R_CMD : sk.R_CMD + 4] = rng.uniform(0.0, 1.0, 4) * w_max
        rot[sk.R_SPINNING] = 1.0
        qpos = np.concatenate((landed.p_W + rng.uniform(0.0, 0.5) * z_S, landed.q_WB))
        rotor_step(rot, qpos, rng.normal(0.0, 1.0, 6), *arrays, work, ctrl, wrench)
        row, row_ref = np.full(16, np.nan), np.full(16, np.nan)
        sk.rotor_row_into(rot, wrench, row)
        sk.rotor_row_reference(rot, wrench, row_ref)
        assert np.array_equal(row[:15], row_ref[:15])
        assert np.isnan(row[15])  # nothing written past the row
        w, k = rot[sk.R_W : sk.R_W + 4], rot[sk.R_FACTOR : sk.R_FACTOR + 4]
        np.testing.assert_array_equal(row[0:4], w)
        np.testing.assert_allclose(row[4:8], c_f * w**2 * (k if aero else 1.0), rtol=1e-15)
        np.testing.assert_array_equal(row[8:12], k if aero else 1.0)
        np.testing.assert_array_equal(row[12:15], wrench[0:3] if aero else 0.0)
    if aero:
        assert np.all(k > 1.0)  # the slope was under the rotors: factors other than 1


def test_plant_rotor_state_is_the_kernel_row(plant):
    # Plant.rotor_state_into (the runner's log row) is the kernel's row of its own state
    plant.reset(plant.landed_state(), cable_engaged=True)
    plant.command(np.full(4, 0.5 * plant.speed_limit))
    for _ in range(3):
        plant.step()
    out, ref = np.empty(15), np.empty(15)
    plant.rotor_state_into(out)
    sk.rotor_row_reference(plant._rot, plant.data.qfrc_applied[0:6], ref)
    assert np.array_equal(out, ref)
    np.testing.assert_array_equal(plant.rotor_thrusts, out[4:8])


def test_command_kernel_matches_its_plain_form(plant):
    # random command sequences with repeats (no change: the flag stays as the last step
    # left it), out-of-range values (clamped), infinities and NaNs (the commands before
    # the NaN held, the rest not, False): the compiled and the plain form leave the
    # same rotor state bit for bit and agree on the outcome
    rng = np.random.default_rng(5)
    w_max = plant.speed_limit
    rot = rotor_state(plant.scenario.vehicle.thrust_coefficient, 0.5, 0.9, 1e-9, True)
    ref = rot.copy()
    outcomes = set()
    cmd = rng.uniform(-0.2, 1.2, 4) * w_max
    for i in range(2000):
        if rng.random() < 0.6:
            cmd = rng.uniform(-0.2, 1.2, 4) * w_max
            if rng.random() < 0.2:
                cmd[rng.integers(4)] = rng.choice([np.nan, np.inf, -np.inf])
        if i % 3 == 0:  # the kernel's step settles the rotors: the flag goes down
            rot[sk.R_SPINNING] = ref[sk.R_SPINNING] = 0.0
        ok = sk.command_rotors(rot, cmd, w_max)
        assert ok == sk.command_rotors_reference(ref, cmd, w_max)
        assert np.array_equal(rot, ref)
        held = rot[sk.R_CMD : sk.R_CMD + 4]
        assert np.all((held >= 0.0) & (held <= w_max))
        outcomes.add((ok, rot[sk.R_SPINNING]))
    assert outcomes == {(True, 0.0), (True, 1.0), (False, 0.0), (False, 1.0)}


def test_plant_command_clamps_and_names_a_nan(plant):
    plant.reset()
    w_max = plant.speed_limit
    plant.command([-1.0, 0.5 * w_max, 2.0 * w_max, np.inf])
    np.testing.assert_array_equal(plant.commanded_speeds, [0.0, 0.5 * w_max, w_max, w_max])
    with pytest.raises(Exception, match="non-finite rotor speed command"):
        plant.command([0.1 * w_max, np.nan, 0.0, 0.0])
    # the command before the NaN is held, the ones after it are not
    np.testing.assert_array_equal(plant.commanded_speeds, [0.1 * w_max, 0.5 * w_max, w_max, w_max])
    with pytest.raises(Exception, match="expected 4 rotor speed commands, got 3"):
        plant.command([1.0, 2.0, 3.0])
