"""The magnet mechanism's centre of mass (docs/mechanism.md, *The mass*): the robot's
belief of the weight's moment with the magnet clipped, held or hanging, the torque fed
forward with it, and the mission flying it; expected values derived here from the
plant's compiled bodies and the configuration."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.config import load_scenario
from tetherland.control.switching import with_torque
from tetherland.geometry import link_angles
from tetherland.interfaces import Command, StateEstimate
from tetherland.mission import MissionSupervisor, Phase, plan_mission
from tetherland.models.hook import (
    MAGNET_BALANCE,
    magnet_boom,
    magnet_centre_B,
    magnet_load,
    weight_torque_B,
)
from tetherland.models.quadrotor import RotorLayout
from tetherland.rotations import quat_to_rotmat, rotation_from_z_and_yaw, rotmat_to_quat
from tetherland.sim.mjcf import SOCKET_MASS
from tetherland.sim.plant import Plant
from tetherland.state import LinkState, RigidBodyState


def _moment_B(plant: Plant, root: str) -> tuple[float, np.ndarray]:
    """Mass and mass moment about the vehicle's body origin, F_B, of every body whose
    kinematic root is the body ``root``, at the model's reference pose [kg, kg m]."""
    m, d = plant.model, plant.data
    d.qpos[:] = m.qpos0
    mujoco.mj_kinematics(m, d)
    obj = mujoco.mjtObj.mjOBJ_BODY
    vehicle = mujoco.mj_name2id(m, obj, "vehicle")
    rid = mujoco.mj_name2id(m, obj, root)
    R = d.xmat[vehicle].reshape(3, 3)
    mass, moment = 0.0, np.zeros(3)
    for b in range(m.nbody):
        if m.body_rootid[b] == rid:
            mass += float(m.body_mass[b])
            moment += float(m.body_mass[b]) * (R.T @ (d.xipos[b] - d.xpos[vehicle]))
    return mass, moment


@pytest.mark.parametrize("name", ["wall90", "overhang93"])
def test_the_believed_weight_moment_is_the_plants(name: str) -> None:
    """With the magnet clipped the weight's moment about the body origin is (1 - beta) m
    r_m, once it has left the boom -beta m r_m (the frame balanced for the boom and beta
    of the magnet's moment): the plant's bodies carry those moments, to the clip's 1 g
    socket at the boom's tip, which the robot's model leaves out."""
    s = load_scenario(name, ["mechanism.kind=magnet"])
    plant = Plant(s)
    M, m = s.vehicle.mass, s.mechanism.magnet_mass
    r_m = magnet_centre_B(s)
    socket = SOCKET_MASS * float(np.linalg.norm(r_m))  # its moment is at most this
    frame_mass, frame_moment = _moment_B(plant, "vehicle")  # the vehicle without the magnet
    magnet_mass, magnet_moment = _moment_B(plant, "magnet")
    assert magnet_mass == pytest.approx(m, rel=1e-12)
    assert frame_mass == pytest.approx(M - m + SOCKET_MASS, rel=1e-12)

    mass, c = magnet_load(s, "clipped")
    assert mass == pytest.approx(M, rel=1e-12)
    np.testing.assert_allclose(mass * c, (1.0 - MAGNET_BALANCE) * m * r_m, atol=1e-15)
    assert np.linalg.norm(mass * c - (frame_moment + magnet_moment)) <= socket + 1e-12

    mass, c = magnet_load(s, "held")
    assert mass == pytest.approx(M - m, rel=1e-12)
    np.testing.assert_allclose(mass * c, -MAGNET_BALANCE * m * r_m, atol=1e-15)
    assert np.linalg.norm(mass * c - frame_moment) <= socket + 1e-12

    # hanging on the cable: the frame's moment and the magnet's weight at the attachment
    mass, c = magnet_load(s, "hanging")
    r_att = np.asarray(s.vehicle.cable_attachment)
    np.testing.assert_allclose(mass * c, m * r_att - MAGNET_BALANCE * m * r_m, atol=1e-15)


def test_weight_torque_holds_the_weight_about_the_body_origin() -> None:
    """tau = mass g c x z_W (z_W in F_B): it cancels the weight's moment c x (-mass g z_W)
    at any attitude, and has no part along z_W (the weight turns nothing about the
    vertical)."""
    rng = np.random.default_rng(3)
    c = np.array([0.006, -0.001, -0.005])
    for _ in range(5):
        q = rng.normal(size=4)
        R = quat_to_rotmat(q / np.linalg.norm(q))
        tau = weight_torque_B(0.97, c, R)
        weight_B = R.T @ np.array([0.0, 0.0, -0.97 * GRAVITY])
        np.testing.assert_allclose(tau + np.cross(c, weight_B), 0.0, atol=1e-15)
        assert abs(float(tau @ R[2])) < 1e-15


