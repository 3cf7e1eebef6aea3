"""Every part of the vehicle collides (issue 22, item 2): legs, arms and the cable's mount
are contact geometry shared by the plant and the clearance check, their contacts are read
at every physics step, and a crash names the part, the phase, the time and the force.

The crash scenes are a level landing patch (``surface.slope_deg=0``) with the ground far
below: the vehicle is dropped from rest with the motors off so that one part overhangs the
patch's edge and hits it first. On a plane the landers always touch first (every other
part lies inside the hull of the landers and guards, see
:func:`test_the_landers_touch_a_plane_first`); an edge or a step under an arm or a leg is
what a real vehicle hits them with.
"""

from __future__ import annotations

import json
import math

import mujoco
import numpy as np
import pytest

from penetration import assert_nothing_behind_surfaces, deepest_behind
from tetherland import GRAVITY
from tetherland.analysis.clearance import part_distances, segment_distance, surface_distance
from tetherland.campaign.jobs import campaign_fields
from tetherland.config import builtin_scenarios, load_scenario
from tetherland.geometry import LandingGeometry
from tetherland.mission import Phase
from tetherland.models.airframe import Airframe
from tetherland.rotations import rotmat_to_quat
from tetherland.runs.closed_loop import RunResult
from tetherland.sim.baselines import ConstantReference, ConstantSpeedController
from tetherland.sim.mjcf import FRAME_PARTS, VEHICLE_CONAFFINITY, VEHICLE_CONTYPE
from tetherland.sim.plant import CONTACT_PEAK_WIDTH, Plant
from tetherland.sim.runner import Runner
from tetherland.state import RigidBodyState
from tetherland.verdict import Expectations, RunRecord, judge

DROP = 0.02
"""Free fall of the part onto the edge [m]."""


def _geom(plant: Plant, name: str) -> int:
    return mujoco.mj_name2id(plant.model, mujoco.mjtObj.mjOBJ_GEOM, name)


def _distance(plant: Plant, a: str, b: str) -> float:
    """MuJoCo's signed distance between geoms ``a`` and ``b`` (up to 1 m) [m]."""
    fromto = np.zeros(6)
    return mujoco.mj_geomDistance(plant.model, plant.data, _geom(plant, a), _geom(plant, b),
                                  1.0, fromto)  # fmt: skip


def _vehicle_geoms(plant: Plant) -> list[str]:
    m = plant.model
    body = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "vehicle")
    return [
        mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g)
        for g in range(m.ngeom)
        if m.body_rootid[m.geom_bodyid[g]] == body and (m.geom_contype[g] or m.geom_conaffinity[g])
    ]


def _rotation(d_B: np.ndarray, d_W: np.ndarray, alpha: float) -> np.ndarray:
    """R_WB taking the horizontal body direction ``d_B`` to cos(alpha) d_W + sin(alpha) z_W
    (``d_W`` horizontal): the vehicle pitched by alpha about the horizontal axis across
    d_W, the end of ``d_B`` raised for alpha > 0."""
    z = np.array([0.0, 0.0, 1.0])
    w_d = math.cos(alpha) * d_W + math.sin(alpha) * z
    w_z = -math.sin(alpha) * d_W + math.cos(alpha) * z
    q_B = np.cross(z, d_B)
    return np.column_stack((w_d, np.cross(w_z, w_d), w_z)) @ np.column_stack((d_B, q_B, z)).T


def _record(truth) -> RunRecord:
    return RunRecord(
        method="tethered", seed=0, truth=truth.model_dump(mode="json"),
        belief=truth.model_dump(mode="json"), expects=Expectations(), finished=True,
        phase_codes={p.name.lower(): int(p) for p in Phase},
    )  # fmt: skip


@pytest.fixture(scope="module")
def edge_world():
    """A level patch whose downhill edge the vehicle overhangs, the ground 2 m below."""
    truth = load_scenario("slope50", ["surface.slope_deg=0", "sim.ground_z=-2.0"])
    geo = LandingGeometry.from_scenario(truth)
    x_S = geo.surface.x_S
    assert abs(x_S[2]) < 1e-12  # level: the edge is horizontal, outward along x_S
    edge = geo.surface.origin + truth.surface.extent * x_S
    return truth, Plant(truth), edge, x_S


