"""Hot-path workloads for instruction counts (valgrind callgrind): load-independent speed.

Wall-clock timings on the shared 2-core machine vary by 30 % and more; instruction counts
do not. Each workload runs its hot path ``n`` times after a warm-up, inside a call of
``math.fsum`` (a C function nothing else here uses), so that callgrind counts only the
hot path with ``--toggle-collect=math_fsum``:

    valgrind --tool=callgrind --toggle-collect=math_fsum --callgrind-out-file=/dev/null \\
        .venv/bin/python benchmarks/hotpaths.py WORKLOAD N

Workloads: ``free_flight``, ``hierarchical``, ``dfl`` (one controller update),
``estimator`` (one control tick: two IMU samples, the estimate, a mocap update every 4th
tick), ``mission`` (the runner loop of N full slope50 missions, counted per control tick;
prints the number of ticks), ``aero`` (the plant's surface-factor kernel ``aero_into``
of slope50, cycling over poses near the slope, on the pad and at cruise height),
``believed`` (the estimator's believed ground effect at the same poses),
``compensation`` (the controller wrappers of a mission, rotor-drag feed-forward and
ground-effect compensation, around a controller that returns fixed speeds: the same poses,
moving, with free-flight references of 2 to 4 rows and tethered ones in turn),
``stack`` and ``stack_layered`` (a mission's whole controller, the wrappers around the
switching controller, on free-flight ticks at the same poses: the tick in one compiled
call, :class:`~tetherland.control.stack.CompiledStack`, or through the layers) and
``plant`` (one physics step of the slope50 plant, :meth:`Plant.step`, as the runner calls
it: the command changed every second step, cycling over 16 starts near the slope with the
cable engaged, each held for 64 steps; counted per physics step, the restarts included).
``bar_free`` and ``bar_seated`` are the same with the bar mechanism (a 69-dof tree: the
vehicle, the 20-link hanging line and the hook): the hook hanging and swinging under the
vehicle hovering at 1.5 m (no contact), and the hook seated on the bar with the line
pulled to 3 N by a vehicle driven over the bar as in the catch test (contacts of the line
and the hook with the bar, elliptic cones), each restarted every 64 steps from its state.
Both fly the flat arm (``mechanism.hook_arm_rise_deg = 0``), the workload measured
below, since kept when the default became the rising arm (25 deg).
Measured (issue 25, s25-barstep against 2291551, the same workload file): ``bar_free``
788.1k -> 759.6k instructions per physics step (the line's armature and crown checks
skipped when they cannot change anything; the same bits); ``bar_seated`` not counted yet
(its warm-up, the catch, takes many minutes under valgrind): MuJoCo's step alone,
replayed from contact states of a slope50 bar mission, 2.59M -> 2.07M with the sparse
Jacobian.
``benchmarks/bench_callgrind.sh`` runs them all and prints instructions per call.

Measured (issue 25, exact culling in ``aero_into``, the same bits): ``aero`` 74.6k ->
53.7k and ``believed`` 68.5k -> 56.1k instructions per call, main b01e26b -> i25-speed
(the same workload file run against both source trees). The believed aerodynamics
compiled (one call per wrapper per tick, the belief's one shape, the same bits):
``compensation`` 255.9k -> 84.6k, ``believed`` 55.7k -> 26.6k and ``estimator`` 280.5k ->
234.0k instructions per call, main 2900ad9 -> s25-ctrl-aero. The plant's step
(sim/step_kernel.py, no row views in the aero kernel's ray loop; the same bits): ``aero``
53.7k -> 34.5k instructions per call and ``plant`` 170.9k -> 136.0k per physics step, main
2900ad9 -> s25-plant. The estimator's steps one compiled call each on packed per-run state
(the same bits): ``estimator`` 201.4k -> 166.2k instructions per call, main 5b110a9 ->
s25-est (the same workload file run against both source trees). A mission's whole
controller on free-flight ticks (the same tree, 7eacded): ``stack_layered`` 89.8k ->
``stack`` 61.6k instructions per call (the layers' four calls as one); ``mission`` 730.3k
(7754ade) -> 703.9k (7eacded) per control tick. Under valgrind numba
sees another CPU and recompiles every kernel once (its cache is keyed by CPU features):
the first callgrind run of a tree takes tens of minutes.
"""

from __future__ import annotations

import functools
import math
import sys

import mujoco
import numpy as np

from tetherland.config import load_scenario