def test_with_torque_adds_the_torque_and_keeps_the_thrust() -> None:
    """The rotors' wrench Gamma f moves by exactly [0, tau] (within the rotor limits), the
    wanted torque by tau; at a limit the rotor is held there."""
    s = load_scenario("wall90", ["mechanism.kind=magnet"])
    layout = RotorLayout.from_config(s.vehicle)
    c_f = layout.thrust_coefficient
    f = np.array([0.6, 0.7, 0.65, 0.55])  # N, all inside [f_min, f_max]
    cmd = Command(np.sqrt(f / c_f), float(f.sum()), layout.wrench(f)[1:4])
    tau = weight_torque_B(*magnet_load(s, "held"), np.eye(3))
    out = with_torque(cmd, tau, layout)
    f_out = c_f * np.asarray(out.rotor_speeds) ** 2
    np.testing.assert_allclose(layout.wrench(f_out) - layout.wrench(f),
                               [0.0, *tau], atol=1e-12)  # fmt: skip
    np.testing.assert_allclose(out.torque_B, np.asarray(cmd.torque_B) + tau, atol=1e-15)
    assert out.thrust == cmd.thrust
    low = np.full(4, layout.f_min)
    out = with_torque(Command(np.sqrt(low / c_f), float(low.sum()), np.zeros(3)),
                      np.array([0.05, 0.05, 0.0]), layout)  # fmt: skip
    assert float(np.min(c_f * np.asarray(out.rotor_speeds) ** 2)) >= layout.f_min - 1e-12


@pytest.mark.parametrize("deeper", [0.0, 0.8, None])
def test_the_supervisor_feeds_the_believed_moment_forward(deeper: float | None) -> None:
    """Flown with perfect tracking (the estimate is the last reference), but stopped by
    the plate (the vehicle no farther along the approach than where the face meets it,
    ``press_depth`` short of the pass's end when it is where believed; ``deeper`` times
    ``press_depth`` farther; None: no plate), the supervisor's references carry the
    clipped magnet's weight torque up to the end of the hooking pass, the EPM's switching
    time, ``latch_settle`` and ``latch_time`` after it (the latch, opened at the settle's
    end, takes the magnet off the clip), the held one from there; the fault monitor is
    told the law's own torque, the command less that feed-forward. A pass that reaches
    within half of ``press_depth`` of its end (0.8 deeper, or no plate) switches nothing
    on, keeps the latch shut and the magnet clipped, and the pass is flown again
    ``press_depth`` deeper: the plate 0.8 ``press_depth`` deeper is pressed on the second
    pass; with none the supervisor retries until ``max_attempts`` and aborts."""
    s = load_scenario("wall90", ["mechanism.kind=magnet"])
    m = s.mechanism
    plan = plan_mission(s, Plant(s).start_state())
    sup = MissionSupervisor(s, plan)
    told: list[np.ndarray] = []
    sup.monitor.command_sent = lambda t, c: told.append(np.asarray(c.torque_B))
    geo = plan.geometry
    n_W = geo.R_WA @ magnet_boom(s).n_B
    stop = None if deeper is None else (  # the face on the plate
        float(plan.waypoints.hook_end @ n_W) - m.press_depth + deeper * m.press_depth)
    passes = 1 if deeper == 0.0 else 2 if deeper is not None else s.mission.hooking.max_attempts
    dt = 1.0 / s.controller.rate_hz
    rows = np.zeros((3, 3))
    rows[0] = plan.start.p_W
    R = rotation_from_z_and_yaw(np.array([0.0, 0.0, 1.0]), sup.yaw)
    q = rotmat_to_quat(R)
    clipped = weight_torque_B(*magnet_load(s, "clipped"), R)
    held = weight_torque_B(*magnet_load(s, "held"), R)
    # the two differ by the magnet's moment m g |r_m x z_W| (0.08 N m): not a rounding
    assert np.linalg.norm(held - clipped) > 0.5 * m.magnet_mass * GRAVITY * float(
        np.linalg.norm(np.cross(magnet_centre_B(s), [0.0, 0.0, 1.0]))
    )
    t_on = None
    t_latch = None  # when the robot opens the latch
    for k in range(round(80.0 / dt)):
        t = k * dt
        phi, delta = link_angles(geo.R_WA.T @ (rows[0] - geo.p_A))
        est = StateEstimate(t=t, body=RigidBodyState(rows[0].copy(), rows[1].copy(), q,
                                                     np.zeros(3)),
                            link=LinkState(phi, delta), tension=0.0)  # fmt: skip
        ref = sup.reference(t, est)
        if t_on is None and sup.magnet_on:
            t_on = t
            t_latch = t_on + m.epm_on_time + m.latch_settle
            assert sup.phase == Phase.STRETCH  # on at the pass's end
            assert sup.hook_attempts == passes
        deciding = t_latch is not None and t >= t_latch - 1e-9
        assert sup.latch_open == deciding
        pulling = deciding and t >= t_latch + m.latch_time - 1e-9
        np.testing.assert_allclose(ref.torque_ff_B, held if pulling else clipped, atol=1e-12)
        law = np.array([0.01, -0.02, 0.003])
        sup.command_sent(t + dt, Command(np.zeros(4), 9.0, law + ref.torque_ff_B))
        np.testing.assert_allclose(told[-1], law, atol=1e-15)
        if pulling and t > t_latch + m.latch_time + 1.0:
            assert sup.phase == Phase.STRETCH
            break
        if sup.abort_reason is not None:  # no plate: every pass missed
            assert deeper is None and t_on is None and not sup.latch_open
            assert sup.abort_reason == f"hook missed {passes} times"
            assert sup.hook_attempts == passes
            break
        rows = np.asarray(ref.p_W)[:3]
        if stop is not None and float(rows[0] @ n_W) > stop:  # the plate stops the vehicle
            rows = rows.copy()
            rows[0] -= (float(rows[0] @ n_W) - stop) * n_W
            rows[1] = 0.0
    else:
        raise AssertionError("neither the latch nor the abort came")
