"""Compile (or load) every compiled kernel of the closed loop once: ``python -m tetherland.warmup``.

numba compiles a kernel on its first call and caches the machine code on disk
(``cache=True``, in ``__pycache__`` beside the source). On a fresh installation that first
call costs about 50 s of CPU for all kernels together, paid by the first mission or the
first test that needs them, and by every process that starts before the cache is written
(two test workers and the campaign workers they spawn all compile the same kernels at
once). Running this module right after installation pays it once; later processes only
load the cache (about 0.1 s). The calls use the same argument types as the mission loop,
so the loop finds every specialisation it needs (``tests/test_warmup.py`` flies a whole
mission after the warm-up and checks that it compiles nothing more).

The kernels fall in two groups of about equal compile time, which ``--jobs 2`` compiles
in two processes at once: the estimator and the controllers (:func:`warm_estimation_and_control`),
and the plant, the planner and the mission's supervisor and fault rules
(:func:`warm_plant_and_mission`).
"""

from __future__ import annotations

import argparse
import multiprocessing
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from tetherland.config import load_scenario
from tetherland.interfaces import (
    ControlMode,
    Feedforward,
    ImuSample,
    MocapSample,
    Reference,
    StateEstimate,
)


def warm_estimation_and_control() -> None:
    """The UKF, the free-flight, tracking, hierarchical and DFL controllers, each alone and
    wrapped as a mission composes them (believed ground effect and rotor drag)."""
    from tetherland.control import (
        DflController,
        FreeFlightController,
        HierarchicalController,
        SwitchingController,
    )
    from tetherland.control.stack import with_aero_belief
    from tetherland.control.tracking import FreeFlightTracker
    from tetherland.estimation import UkfEstimator
    from tetherland.geometry import LandingGeometry
    from tetherland.state import RigidBodyState, link_state_of

    sc = load_scenario("slope50")
    geo = LandingGeometry.from_scenario(sc)
    start = RigidBodyState.at_rest(geo.p_A + np.array([-0.5, 0.0, 0.5]))
    est = UkfEstimator(sc, start, 0.0)
    f, w = np.array([0.0, 0.0, 9.81]), np.zeros(3)
    est.predict(ImuSample(1e-3, f, w))
    est.update(MocapSample(5e-4, 1e-3, start.p_W, start.q_WB))
    est.predict(ImuSample(2e-3, f, w))
    e = est.estimate()
    held = np.zeros((3, 3))
    held.setflags(write=False)  # a free-flight path's pause hands out read-only rows
    for rows in (np.zeros((3, 3)), held):
        FreeFlightController(sc).update(2e-3, e, Reference(t=2e-3, p_W=rows))
        with_aero_belief(FreeFlightController(sc), sc).update(2e-3, e, Reference(t=2e-3, p_W=rows))
        # a mission's stack: its free-flight ticks in one compiled call (control.stack;
        # the first tick, the switch into free flight, goes through the layers)
        stack = with_aero_belief(SwitchingController(sc), sc)
        for t in (2e-3, 4e-3):
            stack.update(t, e, Reference(t=t, p_W=rows))
    FreeFlightTracker(sc).update(2e-3, e, Reference(t=2e-3, p_W=np.zeros((5, 3))))
    output = np.zeros((5, 4))
    output[0, 0] = e.link.phi if e.link is not None else 0.5
    ff = Feedforward(omega_B=np.zeros(3), omega_dot_B=np.zeros(3), f_R=sc.vehicle.mass * 9.81)
    ref = Reference(t=2e-3, mode=ControlMode.TETHERED, output=output, feedforward=ff)
    for ctrl in (HierarchicalController(sc), DflController(sc)):
        ctrl.update(2e-3, e, ref)
        with_aero_belief(ctrl, sc).update(2e-3, e, ref)
    x = np.concatenate((start.p_W, start.q_WB, start.v_W, start.omega_B))
    link_state_of(x, np.asarray(sc.vehicle.cable_attachment, dtype=float), geo.p_A, geo.R_WA)