def test_every_part_collides_with_the_world_and_no_part_with_another():
    plant = Plant(load_scenario("slope50"))
    m = plant.model
    names = _vehicle_geoms(plant)
    assert sorted(names) == sorted([*FRAME_PARTS, *(f"lander{i}" for i in range(4))])
    for name in names:
        g = _geom(plant, name)
        assert (m.geom_contype[g], m.geom_conaffinity[g]) == (VEHICLE_CONTYPE, VEHICLE_CONAFFINITY)
    # MuJoCo's rule: a pair collides iff contype_a & conaffinity_b or contype_b & conaffinity_a
    for world in ("surface", "ground"):
        w = _geom(plant, world)
        w_type, w_affinity = m.geom_contype[w], m.geom_conaffinity[w]
        assert (VEHICLE_CONTYPE & w_affinity) or (w_type & VEHICLE_CONAFFINITY)
    assert not (VEHICLE_CONTYPE & VEHICLE_CONAFFINITY)  # two vehicle geoms never collide


@pytest.mark.parametrize("name", ["slope50", "pipe60", "wall90"])
def test_the_clearance_check_and_the_plant_share_every_part(name):
    """At tilted poses 3-25 cm off the surface, the distance the plan-stage check computes
    for each part (:func:`part_distances`) is MuJoCo's distance of that geom: exact for
    the spheres and capsules (legs, arms, mount, landers), within the 5 degree rim sampling
    for the rotor guards, and from above for the hub's corners."""
    truth = load_scenario(name)
    plant = Plant(truth)
    surf = LandingGeometry.from_scenario(truth).surface
    rng = np.random.default_rng(22)
    for _ in range(6):
        axis = rng.normal(size=3)
        angle = rng.uniform(0.0, 0.8)
        K = np.cross(np.eye(3), axis / np.linalg.norm(axis))
        R = np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K
        R = surf.R_WS @ R  # tilted from the surface frame
        p = surf.origin + rng.uniform(-0.3, 0.3) * surf.y_S + rng.uniform(0.3, 0.5) * surf.z_S
        plant.set_state(RigidBodyState.at_rest(p, rotmat_to_quat(R)))
        # move along z_S until the nearest part is 3-25 cm away (keeps MuJoCo's distance
        # query well inside its 1 m range)
        predicted = part_distances(truth.vehicle, surf, p, R)
        p = p + (rng.uniform(0.03, 0.25) - min(predicted.values())) * surf.z_S
        plant.set_state(RigidBodyState.at_rest(p, rotmat_to_quat(R)))
        predicted = part_distances(truth.vehicle, surf, p, R)
        for part in [*(f"leg{i}" for i in range(4)), *(f"arm{i}" for i in range(4)), "mount"]:
            assert _distance(plant, "surface", part) == pytest.approx(predicted[part], abs=2e-5)
        landers = min(_distance(plant, "surface", f"lander{i}") for i in range(4))
        assert landers == pytest.approx(predicted["landers"], abs=2e-5)
        guards = min(_distance(plant, "surface", f"prop{i}") for i in range(4))
        assert guards == pytest.approx(predicted["guards"], abs=5e-4)
        assert _distance(plant, "surface", "hub") <= predicted["hub"] + 2e-5


def test_segment_distance_is_exact_on_a_pipe():
    """A segment crossing over a pipe: its least distance is where it passes the axis, not
    at an end (the ends' distances are larger)."""
    surf = LandingGeometry.from_scenario(load_scenario("pipe60")).surface
    R = surf.pipe_radius
    top = surf.origin + 0.4 * surf.x_S + 0.05 * surf.z_S  # 5 cm above the top line
    a, b = top - 0.2 * surf.y_S, top + 0.2 * surf.y_S
    assert segment_distance(surf, a, b)[0] == pytest.approx(0.05, abs=1e-12)
    assert surface_distance(surf, a)[0] == pytest.approx(math.hypot(R + 0.05, 0.2) - R)


