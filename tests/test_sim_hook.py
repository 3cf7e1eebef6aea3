"""Hook model: engage on a correct approach, miss when offset, release on the way back."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.config import load_scenario
from tetherland.errors import ConfigError
from tetherland.sim.hook import Hook, HookEventKind
from tetherland.sim.mjcf import hook_timeconst
from tetherland.sim.plant import Plant
from tetherland.state import RigidBodyState

# the passes are flown kinematically against the plain rotor model: no rotor drag or
# surface effects (those are tested in test_sim_aero.py)
NO_AERO = ["aero.ground_effect=false", "aero.rotor_drag=[0, 0]"]


def test_hook_state_machine_unit():
    hook = Hook([0, 0, 0], [0, 0, -1], capture_radius=0.1, hook_drop=0.0, miss_radius=1.0)
    hook.update(0.0, 0.05, 0.0, 0.2)
    assert hook.update(0.1, 0.05, 0.0, -0.2) is HookEventKind.ENGAGED  # down through the disk
    assert hook.events[-1].distance == pytest.approx(0.05)
    np.testing.assert_allclose(hook.events[-1].point_W, [0.05, 0, 0], atol=1e-15)
    assert hook.update(0.2, 0.5, 0.0, -0.2) is None  # moving around below: still engaged
    assert hook.update(0.3, 0.5, 0.0, 0.2) is None  # back up outside the disk: still hooked
    assert hook.engaged
    assert hook.update(0.4, 0.0, 0.0, -0.1) is None  # down again (forward) while engaged
    assert hook.update(0.5, 0.0, 0.0, 0.1) is HookEventKind.RELEASED  # back up through it
    assert not hook.engaged
    assert hook.update(0.6, 0.5, 0.0, -0.1) is HookEventKind.MISSED  # down, 0.5 m off
    assert hook.update(0.7, 2.0, 0.0, 0.1) is None
    assert hook.update(0.8, 2.0, 0.0, -0.1) is None  # farther than miss_radius: not reported
    assert [e.kind for e in hook.events] == [
        HookEventKind.ENGAGED,
        HookEventKind.RELEASED,
        HookEventKind.MISSED,
    ]


def test_hook_drop_lowers_the_hook_point():
    hook = Hook([0, 0, 0], [0, 0, -1], capture_radius=0.1, hook_drop=0.5)
    hook.update(0.0, 0.0, 0.0, 0.6)  # hook point at 0.1 above the anchor
    assert hook.update(0.1, 0.0, 0.0, 0.45) is HookEventKind.ENGAGED


def _descend_over_anchor(plant: Plant, offset: float, v_down: float = 0.3) -> None:
    """Hover speeds (constant velocity), hook point 0.1 m above the anchor plane, offset
    ``offset`` along y_A, moving down at ``v_down``."""
    sc = plant.scenario
    geo = plant.layout.geometry
    hook0 = geo.p_A + offset * geo.R_WA[:, 1] + np.array([0.0, 0.0, 0.1])
    p_com = (
        hook0 + np.array([0.0, 0.0, sc.tether.hook_drop]) - np.asarray(sc.vehicle.cable_attachment)
    )
    start = RigidBodyState(
        p_com, np.array([0.0, 0.0, -v_down]), plant.start_state().q_WB, np.zeros(3)
    )
    w = math.sqrt(sc.vehicle.mass * GRAVITY / 4 / sc.vehicle.thrust_coefficient)
    plant.reset(start, rotor_speeds=np.full(4, w))
    plant.step(round(0.2 / v_down / plant.dt))  # 0.1 m through the capture plane


CABLES = {
    "ideal": ['tether.material="ideal"'],
    "elastic": [],  # the default: massless Dyneema
    "chain": ["tether.segments=5"],
}


@pytest.fixture(scope="module", params=sorted(CABLES))
def plant(request):
    return Plant(load_scenario("slope50", CABLES[request.param] + NO_AERO))


def _slack_tension(plant: Plant, speed: float = 0.3) -> float:
    """Upper bound of the tension of a slack engaged cable [N]: 0, or for a massive one its
    weight plus picking it up at ``speed`` within the hook's time constant (it is laid
    out at rest when the hook catches)."""
    sc = plant.scenario
    mass = sc.tether.mass_per_length * sc.tether.length
    return mass * (GRAVITY + speed / hook_timeconst(sc)) + 1e-9


def test_correct_approach_engages_and_the_cable_then_holds(plant):
    sc = plant.scenario
    _descend_over_anchor(plant, offset=0.03)
    assert plant.cable_engaged
    (event,) = plant.hook.events
    assert event.kind is HookEventKind.ENGAGED and event.distance == pytest.approx(0.03, abs=1e-6)
    assert 0.0 <= plant.tension <= _slack_tension(plant)  # slack: engaged 0.5 m < l from p_A
    assert plant.frame_contact_force == 0.0 and not np.any(plant.lander_forces)
    # Fly away sideways: the cable stops the vehicle at length l.
    s = plant.state()
    plant.set_state(RigidBodyState(s.p_W, np.array([0.0, 0.6, 0.0]), s.q_WB, s.omega_B))
    longest, peak = 0.0, 0.0
    for _ in range(1500):
        plant.step()
        longest, peak = max(longest, plant.cable_length), max(peak, plant.tension)
    assert peak > 10.0  # the cable snapped taut
    stretch = sc.tether.stretch(peak)  # 0 for the ideal cable
    assert longest < sc.tether.length + stretch + 2e-3  # elastic stretch + compliant limit
    assert (
        abs(np.linalg.norm(plant.attachment_point() - plant.layout.geometry.p_A))
        < sc.tether.length + stretch + 1e-3
    )


def test_offset_beyond_capture_radius_misses(plant):
    _descend_over_anchor(plant, offset=0.15)  # capture radius 0.1 m
    assert not plant.cable_engaged
    (event,) = plant.hook.events
    assert event.kind is HookEventKind.MISSED and event.distance == pytest.approx(0.15, abs=1e-6)
    # disengaged cable: flying far away produces no tension
    s = plant.state()
    plant.set_state(RigidBodyState(s.p_W, np.array([0.0, 2.0, 0.0]), s.q_WB, s.omega_B))
    plant.step(1000)
    assert np.linalg.norm(plant.attachment_point() - plant.layout.geometry.p_A) > 1.5
    assert plant.tension == 0.0


def test_flying_back_out_the_same_way_releases(plant):
    _descend_over_anchor(plant, offset=0.0)
    assert plant.cable_engaged
    s = plant.state()
    plant.set_state(RigidBodyState(s.p_W, -s.v_W, s.q_WB, s.omega_B))  # reverse the path
    plant.step(700)
    assert not plant.cable_engaged
    assert [e.kind for e in plant.hook.events] == [HookEventKind.ENGAGED, HookEventKind.RELEASED]
    plant.step(10)
    assert plant.tension == 0.0  # released: no force of any cable model
    if plant.cable.kind.value == "ideal":
        assert plant.model.tendon_limited[0] == 0
    if plant.cable.kind.value == "chain":
        assert plant.data.eq_active[0] == 0


def test_hook_settings_are_validated():
    with pytest.raises(ConfigError, match="hook_drop"):
        load_scenario("slope50", ["tether.hook_drop=0.95"])
    with pytest.raises(ConfigError, match="approach_direction"):
        load_scenario("slope50", ["tether.approach_direction=[0,0,0]"])


def test_teleporting_is_not_a_crossing(plant):
    """set_state/reset restart the hook tracking: jumping through the disk does not hook."""
    geo = plant.layout.geometry
    sc = plant.scenario
    above = geo.p_A + np.array([0.0, 0.0, sc.tether.hook_drop + 0.2])
    below = geo.p_A + np.array([0.0, 0.0, sc.tether.hook_drop - 0.05])
    q = plant.start_state().q_WB
    plant.reset(RigidBodyState.at_rest(above, q))
    plant.set_state(RigidBodyState.at_rest(below, q))
    plant.step(2)
    assert not plant.cable_engaged and not plant.hook.events


# -- hooking along any direction: steep slopes, walls, overhangs ---------------------------

_WALL_DESIGN = [
    "tether.length=0.4", "vehicle.cable_attachment=[0,0,0]", "anchor.h_A=0",
    "tether.hook_drop=0.34", "tether.capture_radius=0.05", "mission.hooking.overshoot=0.05",
]  # fmt: skip


def _normal_approach(slope_deg: float) -> str:
    """-n_S in F_A: straight at the surface along its normal."""
    b = math.radians(slope_deg)
    return f"tether.approach_direction=[{-math.sin(b)!r},0,{-math.cos(b)!r}]"


DIRECTIONS = {
    "normal-80": ["surface.slope_deg=80", _normal_approach(80.0)],
    "horizontal-wall": ["surface.slope_deg=90", "tether.approach_direction=[-1,0,0]"],
    "normal-overhang-93": ["surface.slope_deg=93", _normal_approach(93.0)],
}


@pytest.fixture(scope="module", params=[(d, c) for d in sorted(DIRECTIONS) for c in sorted(CABLES)])
def directed_plant(request):
    direction, cable = request.param
    return Plant(
        load_scenario("slope50", _WALL_DESIGN + DIRECTIONS[direction] + CABLES[cable] + NO_AERO)
    )


def _fly_pass(plant: Plant, across: float, speed: float = 0.3) -> tuple[float, np.ndarray]:
    """Level at hover thrust, the hook point from 0.1 m before the capture disk to
    ``mission.hooking.overshoot`` beyond it along n, ``across`` off the anchor along y_A.
    Returns the largest frame and lander contact force during the pass [N] and n_W."""
    sc = plant.scenario
    geo = plant.layout.geometry
    n_W = plant.layout.approach_W
    np.testing.assert_allclose(plant.hook.n_W, n_W, atol=1e-15)
    hook0 = geo.p_A - 0.1 * n_W + across * geo.R_WA[:, 1]
    q = plant.start_state().q_WB  # level, x_B along x_A: the mission's heading
    p_att_B = np.asarray(sc.vehicle.cable_attachment)
    p_com = hook0 - sc.tether.hook_drop * n_W - p_att_B  # level: R_WB r_att = r_att here
    w = math.sqrt(sc.vehicle.mass * GRAVITY / 4 / sc.vehicle.thrust_coefficient)
    plant.reset(RigidBodyState(p_com, speed * n_W, q, np.zeros(3)), rotor_speeds=np.full(4, w))
    np.testing.assert_allclose(plant.hook.hook_point(plant.attachment_point()), hook0, atol=1e-12)
    touch = 0.0
    for _ in range(round((0.1 + sc.mission.hooking.overshoot) / speed / plant.dt)):
        plant.step()
        touch = max(touch, plant.frame_contact_force + float(np.sum(plant.lander_forces)))
    return touch, n_W


def test_hooking_along_the_approach_direction_engages_then_holds(directed_plant):
    """Along the normal of an 80 deg slope or a 93 deg overhang, horizontally toward a
    wall: the hook point held hook_drop ahead along n catches the anchor; the frame keeps
    off the surface (the pass the mission flies); the engaged cable then holds at l."""
    plant = directed_plant
    sc = plant.scenario
    touch, n_W = _fly_pass(plant, across=0.02)
    assert touch == 0.0
    assert plant.cable_engaged
    (event,) = plant.hook.events
    assert event.kind is HookEventKind.ENGAGED
    assert event.distance == pytest.approx(0.02, abs=1e-6)  # the pass is along n exactly
    geo = plant.layout.geometry
    assert float(n_W @ (event.point_W - geo.p_A)) == pytest.approx(0.0, abs=1e-9)  # on the disk
    assert 0.0 <= plant.tension <= _slack_tension(plant, speed=0.3)
    # Fly parallel to the capture plane, down the surface: no crossing, the cable snaps taut.
    x_S = geo.surface.x_S
    u = x_S - (x_S @ n_W) * n_W
    u /= np.linalg.norm(u)
    s = plant.state()
    plant.set_state(RigidBodyState(s.p_W, 0.6 * u, s.q_WB, s.omega_B))
    longest, peak = 0.0, 0.0
    for _ in range(800):
        plant.step()
        longest, peak = max(longest, plant.cable_length), max(peak, plant.tension)
    assert plant.cable_engaged and len(plant.hook.events) == 1
    assert peak > 5.0  # stopped by the cable
    assert longest < sc.tether.length + sc.tether.stretch(peak) + 2e-3


def test_the_reverse_pass_releases_along_any_direction(directed_plant):
    plant = directed_plant
    _fly_pass(plant, across=0.0)
    assert plant.cable_engaged
    s = plant.state()
    plant.set_state(RigidBodyState(s.p_W, -s.v_W, s.q_WB, s.omega_B))  # the unhooking pass
    plant.step(round(0.15 / 0.3 / plant.dt))
    assert not plant.cable_engaged
    assert [e.kind for e in plant.hook.events] == [HookEventKind.ENGAGED, HookEventKind.RELEASED]
    assert plant.hook.events[-1].distance < 1e-4  # a chain's weight pulls a little
    plant.step(10)
    assert plant.tension == 0.0


def test_a_pass_beside_the_capture_disk_misses_along_any_direction(directed_plant):
    plant = directed_plant
    _fly_pass(plant, across=0.08)  # capture radius 0.05 m
    assert not plant.cable_engaged
    (event,) = plant.hook.events
    assert event.kind is HookEventKind.MISSED and event.distance == pytest.approx(0.08, abs=1e-6)


def test_hook_point_leads_the_attachment_along_n():
    """The plant's hook model is the one of models.hook: hook = attachment + hook_drop n."""
    from tetherland.models.hook import hook_offset

    n = np.array([-3.0, 0.0, 4.0])  # not unit: the model normalises it
    hook = Hook([1.0, 2.0, 3.0], n, capture_radius=0.05, hook_drop=0.3)
    np.testing.assert_allclose(hook.offset_W, hook_offset(n / 5.0, 0.3), atol=1e-15)
    p_att = np.array([1.5, 2.0, 2.2])
    np.testing.assert_allclose(hook.hook_point(p_att), p_att + 0.3 * n / 5.0, atol=1e-15)
    # side() is the signed distance of the hook point along n, and plane() agrees with it
    expect = float((p_att + 0.3 * n / 5.0 - [1.0, 2.0, 3.0]) @ (n / 5.0))
    assert hook.side(*p_att) == pytest.approx(expect, abs=1e-15)
    nx, ny, nz, c = hook.plane
    assert nx * p_att[0] + ny * p_att[1] + nz * p_att[2] - c == pytest.approx(expect, abs=1e-15)