def warm_plant_and_mission() -> None:
    """The plant's rotor step, aerodynamics, IMU row and log row (the point hook's and the bar's
    plant, whose hanging line has its drag), the magnet's EPM pull, the landing plan's
    verification, the supervisor's paths, the fault rules' cable torque and the perching
    maneuver's reference."""
    from tetherland.mission import MissionSupervisor, plan_mission
    from tetherland.mission.faults import cable_torque_xy_of
    from tetherland.planning.perching import kernels as perching_kernels
    from tetherland.sim.epm import cell_offsets, epm_pull_into
    from tetherland.sim.plant import ROTOR_STATE_WIDTH, Plant
    from tetherland.sim.sensors import Imu

    sc = load_scenario("slope50")
    for plant in (Plant(sc), Plant(load_scenario("pipe60", ["mechanism.kind=bar"]))):
        hover = np.full(4, 0.9 * plant.speed_limit)
        plant.reset(rotor_speeds=hover)
        plant.command(hover)
        plant.step(2)
        plant.rotor_state_into(np.empty(ROTOR_STATE_WIDTH))
        # the IMU's row, as the runner takes it (truth: a view into MuJoCo's sensordata)
        Imu(sc.sensors.imu, np.random.default_rng(0)).sample_into(
            0.0, plant.sensordata[0:6], np.empty((2, 7))[0]
        )
    # the EPM's pull (the magnet's plant calls it only while the EPM is on)
    epm_pull_into(np.zeros(3), np.eye(3).ravel(), np.zeros(3), cell_offsets(0.02), np.zeros(3),
                  np.eye(3).ravel(), 0.1, 1.0, 1e-3, np.empty(6))  # fmt: skip
    start = Plant(sc).start_state()
    plan = plan_mission(sc, start)  # verifies its trajectories with the compiled RK4
    supervisor = MissionSupervisor(sc, plan)
    supervisor.reference(0.0, StateEstimate(t=0.0, body=start))
    r_att = np.asarray(sc.vehicle.cable_attachment, dtype=float)
    cable_torque_xy_of(start.q_WB, start.p_W, 0.0, r_att, np.asarray(plan.geometry.p_A))
    # the contact-free method's maneuver reference (its arrays as the trajectory packs them)
    c = perching_kernels.pack(1.0, 0.01, 9.81, 0.0, 1, np.eye(3), np.zeros(3))
    perching_kernels.reference_into(0.5, np.array([0.0, 1.0]), np.zeros((1, 1, 10)),
                                    np.zeros((1, 2)), c, np.empty((5, 3)))  # fmt: skip


GROUPS: tuple[Callable[[], None], ...] = (warm_estimation_and_control, warm_plant_and_mission)
"""The warm-up's independent parts (each compiles its own kernels)."""


def _timed(part: Callable[[], None]) -> float:
    t0 = time.perf_counter()
    part()
    return time.perf_counter() - t0


def warm_up(jobs: int = 1) -> float:
    """Call every kernel once with the loop's argument types; returns the time taken [s].

    Parameters
    ----------
    jobs : int
        Processes to compile in (1: in this process; more: the :data:`GROUPS` in a pool of
        fresh processes, which write the shared on-disk cache).
    """
    t0 = time.perf_counter()
    if jobs <= 1:
        for part in GROUPS:
            part()
    else:
        spawn = multiprocessing.get_context("spawn")  # (no half-initialised numba state)
        with ProcessPoolExecutor(min(jobs, len(GROUPS)), mp_context=spawn) as pool:
            list(pool.map(_timed, GROUPS))
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m tetherland.warmup", description=__doc__)
    parser.add_argument("--jobs", type=int, default=1, help="processes to compile in (>= 1)")
    args = parser.parse_args(argv)
    if args.jobs < 1:
        parser.error(f"--jobs = {args.jobs}: must be at least 1")
    print(f"compiled kernels ready ({warm_up(args.jobs):.1f} s)")


if __name__ == "__main__":
    main()