@pytest.mark.parametrize("name", [s.name for s in builtin_scenarios()])
def test_the_landers_touch_a_plane_first(name):
    """The vehicle of every built-in scenario, its landers touching a plane with z_B up to
    30 deg off the normal in any direction: every other part is at least 5 mm off it. A
    leg reaches the plane before its lander only past atan(dz/dr) + asin((1 - 0.35) r /
    leg length) = 36 deg of tilt (its slope under the hub plus the radii), and then the
    landers of the other side are lower still."""
    truth = load_scenario(name)
    surf = LandingGeometry.from_scenario(load_scenario("slope50")).surface
    frame = Airframe.of(truth.vehicle)
    leg = frame.capsule("leg0")
    d = leg.b_B - leg.a_B
    r_xy, dz = float(np.hypot(d[0], d[1])), float(-d[2])
    leg_tilt = math.atan2(dz, r_xy) + math.asin(
        (frame.lander_radius - leg.radius) / float(np.linalg.norm(d))
    )
    assert math.degrees(leg_tilt) > 30.0
    for tilt in np.radians([0.0, 10.0, 20.0, 30.0]):
        for azimuth in np.radians(np.arange(0.0, 360.0, 15.0)):
            axis = np.array([math.cos(azimuth), math.sin(azimuth), 0.0])
            K = np.cross(np.eye(3), axis)
            R = surf.R_WS @ (np.eye(3) + math.sin(tilt) * K + (1 - math.cos(tilt)) * K @ K)
            d0 = part_distances(truth.vehicle, surf, surf.origin, R)
            p = surf.origin - d0["landers"] * surf.z_S  # the lowest lander on the plane
            parts = part_distances(truth.vehicle, surf, p, R)
            assert parts.pop("landers") == pytest.approx(0.0, abs=1e-12)
            assert min(parts.values()) > 0.005, (math.degrees(tilt), math.degrees(azimuth))


def test_the_landed_pose_on_the_pipe_keeps_the_hub_and_mount_off_it():
    """pipe60's landed pose: the landers on the pipe, their centres R + r from the axis at
    +-w across it, so the centre of mass sqrt((R + r)^2 - w^2) + h_R - r above the axis;
    the cable's mount (its sphere's bottom |z_att| + r_m under the centre of mass) clears
    the pipe by that minus R minus its depth."""
    truth = load_scenario("pipe60")
    plant = Plant(truth)
    s = plant.landed_state()
    surf = plant.layout.geometry.surface
    R_WB = s.R_WB
    parts = part_distances(truth.vehicle, surf, s.p_W, R_WB)
    assert parts.pop("landers") == pytest.approx(0.0, abs=1e-6)
    v = truth.vehicle
    R, w, r = surf.pipe_radius, v.lander_half_width, v.lander_radius
    com = math.sqrt((R + r) ** 2 - w * w) + v.h_R - r  # above the axis
    mount_depth = -v.cable_attachment[2] + Airframe.of(v).mount_radius
    assert parts["mount"] == pytest.approx(com - R - mount_depth, abs=1e-6)
    assert min(parts.values()) > 0.005


def _drop_pose(frame: Airframe, part: str, edge, x_S, alpha: float):
    """Where to hold the vehicle so that ``part`` overhangs the edge: (d_B, offset) with
    d_B the part's horizontal direction in F_B, pointing back over the patch (-x_S)."""
    c = frame.capsule(part)
    d = c.b_B[:2] / np.linalg.norm(c.b_B[:2])
    d_B = np.array([d[0], d[1], 0.0])
    return d_B, _rotation(d_B, -x_S, alpha)


def _settle_height(plant: Plant, part: str, p_xy, R, drop: float) -> np.ndarray:
    """The centre of mass above ``p_xy`` such that ``part`` falls ``drop`` straight down
    before it touches the surface (bisection on MuJoCo's geom distance: the patch's edge
    is not a plane)."""
    q = rotmat_to_quat(R)

    def inside(z: float) -> bool:
        plant.set_state(RigidBodyState.at_rest(np.array([p_xy[0], p_xy[1], z]), q))
        return _distance(plant, "surface", part) < 0.0

    hi = 0.5
    while not inside(hi - 0.005):  # down in 5 mm steps (the patch is 10 cm thick)
        hi -= 0.005
    lo = hi - 0.005  # touching in between: the part inside at lo, clear at hi
    for _ in range(50):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if inside(mid) else (lo, mid)
    p = np.array([p_xy[0], p_xy[1], hi + drop])
    plant.set_state(RigidBodyState.at_rest(p, rotmat_to_quat(R)))
    return p


