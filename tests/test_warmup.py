"""The warm-up compiles exactly the kernel specialisations the closed loop uses."""

from __future__ import annotations

import numpy as np

from tetherland import state, warmup
from tetherland.config import load_scenario, with_overrides
from tetherland.control import DflController, HierarchicalController
from tetherland.control.kernels import dfl, free_flight, hierarchical, tracker
from tetherland.control.tracking import FreeFlightTracker
from tetherland.estimation import UkfEstimator, ukf_kernels
from tetherland.estimation import kernels as estimation_kernels
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import ImuSample, Reference
from tetherland.methods import Planners
from tetherland.planning import Planner
from tetherland.planning.tracking import TrajectoryTrack
from tetherland.rotations import rotmat_to_quat
from tetherland.runs import run_mission
from tetherland.sim.analytic import estimate_of

KERNELS = (
    free_flight.free_flight_into,
    tracker.tracker_into,
    hierarchical.hierarchical_into,
    dfl.dfl_into,
    ukf_kernels.predict_ws,
    ukf_kernels.update_pose_ws,
    estimation_kernels.push_imu,
    estimation_kernels.estimate_tick,
    estimation_kernels.fuse_pose,
    estimation_kernels.command_into,
    state.link_kernel,
)


def _signatures() -> dict[str, set]:
    return {k.__name__: set(k.signatures) for k in KERNELS}


def test_the_loop_needs_no_specialisation_beyond_the_warm_up():
    warmup.warm_up()
    warmed = _signatures()
    assert all(warmed.values())  # every kernel compiled (or loaded from the cache)
    sc = load_scenario("slope50")
    planners = Planners()
    # free flight, the estimator and mocap in the mission loop ...
    short = ["mission.abort_time=0.25", "mission.safe_hover_time=0.25"]  # ends at 0.5 s
    run_mission(with_overrides(sc, short), planners=planners)
    # ... and the tethered controllers on a planned track's references, from the estimator
    traj = Planner().plan(sc, "landing").require()
    track = TrajectoryTrack(traj, 0.0, sc.controller.rate_hz)
    nom, out = traj.nominal(1.0), traj.output(1.0)
    x = np.concatenate(([out.phi[0], 0.0, out.phi[1], 0.0], rotmat_to_quat(nom.R_WB), nom.omega_B))
    body = estimate_of(x, 1.0, LandingGeometry.from_scenario(sc), sc.tether.length).body
    estimator = UkfEstimator(sc, body, 1.0)
    estimator.predict(ImuSample(1.001, np.array([0.0, 0.0, 9.81]), np.zeros(3)))
    estimate = estimator.estimate()
    for ctrl in (HierarchicalController(sc), DflController(sc)):
        ctrl.update(1.0, estimate, track.reference(1.0))
        ctrl.update(1.002, estimate, track.reference(traj.duration + 0.5))  # held end
    # ... and the contact-free tracker on hover, continuation and maneuver rows (read-only
    # or views of a larger array, as the perching reference hands them out)
    free = FreeFlightTracker(sc)
    held = np.zeros((3, 3))
    held.setflags(write=False)
    for i, rows in enumerate((np.zeros((1, 3)), held, np.zeros((2, 5, 3))[1])):
        free.update(1.0 + 2e-3 * i, estimate, Reference(t=1.0, p_W=rows))
    assert _signatures() == warmed
