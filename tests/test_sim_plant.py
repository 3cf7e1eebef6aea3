"""The MuJoCo plant against first principles: hover, free fall, rotors, allocation."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.config import load_scenario
from tetherland.errors import SimulationError
from tetherland.models.quadrotor import RotorLayout
from tetherland.rotations import quat_to_rotmat
from tetherland.sim.mjcf import SENSOR_SLICES, SceneLayout, build_mjcf
from tetherland.sim.plant import CONTACT_PEAK_WIDTH, Plant
from tetherland.state import RigidBodyState


@pytest.fixture(scope="module")
def scenario():
    # the plain rotor model, out of ground effect and without rotor drag (the aero
    # effects near surfaces are tested in test_sim_aero.py)
    return load_scenario("slope50", ["aero.ground_effect=false", "aero.rotor_drag=[0, 0]"])


@pytest.fixture
def plant(scenario):
    return Plant(scenario)


def in_air(plant: Plant, height: float = 1.5) -> RigidBodyState:
    s = plant.start_state()
    return RigidBodyState.at_rest(s.p_W + np.array([0.0, 0.0, height]), s.q_WB)


def hover_speed(scenario) -> float:
    return math.sqrt(scenario.vehicle.mass * GRAVITY / 4 / scenario.vehicle.thrust_coefficient)


def test_mjcf_compiles_for_every_builtin_scenario():
    import mujoco

    cables = (['tether.material="ideal"'], [], ["tether.segments=4"])
    for name in ("flat", "slope50", "pipe60", "steep70"):
        for cable in cables:
            sc = load_scenario(name, cable)
            model = mujoco.MjModel.from_xml_string(build_mjcf(sc))
            body = model.body("vehicle")
            assert body.mass[0] == pytest.approx(sc.vehicle.mass)
            np.testing.assert_allclose(body.inertia, sc.vehicle.inertia)
            np.testing.assert_allclose(body.ipos, 0.0, atol=1e-12)  # body frame at the CoM
            assert model.jnt_qposadr[0] == 0 and model.jnt_dofadr[0] == 0  # vehicle first
            kind = sc.tether.cable_model.value
            assert model.ntendon == 1
            assert model.nu == (5 if kind == "elastic" else 4)
            assert bool(model.tendon_limited[0]) == (kind == "ideal")
            if kind == "ideal":
                assert model.tendon_range[0, 1] == pytest.approx(sc.tether.length)
            if kind == "chain":
                links = [model.body(f"cable_link{i}") for i in range(sc.tether.segments)]
                total = sum(b.mass[0] for b in links)
                assert total == pytest.approx(sc.tether.mass_per_length * sc.tether.length)
                assert model.neq == 1 and model.nq == 7 + 4 * sc.tether.segments


def test_lander_tips_form_the_landers_plane(plant, scenario):
    """Lowest points of the four lander spheres lie h_R below the CoM, at (+-w, +-w)."""
    v = scenario.vehicle
    tips = []
    for i in range(4):
        g = plant.model.geom(f"lander{i}")
        tips.append(g.pos - np.array([0.0, 0.0, g.size[0]]))
    tips = np.array(tips)
    np.testing.assert_allclose(tips[:, 2], -v.h_R, atol=1e-12)
    np.testing.assert_allclose(np.abs(tips[:, :2]), v.lander_half_width, atol=1e-12)


def test_the_plant_and_the_robot_place_the_landers_where_the_airframe_says(plant, scenario):
    """One statement of the lander tips (models.airframe), in one order, for the plant's
    geoms and touch zones, the robot's contact rule and the contact-free method."""
    from tetherland.methods.contact_free import LanderGeometry
    from tetherland.mission.contact import ContactGeometry
    from tetherland.models.airframe import lander_centres_B, lander_tips_B

    v = scenario.vehicle
    w, r = v.lander_half_width, v.lander_radius
    tips = lander_tips_B(w, v.h_R)
    # lander 0 front left (+x, +y), then counter-clockwise seen from above, 90 deg apart
    azimuths = np.degrees(np.unwrap(np.arctan2(tips[:, 1], tips[:, 0])))
    np.testing.assert_allclose(azimuths, [45.0, 135.0, 225.0, 315.0], atol=1e-12)
    np.testing.assert_allclose(np.hypot(tips[:, 0], tips[:, 1]), math.sqrt(2) * w, rtol=1e-15)
    np.testing.assert_array_equal(tips[:, 2], -v.h_R)
    np.testing.assert_allclose(lander_centres_B(w, v.h_R, r) - tips, [[0.0, 0.0, r]] * 4,
                               atol=1e-15)  # fmt: skip
    for i, tip in enumerate(tips):
        centre = plant.model.geom(f"lander{i}").pos
        np.testing.assert_allclose(centre - [0.0, 0.0, r], tip, atol=1e-12)
        np.testing.assert_array_equal(plant.model.site(f"lander{i}_zone").pos, centre)
    np.testing.assert_array_equal(ContactGeometry.from_scenario(scenario).tips_B, tips)
    lander_geometry = LanderGeometry.create(w, v.h_R, [0.0, 0.0, 1.0], [0.0, 0.0, 0.0])
    np.testing.assert_array_equal(lander_geometry.tips_B, tips)