def _first_to_touch(plant: Plant, state: RigidBodyState, part: str, drop: float) -> None:
    """Assert that ``part`` is the first geom of the vehicle to reach the surface when
    ``state`` falls straight down by ``drop`` plus 3 mm."""
    names = _vehicle_geoms(plant)
    for h in np.linspace(0.0, drop + 0.003, 47):
        plant.set_state(RigidBodyState.at_rest(state.p_W - [0.0, 0.0, h], state.q_WB))
        for g in names:
            if g != part:
                assert _distance(plant, "surface", g) > 0.0, (g, h)
    assert _distance(plant, "surface", part) < 0.0


def _arm_drop(edge_world):
    """arm0's end cap over the edge: the rotor centre 4 mm inside it, lander0 (whose reach
    along the arm is shorter) 4 mm outside, the arm's end 3 deg down so that its cap alone
    touches; arm0 2 cm above the patch."""
    truth, plant, edge, x_S = edge_world
    frame = Airframe.of(truth.vehicle)
    arm = frame.capsule("arm0")
    rotor_reach = float(np.linalg.norm(arm.b_B[:2]))
    lander_reach = float(np.linalg.norm(frame.lander_centres_B[0, :2])) + frame.lander_radius
    assert lander_reach < rotor_reach  # the edge can pass between them
    offset = 0.5 * (rotor_reach + lander_reach)
    _, R = _drop_pose(frame, "arm0", edge, x_S, math.radians(-3.0))
    p = _settle_height(plant, "arm0", edge + offset * x_S, R, DROP)
    return truth, plant, RigidBodyState.at_rest(p, rotmat_to_quat(R))


def test_an_arm_hitting_an_edge_is_a_crash_named_with_its_phase_time_and_force(edge_world):
    """Dropped 2 cm with arm0 over the patch's edge: the judge's crash record names arm0,
    the phase the log holds, the time of the fall sqrt(2 h / g) (to a control period and
    a physics step), and the peak normal force the plant saw at the physics rate. The
    impulse of that contact's per-step normal forces equals the vehicle's change of
    vertical momentum plus gravity's impulse over the impact, and while the arm's end
    presses on the level face (normal z_W, friction horizontal) it is the vertical force;
    the plant's force is the sum over every contact of the arm (MuJoCo's contact list,
    mj_contactForce)."""
    truth, plant, state = _arm_drop(edge_world)
    _first_to_touch(plant, state, "arm0", DROP)

    # the physics, step by step: the arm's contact forces from MuJoCo's contact list
    plant.reset(state)
    m, d = plant.model, plant.data
    arm = _geom(plant, "arm0")
    i_arm = FRAME_PARTS.index("arm0")
    f6 = np.zeros(6)
    steps = []  # (t, sensor force on arm0, own normal force sum, other parts, v_z)
    for _ in range(150):
        v_before = plant.qvel[2]
        t = plant.time
        plant.step(1)
        own, lift = 0.0, 0.0  # the arm's normal forces, and their pull on the vehicle along z_W
        for i in range(d.ncon):
            g1, g2 = d.contact.geom1[i], d.contact.geom2[i]
            if arm in (g1, g2):
                mujoco.mj_contactForce(m, d, i, f6)
                own += f6[0]
                # the force on geom2 in F_W is frame^T f (the frame's rows: normal from
                # geom1 to geom2, tangents); the vehicle gets it if it is geom2
                f_W = d.contact.frame[i].reshape(3, 3).T @ f6[:3]
                lift += f_W[2] if g2 == arm else -f_W[2]
        parts = plant.part_forces
        other = float(np.delete(parts, i_arm).max()) + float(plant.lander_forces.max())
        steps.append((t, float(parts[i_arm]), own, other, v_before, lift))
    steps = np.array(steps)
    touching = np.flatnonzero(steps[:, 1] > 0.0)
    k0 = int(touching[0])
    # the impact: until the arm lets go or another part (pivoting about the edge) touches
    alone = (steps[k0:, 1] > 0.0) & (steps[k0:, 3] == 0.0)
    k1 = k0 + (int(np.argmin(alone)) if not alone.all() else len(alone) - 1)
    assert k1 > k0 + 10  # a soft contact of several steps
    np.testing.assert_allclose(steps[k0:k1, 1], steps[k0:k1, 2], rtol=1e-9)  # every contact
    t_hit = math.sqrt(2 * DROP / GRAVITY)
    assert abs(steps[k0, 0] - t_hit) <= 2 * plant.dt
    mass, dt = truth.vehicle.mass, plant.dt
    impulse = float(steps[k0:k1, 5].sum() * dt)
    momentum = mass * (steps[k1, 4] - steps[k0, 4]) + mass * GRAVITY * (k1 - k0) * dt
    assert impulse == pytest.approx(momentum, rel=1e-6) and impulse > 0.0
    # while the arm's end presses on the face (before it slides onto the edge) the normal
    # is z_W: the impulse of the normal forces the plant reports is that impulse
    tilted = np.abs(steps[k0:k1, 5] - steps[k0:k1, 1]) > 1e-9 * steps[k0, 1]
    flat = k0 + (int(np.argmax(tilted)) if tilted.any() else k1 - k0)
    assert flat > k0 + 5
    np.testing.assert_allclose(steps[k0:flat, 1], steps[k0:flat, 5], rtol=1e-9)

    # the same drop through the runner and the judge
    period = 1.0 / truth.controller.rate_hz
    runner = Runner(truth, ConstantSpeedController.motors_off(), plant=plant,
                    reference=ConstantReference(phase=int(Phase.TETHERED_LANDING)))  # fmt: skip
    log = runner.run(0.15, initial_state=state)
    record = _record(truth)
    verdict = judge(log, record)
    crash = verdict.summary["crash"]
    assert verdict.summary["crashed"] and verdict.outcome.value == "crashed"
    assert crash["part"] == "arm0" and crash["phase"] == "tethered_landing"
    assert steps[k0, 0] <= crash["t"] < steps[k0, 0] + period
    assert crash["force_N"] == pytest.approx(steps[k0:k1, 1].max(), rel=1e-6)
    assert "arm0" in verdict.reason
    # a campaign's results.jsonl line carries the same record, and explains the failure
    result = RunResult("tethered", record, verdict, log, None, None, truth, truth)
    fields = json.loads(json.dumps(campaign_fields(result)))
    assert fields["crash"] == crash
    first = fields["failures"][0]
    assert (first["outcome"], first["part"], first["phase"]) == (
        "crashed",
        "arm0",
        "tethered_landing",
    )
    assert first["force_N"] == crash["force_N"] and first["t"] == crash["t"]
    # every logged tick holds the peak of its control period's physics steps
    n = round(period / dt)
    for row in range(1, len(log)):
        k = round(log["t"][row] / dt)
        window = steps[k - n + 1 : k + 1, 1] if k < len(steps) else None
        if window is not None and window.size == n:
            assert log["frame_force"][row] == pytest.approx(window.max(), rel=1e-6, abs=1e-12)