@functools.lru_cache(maxsize=1)
def _landing():
    """A slope50 landing plan, its reference track and an estimate on it at t = 1 s."""
    from tetherland.geometry import LandingGeometry
    from tetherland.planning import Planner
    from tetherland.planning.tracking import TrajectoryTrack
    from tetherland.rotations import rotmat_to_quat
    from tetherland.sim.analytic import estimate_of

    sc = load_scenario("slope50")
    traj = Planner().plan(sc, "landing").require()
    track = TrajectoryTrack(traj, 0.0, 500.0)
    nom, out = traj.nominal(1.0), traj.output(1.0)
    x = np.concatenate(([out.phi[0], 0.0, out.phi[1], 0.0], rotmat_to_quat(nom.R_WB), nom.omega_B))
    est = estimate_of(x, 1.0, LandingGeometry.from_scenario(sc), sc.tether.length)
    return sc, track, est


def _controllers(name: str):
    from tetherland.control import DflController, FreeFlightController, HierarchicalController
    from tetherland.interfaces import Reference

    sc, track, est = _landing()
    if name == "free_flight":
        ctrl = FreeFlightController(sc)
        ref = Reference(t=1.0, p_W=np.array([est.body.p_W, np.zeros(3), np.zeros(3)]))
    else:
        ctrl = HierarchicalController(sc) if name == "hierarchical" else DflController(sc)
        ref = track.reference(1.0)
    clock = [1.0]

    def call() -> None:
        clock[0] += 2e-3
        ctrl.update(clock[0], est, ref)

    return call


def _estimator():
    from tetherland.estimation import UkfEstimator
    from tetherland.interfaces import ImuSample, MocapSample
    from tetherland.state import RigidBodyState

    sc = load_scenario("slope50")
    level = RigidBodyState.at_rest(np.array([0.0, 0.0, 1.0]))
    est = UkfEstimator(sc, level, 0.0)
    rng = np.random.default_rng(0)
    f = np.array([0.0, 0.0, 9.81]) + rng.normal(0, 0.05, (4096, 3))
    w = rng.normal(0, 0.005, (4096, 3))
    k = [0]

    def call() -> None:
        for _ in range(2):
            k[0] += 1
            i = k[0] % 4096
            est.predict(ImuSample(k[0] * 1e-3, f[i], w[i]))
        est.estimate()
        if k[0] % 8 == 0:
            est.update(MocapSample(k[0] * 1e-3 - 0.005, k[0] * 1e-3, level.p_W, level.q_WB))

    return call


def _aero(name: str):
    """One surface-factor evaluation per call, cycling over the 64 poses of
    :func:`_poses`."""
    from tetherland.estimation.ground_effect import BelievedGroundEffect
    from tetherland.models.aero import aero_into
    from tetherland.sim.plant import Plant

    sc = load_scenario("slope50")
    plant = Plant(sc)
    poses = _poses(sc, plant)
    thrusts, v_W = np.full(4, 2.45), np.zeros(3)
    k = [0]
    if name == "believed":
        belief = BelievedGroundEffect(sc)

        def call() -> None:
            k[0] += 1
            q = poses[k[0] % len(poses)]
            belief.total_thrust(q[0:3], q[3:7], thrusts)

        return call
    m = plant.aero
    args = (m.rotor_centres_B, m.samples, m.shapes, m.params)
    factors, acting, wrench = np.empty(4), np.empty(4), np.empty(6)

    def call() -> None:
        k[0] += 1
        aero_into(poses[k[0] % len(poses)], v_W, thrusts, *args, factors, acting, wrench)

    return call