def test_hover_speeds_keep_the_vehicle_still(plant, scenario):
    """Rotor speeds for m g, lag settled: no drift over 2 s (the plant has no disturbances)."""
    start = in_air(plant)
    w = hover_speed(scenario)
    plant.reset(start, rotor_speeds=np.full(4, w))
    plant.step(2000)
    s = plant.state()
    assert np.linalg.norm(s.p_W - start.p_W) < 1e-6
    assert np.linalg.norm(s.omega_B) < 1e-9
    np.testing.assert_allclose(plant.sensordata[0:3], [0, 0, GRAVITY], atol=1e-9)


def test_free_fall_matches_g(plant):
    """Rotors stopped: v_z = -g t exactly; z = -g t^2/2 up to the integrator's g dt t/2."""
    start = in_air(plant)
    plant.reset(start)
    n = 300
    plant.step(n)
    t, dt = plant.time, plant.dt
    s = plant.state()
    assert s.v_W[2] == pytest.approx(-GRAVITY * t, abs=1e-9)
    # semi-implicit Euler: z_n = z_0 - g dt^2 n (n + 1) / 2
    assert s.p_W[2] - start.p_W[2] == pytest.approx(-GRAVITY * dt * dt * n * (n + 1) / 2, abs=1e-9)
    assert abs(s.p_W[2] - start.p_W[2] + 0.5 * GRAVITY * t * t) < 0.5 * GRAVITY * dt * t + 1e-9
    np.testing.assert_allclose(plant.sensordata[0:3], 0.0, atol=1e-9)  # specific force


def test_motor_lag_is_first_order_and_exact(plant, scenario):
    tau = scenario.vehicle.motor_time_constant
    w_cmd = 600.0
    plant.reset(in_air(plant))
    plant.command(np.full(4, w_cmd))
    n = round(tau / plant.dt)
    plant.step(n)
    expected = w_cmd * (1 - math.exp(-n * plant.dt / tau))
    np.testing.assert_allclose(plant.rotor_speeds, expected, rtol=1e-12)
    np.testing.assert_allclose(
        plant.rotor_thrusts, scenario.vehicle.thrust_coefficient * expected**2
    )


def test_speed_command_is_clamped_to_f_max_but_not_to_f_min(plant, scenario):
    v = scenario.vehicle
    plant.reset(in_air(plant), rotor_speeds=np.full(4, 1e6))
    np.testing.assert_allclose(plant.rotor_thrusts, v.f_max, rtol=1e-12)
    plant.reset(in_air(plant), rotor_speeds=[-5.0, 0.0, 0.0, 0.0])
    assert np.all(plant.rotor_thrusts == 0.0)  # motors off: zero thrust, below f_min > 0


def test_motors_off_stops_the_thrust(plant, scenario):
    plant.reset(in_air(plant, 3.0), rotor_speeds=np.full(4, hover_speed(scenario)))
    plant.command(np.zeros(4))
    plant.step(500)  # 0.5 s = 16.7 tau_m
    assert np.all(plant.rotor_thrusts < 1e-12 * scenario.vehicle.f_max)
    plant.step(1)
    np.testing.assert_allclose(plant.sensordata[0:3], 0.0, atol=1e-9)  # falling freely