def test_a_leg_hitting_an_edge_before_its_lander_is_a_crash(edge_world):
    """Pitched 45 deg (leg0's outer end up: past the 36 deg at which the leg slopes up
    from its root), leg0 crossing the edge 2 cm above it and lander0 over the patch but
    higher: the leg hits the edge first and the crash names leg0, at the fall time."""
    truth, plant, edge, x_S = edge_world
    frame = Airframe.of(truth.vehicle)
    alpha = math.radians(45.0)
    _, R = _drop_pose(frame, "leg0", edge, x_S, alpha)
    leg = frame.capsule("leg0")
    # the edge under the leg, 1 cm outward of the outermost point of the hub, the mount and
    # the other legs and landers along the leg's world direction -x_S (lander0 and arm0
    # overhang the patch too, higher)
    reach = []
    for g in ("hub", "mount", "leg1", "leg2", "leg3", "lander1", "lander2", "lander3"):
        plant.set_state(RigidBodyState.at_rest(np.zeros(3), rotmat_to_quat(R)))
        reach.append(_extent(plant, g, -x_S))
    root = float(-(R @ leg.a_B) @ x_S)  # the leg's root along -x_S
    offset = max(max(reach), root) + 0.01
    assert offset < float(-(R @ leg.b_B) @ x_S)  # the leg does cross the edge
    p = _settle_height(plant, "leg0", edge + offset * x_S, R, DROP)
    state = RigidBodyState.at_rest(p, rotmat_to_quat(R))
    _first_to_touch(plant, state, "leg0", DROP)
    runner = Runner(truth, ConstantSpeedController.motors_off(), plant=plant,
                    reference=ConstantReference(phase=int(Phase.TOUCHDOWN)))  # fmt: skip
    log = runner.run(0.15, initial_state=state)
    crash = judge(log, _record(truth)).summary["crash"]
    period = 1.0 / truth.controller.rate_hz
    assert crash["part"] == "leg0" and crash["phase"] == "touchdown"
    assert crash["force_N"] > 0.0
    assert abs(crash["t"] - math.sqrt(2 * DROP / GRAVITY)) <= period + 2 * plant.dt