def _plant():
    """One :meth:`Plant.step` per call (see the module doc)."""
    from tetherland import GRAVITY
    from tetherland.sim.plant import Plant
    from tetherland.state import RigidBodyState

    sc = load_scenario("slope50")
    v = sc.vehicle
    plant = Plant(sc)
    landed = plant.landed_state()
    z_S = plant.layout.geometry.surface.z_S
    starts = [RigidBodyState.at_rest(landed.p_W + h * z_S, landed.q_WB)
              for h in np.linspace(0.03, 0.6, 16)]  # fmt: skip
    w_h = math.sqrt(v.mass * GRAVITY / (4.0 * v.thrust_coefficient))
    commands = (np.full(4, w_h + 0.5), np.full(4, w_h - 0.5))
    plant.reset(starts[0], rotor_speeds=commands[0], cable_engaged=True)
    k = [0]

    def call() -> None:
        i = k[0]
        k[0] = i + 1
        if i % 64 == 0:
            plant.set_state(starts[(i // 64) % len(starts)])
        if i % 2 == 0:
            plant.command(commands[(i // 2) % 2])
        plant.step()

    return call


def _bar_plant(seated: bool):
    """One :meth:`Plant.step` of the slope50 bar plant per call (see the module doc)."""
    from tetherland import GRAVITY
    from tetherland.mission.hooking import scenario_hook_offset
    from tetherland.sim.plant import Plant
    from tetherland.state import RigidBodyState

    sc = load_scenario("slope50", ["mechanism.kind=bar", "mechanism.hook_arm_rise_deg=0"])
    plant = Plant(sc)
    m, d = plant.model, plant.data
    line_mass = float(m.body_subtreemass[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY,
                                                           "line_link0")])  # fmt: skip
    w_h = math.sqrt((sc.vehicle.mass + line_mass) * GRAVITY / (4.0 * sc.vehicle.thrust_coefficient))
    geo = plant.layout.geometry
    p_A, x_A, z = geo.p_A, geo.R_WA[:, 0], np.array([0.0, 0.0, 1.0])
    q0 = plant.start_state().q_WB
    if not seated:  # hanging under the hovering vehicle, swinging (moved at 0.3 m/s)
        p0 = plant.start_state().p_W + 1.5 * z
        plant.reset(RigidBodyState.at_rest(p0, q0), rotor_speeds=[w_h] * 4)
        d.qvel[0:3] = 0.3 * x_A
    else:  # lowered beside the bar, flown over it and pulled until the line holds 3 N
        shift = scenario_hook_offset(sc, geo) + np.asarray(sc.vehicle.cable_attachment)
        start, low = p_A + 0.3 * z - shift, p_A - 0.1 * z - shift
        plant.reset(RigidBodyState.at_rest(start, q0), rotor_speeds=[w_h] * 4)
        over = low + 0.45 * x_A
        e = (x_A - 0.8 * z) / np.linalg.norm(x_A - 0.8 * z)
        pos = start

        def move(v: np.ndarray, n: int, until: float = math.inf) -> None:
            nonlocal pos
            for _ in range(n):
                pos = pos + v * plant.dt
                d.qpos[0:3], d.qpos[3:7], d.qvel[0:3], d.qvel[3:6] = pos, q0, v, 0.0
                plant.step()
                if plant.tension > until:
                    return

        for a, b in ((start, low), (low, over)):  # at 0.2 m/s, then held for 0.5 s
            n = round(float(np.linalg.norm(b - a)) / 0.2 / plant.dt)
            move((b - a) / (n * plant.dt), n)
            move(0.0 * e, round(0.5 / plant.dt))
        move(0.1 * e, round(5.0 / plant.dt), 1.0)  # the take-up: to 1 N, then gently to 3 N
        move(0.005 * e, round(100.0 / plant.dt), 3.0)
        d.qvel[0:6] = 0.0
        assert plant.tension > 2.0 and plant.cable.caught, "the hook is not seated"
    spec = mujoco.mjtState.mjSTATE_INTEGRATION
    state = np.empty(mujoco.mj_stateSize(m, spec))
    mujoco.mj_getState(m, d, state, spec)
    armature = m.dof_armature.copy()
    line = plant.cable
    held = (line._t_held, line._t_set, line._push, line.caught, line._apart)
    commands = (np.full(4, w_h + 0.5), np.full(4, w_h - 0.5))
    k = [0]

    def call() -> None:
        i = k[0]
        k[0] = i + 1
        if i % 64 == 0:
            mujoco.mj_setState(m, d, state, spec)
            m.dof_armature[:] = armature
            line._t_held, line._t_set, line._push, line.caught, line._apart = held
        if i % 2 == 0:
            plant.command(commands[(i // 2) % 2])
        plant.step()

    return call


def _compensation():
    """The two controller wrappers of a mission (:func:`~tetherland.control.stack.
    with_aero_belief`) around a controller that returns fixed speeds: one control tick per
    call, cycling over the poses of :func:`_poses` (moving at 0.4 m/s toward the slope,
    turning at 1 rad/s) and over free-flight references of 2, 3 and 4 rows and a
    tethered one."""
    from tetherland.control.stack import with_aero_belief
    from tetherland.geometry import LandingGeometry
    from tetherland.interfaces import Command, ControlMode, Reference, StateEstimate
    from tetherland.state import RigidBodyState

    class Fixed:
        def update(self, t, estimate, reference):
            return Command(np.full(4, 520.0), 9.0, np.zeros(3))

    sc = load_scenario("slope50")
    geo = LandingGeometry.from_scenario(sc)
    ctrl = with_aero_belief(Fixed(), sc)
    v_W, omega_B = -0.4 * geo.surface.z_S, np.array([0.3, -1.0, 0.2])
    estimates = [
        StateEstimate(t=0.0, body=RigidBodyState(q[0:3], v_W, q[3:7], omega_B))
        for q in _poses(sc)
    ]
    rows = np.array([[0.1, 0.2, 1.0], [0.6, -0.3, 0.2], [0.3, 0.1, -0.4], [1.0, 0.5, 0.2]])
    Y = np.array([[0.9, 0.1, 0.0, 0.0], [0.5, -0.3, 0.0, 0.0], [0.2, 0.1, 0.0, 0.0]])
    references = [Reference(t=0.0, p_W=rows[:n]) for n in (2, 3, 4)]
    references.append(Reference(t=0.0, mode=ControlMode.TETHERED, output=Y, thrust_ff=12.0))
    k = [0]

    def call() -> None:
        k[0] += 1
        i = k[0]
        ctrl.update(0.0, estimates[i % len(estimates)], references[i % len(references)])

    return call


def _stack(compiled: bool):
    """A mission's whole controller (:func:`~tetherland.control.stack.with_aero_belief`
    around the switching controller) on free-flight ticks: the poses of :func:`_poses`,
    moving, with references of 3 rows at the pose; ``compiled``: the free-flight tick in
    one call (:class:`~tetherland.control.stack.CompiledStack`), else the layers."""
    from tetherland.control import SwitchingController
    from tetherland.control.stack import with_aero_belief
    from tetherland.geometry import LandingGeometry
    from tetherland.interfaces import Reference, StateEstimate
    from tetherland.state import RigidBodyState

    sc = load_scenario("slope50")
    geo = LandingGeometry.from_scenario(sc)
    ctrl = with_aero_belief(SwitchingController(sc), sc, compiled=compiled)
    v_W, omega_B = -0.4 * geo.surface.z_S, np.array([0.3, -1.0, 0.2])
    estimates = [
        StateEstimate(t=0.0, body=RigidBodyState(q[0:3], v_W, q[3:7], omega_B))
        for q in _poses(sc)
    ]
    references = [
        Reference(t=0.0, p_W=np.array([e.body.p_W + 0.01, v_W, np.zeros(3)])) for e in estimates
    ]
    k = [0]

    def call() -> None:
        k[0] += 1
        i = k[0]
        ctrl.update(2e-3 * i, estimates[i % len(estimates)], references[i % len(references)])

    return call


def _poses(sc, plant=None) -> list:
    """64 poses [p_W, q_WB]: 48 on the normal of the slope50 landing point, from the
    landed height to 1.5 m out, level and aligned with the slope (as on the tethered
    landing), 8 on the start pad and 8 at 1.3 m above it (no planner: quick under
    valgrind)."""
    from tetherland.geometry import LandingGeometry
    from tetherland.rotations import rotation_from_z_and_yaw, rotmat_to_quat
    from tetherland.sim.plant import Plant

    geo = LandingGeometry.from_scenario(sc)
    z_S = geo.surface.z_S
    pad = (Plant(sc) if plant is None else plant).qpos.copy()
    cruise = pad + np.array([0.0, 0.0, 1.3, 0.0, 0.0, 0.0, 0.0])
    level, aligned = (
        np.array([1.0, 0.0, 0.0, 0.0]),
        rotmat_to_quat(rotation_from_z_and_yaw(z_S, 0.0)),
    )
    poses = [np.concatenate((geo.p_L + h * z_S, q))
             for h in np.linspace(sc.vehicle.h_R, 1.5, 24) for q in (level, aligned)]  # fmt: skip
    return poses + [pad] * 8 + [cruise] * 8


def _counted(fn) -> None:
    """Run ``fn()`` inside math.fsum: the region callgrind collects."""
    math.fsum(map(lambda _: fn() or 0.0, range(1)))


def main() -> None:
    name, n = sys.argv[1], int(sys.argv[2])
    if name == "mission":
        from tetherland.config import with_overrides
        from tetherland.methods import Planners
        from tetherland.runs import run_mission
        from tetherland.sim.runner import Runner

        planners = Planners()
        sc = load_scenario("slope50")
        short = ["mission.abort_time=1", "mission.safe_hover_time=1"]  # a 2 s warm-up run
        run_mission(with_overrides(sc, short), planners=planners)
        run = Runner.run
        logs = []

        def counted_run(self, *args, **kwargs):
            _counted(lambda: logs.append(run(self, *args, **kwargs)))
            return logs[-1]

        Runner.run = counted_run
        for seed in range(n):
            run_mission(sc, seed=seed, planners=planners)
        print(f"ticks={sum(len(log) for log in logs)}")
        return
    if name in ("aero", "believed"):
        call = _aero(name)
    elif name == "plant":
        call = _plant()
    elif name in ("bar_free", "bar_seated"):
        call = _bar_plant(name == "bar_seated")
    elif name == "compensation":
        call = _compensation()
    elif name in ("stack", "stack_layered"):
        call = _stack(name == "stack")
    else:
        call = _estimator() if name == "estimator" else _controllers(name)
    for _ in range(50):
        call()

    def calls() -> None:
        for _ in range(n):
            call()

    _counted(calls)


if __name__ == "__main__":
    main()