def test_rotor_forces_match_the_allocation_matrix(plant, scenario):
    """Angular acceleration from unequal rotor thrusts equals J^-1 (Gamma f)[1:4] (6.19)."""
    layout = RotorLayout.from_config(scenario.vehicle)
    f = np.array([2.0, 3.0, 1.0, 2.5])
    plant.reset(in_air(plant), rotor_speeds=layout.speed_from_thrust(f))
    plant.step(1)
    u = layout.allocation @ f
    J = np.asarray(scenario.vehicle.inertia)
    assert np.all(np.abs(u[1:]) > 1e-3)  # roll, pitch and yaw torques all excited
    np.testing.assert_allclose(plant.state().omega_B, u[1:] / J * plant.dt, rtol=1e-9, atol=1e-15)
    # specific force: total thrust along z_B over the mass
    np.testing.assert_allclose(
        plant.sensordata[0:3], [0, 0, u[0] / scenario.vehicle.mass], rtol=1e-9
    )


def test_accelerometer_measures_contact_and_cable_not_gravity(scenario):
    """Landed, motors off, cable holding: specific force = -g expressed in F_B (a = 0)."""
    plant = Plant(scenario)
    plant.reset(plant.landed_state(), cable_engaged=True)
    plant.step(3000)
    R_WB = plant.state().R_WB
    np.testing.assert_allclose(plant.sensordata[0:3], R_WB.T @ [0, 0, GRAVITY], atol=2e-3)


def test_nan_command_is_refused(plant):
    with pytest.raises(SimulationError, match="non-finite"):
        plant.command([np.nan, 0, 0, 0])
    with pytest.raises(SimulationError, match="4 rotor"):
        plant.command([1.0, 2.0])