def _extent(plant: Plant, geom: str, direction: np.ndarray) -> float:
    """How far geom reaches along the horizontal ``direction`` from the centre of mass
    (its bounding sphere: an upper bound) [m]."""
    g = _geom(plant, geom)
    m, d = plant.model, plant.data
    return float((d.geom_xpos[g] - d.qpos[0:3]) @ direction + m.geom_rbound[g])


def test_a_contact_of_one_physics_step_is_seen(edge_world):
    """arm0 pressed 1 mm into the patch for one physics step, the vehicle then moved away
    before the next: the control tick after the two steps finds no contact in the
    sensors, the peak it reads holds the step's force, the part and the depth."""
    _, plant, state = _arm_drop(edge_world)
    into = RigidBodyState.at_rest(state.p_W - (DROP + 0.001) * np.array([0.0, 0.0, 1.0]),
                                  state.q_WB)  # fmt: skip
    plant.reset(into)
    assert plant.penetration == pytest.approx(0.001, abs=2e-4)  # arm0's cap, 1 mm in
    plant.step(1)
    force = plant.part_forces[FRAME_PARTS.index("arm0")]
    assert force > 0.0
    plant.set_state(state)  # 2 cm up again
    plant.step(1)
    assert plant.frame_contact_force == 0.0  # what sampling at the control tick would see
    peaks = np.zeros(CONTACT_PEAK_WIDTH)
    plant.contact_peaks_into(peaks)
    assert peaks[8] == force
    assert FRAME_PARTS[int(peaks[9])] == "arm0"
    assert peaks[10] == pytest.approx(0.001, abs=2e-4)
    plant.contact_peaks_into(peaks)
    assert peaks[8] == 0.0 and peaks[9] == -1 and peaks[10] == 0.0


def test_no_crash_on_the_start_pad_and_no_part_but_the_landers_touches(slope50):
    """Resting on the pad 0.5 s: the landers carry the weight, no part crashes, and the
    contact distance stays far under the 2 mm limit the missions are held to."""
    runner = Runner(slope50, ConstantSpeedController.motors_off())
    log = runner.run(0.5)
    assert np.nanmax(log["frame_force"]) == 0.0 and set(log["frame_part"]) == {-1.0}
    assert log["lander_ground_forces"][-1].sum() == pytest.approx(
        slope50.vehicle.mass * GRAVITY, rel=1e-3
    )
    assert 0.0 < log["penetration"].max() < 0.002
    assert judge(log, _record(slope50)).summary["crash"] is None


def test_the_penetration_check_sees_a_vehicle_5_mm_inside_the_surface(slope50):
    """Started in the landed pose pushed 5 mm into the slope: MuJoCo's contact distance
    and the geometry of the logged pose both measure the 5 mm at t = 0, and the mission
    tests' check refuses the run; 1 mm in, it passes."""
    plant = Plant(slope50)
    landed = plant.landed_state()
    z_S = plant.layout.geometry.surface.z_S
    for depth, ok in ((0.005, False), (0.001, True)):
        start = RigidBodyState.at_rest(landed.p_W - depth * z_S, landed.q_WB)
        log = Runner(slope50, ConstantSpeedController.motors_off(), plant=plant).run(
            0.01, initial_state=start, cable_engaged=True
        )
        found = {m.where: m for m in deepest_behind(log, slope50)}
        assert found["mujoco"].depth_m == pytest.approx(depth, rel=0.02)
        assert found["surface"].depth_m == pytest.approx(depth, abs=1e-6)
        assert found["mujoco"].t == found["surface"].t == 0.0
        if ok:
            assert_nothing_behind_surfaces(log, slope50)
        else:
            with pytest.raises(AssertionError, match=r"\d\.\d\d mm behind a surface"):
                assert_nothing_behind_surfaces(log, slope50)