def test_divergence_raises_instead_of_resetting(plant, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # MuJoCo writes its warning to MUJOCO_LOG.TXT in the cwd
    plant.reset(in_air(plant))
    plant.data.qvel[3] = 1e300  # absurd spin: MuJoCo flags a bad state
    with pytest.raises(SimulationError, match="diverged"):
        plant.step(5)


def test_scene_layout_places_ground_and_start_pad():
    sc = load_scenario("slope50")
    lay = SceneLayout.from_scenario(sc)
    surf = lay.geometry.surface
    foot = surf.origin + sc.surface.extent * surf.x_S
    assert lay.ground_z == pytest.approx(foot[2])
    assert lay.start_position[2] == pytest.approx(lay.ground_z)
    assert surf.height(lay.start_position) > 0.5  # beyond the foot: outside the slope
    plant = Plant(sc)
    plant.reset()  # on the start pad, motors off: rests on its landers
    plant.step(500)
    assert np.all(plant.lander_forces > 0.5)
    assert np.linalg.norm(plant.state().v_W) < 1e-3


def test_pipe_top_line_runs_through_the_surface_origin_along_x_S():
    sc = load_scenario("pipe60")
    plant = Plant(sc)
    surf = plant.layout.geometry.surface
    g = plant.model.geom("surface")
    assert g.type[0] == int(mujoco.mjtGeom.mjGEOM_CYLINDER)
    R = sc.surface.pipe_radius
    axis = quat_to_rotmat(g.quat)[:, 2]
    assert abs(axis @ surf.x_S) == pytest.approx(1.0)
    # the origin is on the pipe, on its top line (the point with normal z_S)
    rel = surf.origin - g.pos
    radial = rel - (rel @ axis) * axis
    assert np.linalg.norm(radial) == pytest.approx(R)
    np.testing.assert_allclose(radial / R, surf.z_S, atol=1e-12)


def test_thrust_impulse_follows_the_continuous_motor_lag(plant, scenario):
    """Spin-up from rest: v_z(T) = 4 c_f/m int_0^T w(t)^2 dt - g T with
    w(t) = w_c (1 - exp(-t/tau)), the command acting from t = 0 (within 0.1 %; measured
    0.02 %: the plant applies the exact mean speed of each step)."""
    v = scenario.vehicle
    tau, c_f, w_c, T = v.motor_time_constant, v.thrust_coefficient, 700.0, 0.1
    plant.reset(in_air(plant))
    plant.command(np.full(4, w_c))
    plant.step(round(T / plant.dt))
    e1, e2 = math.exp(-T / tau), math.exp(-2 * T / tau)
    integral = w_c**2 * (T - 2 * tau * (1 - e1) + 0.5 * tau * (1 - e2))
    expected = 4 * c_f / v.mass * integral - GRAVITY * T
    assert plant.state().v_W[2] == pytest.approx(expected, rel=1e-3)


@pytest.mark.parametrize("where", ["surface", "pad"])
def test_lander_contact_forces_are_split_by_what_they_touch(where):
    """At rest with the motors off, the landers' normal forces sum to the weight's normal
    component, m g cos(beta) on a 20 deg slope (friction 0.6 > tan 20 deg holds it) and
    m g on the start pad, all on that partner and none on the other."""
    sc = load_scenario("slope50", ["surface.slope_deg=20"])
    plant = Plant(sc)
    plant.reset(plant.landed_state() if where == "surface" else None)
    plant.step(800)  # settle
    peaks = np.zeros(CONTACT_PEAK_WIDTH)
    plant.contact_peaks_into(peaks)
    plant.step(1)
    plant.contact_peaks_into(peaks)  # one physics step: the forces at rest
    surface, ground = peaks[:4], peaks[4:8]
    weight = sc.vehicle.mass * GRAVITY
    if where == "surface":
        assert surface.sum() == pytest.approx(weight * math.cos(math.radians(20)), rel=1e-3)
        assert np.all(surface > 0.0) and not np.any(ground)
    else:
        assert ground.sum() == pytest.approx(weight, rel=1e-3)
        assert np.all(ground > 0.0) and not np.any(surface)
    np.testing.assert_allclose(plant.lander_forces, surface + ground, rtol=1e-9)


def test_lander_contact_peaks_are_taken_at_every_physics_step(scenario):
    """Dropped 2 cm onto the pad, the impact's force varies from step to step: the peak
    read after 10 steps is the largest of the 10 per-step normal forces, and reading
    starts over."""
    plant = Plant(scenario)
    s = plant.start_state()
    plant.reset(RigidBodyState.at_rest(s.p_W + np.array([0.0, 0.0, 0.02]), s.q_WB))
    plant.step(60)  # just before the impact (free fall of 2 cm: 64 ms)
    peaks = np.zeros(CONTACT_PEAK_WIDTH)
    plant.contact_peaks_into(peaks)
    first, last = SENSOR_SLICES["lander0_ground"], SENSOR_SLICES["lander3_ground"]
    ground = np.s_[first.start : last.stop : 3]  # the ground sensors' normal entries
    per_step = []
    for _ in range(10):
        plant.step(1)
        per_step.append(plant.sensordata[ground].copy())
    plant.contact_peaks_into(peaks)
    np.testing.assert_array_equal(peaks[4:8], np.max(per_step, axis=0))
    assert np.max(per_step) > np.max(per_step[-1])  # the peak is not the last step's value
    plant.contact_peaks_into(peaks)
    assert not np.any(peaks[:9]) and peaks[9] == -1  # no force, no part touched


def test_a_contact_free_read_overwrites_every_peak(scenario):
    """In the air (no contact at any step since the last read) the read writes no force,
    no part (-1) and no depth over whatever the buffer held; after a touchdown the next
    read carries the landers' forces again, and a read with no step between is empty."""
    plant = Plant(scenario)
    plant.reset(in_air(plant, 0.02))
    peaks = np.full(CONTACT_PEAK_WIDTH, 7.0)
    plant.step(5)
    assert plant.data.ncon == 0
    plant.contact_peaks_into(peaks)
    np.testing.assert_array_equal(peaks[:9], 0.0)
    assert peaks[9] == -1.0 and peaks[10] == 0.0
    plant.step(120)  # falls 2 cm onto the pad: the landers touch
    peaks[:] = 7.0
    plant.contact_peaks_into(peaks)
    assert np.all(peaks[4:8] > 0.0) and not np.any(peaks[:4])
    assert peaks[10] >= 0.0 and peaks[9] == -1.0
    peaks[:] = 7.0
    plant.contact_peaks_into(peaks)  # nothing stepped since: all zero again
    np.testing.assert_array_equal(peaks[:9], 0.0)
    assert peaks[9] == -1.0 and peaks[10] == 0.0
