"""One closed-loop contact-free perching run in the MuJoCo plant (issue 7 baseline).

The planner and the controller see ``scenario_belief`` (the estimated model); the plant
is ``scenario_plant`` (the truth). The vehicle starts at rest, level, at the planned start
point with the rotors at hover speed, hovers ``perching.hover_time``, flies the maneuver,
switches the motors off at touchdown (estimated contact, or ``perching.contact_grace``
after the planned t_L) and rests ``perching.rest_time``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from tetherland.config import Scenario
from tetherland.control.tracking import FreeFlightTracker
from tetherland.geometry import FloatArray, LandingGeometry, effective_h_R
from tetherland.interfaces import Estimator
from tetherland.perching.reference import LanderGeometry, PerchingReference
from tetherland.perching.verdict import PerchVerdict, evaluate_perch
from tetherland.planning.perching import PerchingPlanner, PerchResult
from tetherland.rotations import rotation_from_z_and_yaw, rotmat_to_quat
from tetherland.sim.log import SimLog
from tetherland.sim.plant import Plant
from tetherland.sim.runner import Runner
from tetherland.state import RigidBodyState

EstimatorFactory = Callable[[Scenario, RigidBodyState, float, FloatArray], Estimator]
"""``factory(scenario_belief, initial_state, t0, rotor_speeds0) -> Estimator``, e.g.
``lambda sc, x0, t0, w0: UkfEstimator(sc, x0, t0, rotor_speeds0=w0)``."""

MARGIN_TIME = 0.1
"""Extra simulated time after the planned end of the run (the reference terminates) [s]."""


def build_run(
    scenario_belief: Scenario, plan: PerchResult
) -> tuple[FreeFlightTracker, PerchingReference, RigidBodyState, FloatArray, float]:
    """Controller, reference source, initial state, initial rotor speeds and duration [s]
    of a perching run of ``plan`` (everything from the believed scenario)."""
    traj = plan.require()
    cfg = scenario_belief.perching
    geo = LandingGeometry.from_scenario(scenario_belief)
    landers = LanderGeometry.create(
        scenario_belief.vehicle.lander_half_width, effective_h_R(scenario_belief),
        geo.surface.z_S, geo.p_L,
    )  # fmt: skip
    reference = PerchingReference(
        traj, landers, t_start=cfg.hover_time, rest_time=cfg.rest_time,
        contact_grace=cfg.contact_grace,
    )  # fmt: skip
    tilt = max(cfg.max_pitch_deg, scenario_belief.controller.free_flight.max_tilt_deg)
    controller = FreeFlightTracker(
        scenario_belief, lag_compensation=cfg.lag_compensation, max_tilt_deg=tilt
    )
    p0 = traj.flat_outputs(0.0)[0]
    R0 = rotation_from_z_and_yaw(np.array([0.0, 0.0, 1.0]), traj.meta.heading)
    initial = RigidBodyState.at_rest(p0, rotmat_to_quat(R0))
    duration = cfg.hover_time + traj.duration + cfg.contact_grace + cfg.rest_time + MARGIN_TIME
    return controller, reference, initial, controller.hover_speeds, duration


def run_perching(
    scenario_plant: Scenario,
    scenario_belief: Scenario,
    seed: int,
    estimator_factory: EstimatorFactory | None = None,
    *,
    planner: PerchingPlanner | None = None,
    plant: Plant | None = None,
    observers: Sequence[Callable[[float, Plant], None]] = (),
) -> tuple[SimLog | None, PerchVerdict]:
    """Plan on the belief, fly in the plant, judge the landing.

    Parameters
    ----------
    scenario_plant : Scenario
        The truth: the simulated vehicle and surface, and the verdict's geometry.
    scenario_belief : Scenario
        What the planner, controller and estimator assume.
    seed : int
        Sensor noise seed of the runner.
    estimator_factory : callable, optional
        See :data:`EstimatorFactory`; default: the ground truth.
    planner : PerchingPlanner, optional
        Reuse compiled solvers across runs.
    plant : Plant, optional
        Reuse a plant built for ``scenario_plant``.
    observers : sequence of callables
        Runner observers ``observer(t, plant)`` (progress, wind, video).

    Returns
    -------
    (SimLog or None, PerchVerdict)
        The log is None when no plan was found (the verdict says why). The plan summary
        and the verdict are added to ``log.metadata["perching"]``.
    """
    plan = (planner or PerchingPlanner()).plan(scenario_belief)
    if not plan.success:
        return None, PerchVerdict.failed(f"no perching plan: {plan.status.value}: {plan.message}")
    controller, reference, initial, w0, duration = build_run(scenario_belief, plan)
    estimator = None
    if estimator_factory is not None:
        estimator = estimator_factory(scenario_belief, initial, 0.0, w0)
    runner = Runner(
        scenario_plant,
        controller,
        estimator=estimator,
        reference=reference,
        seed=seed,
        plant=plant,
        diagnostic_keys=FreeFlightTracker.diagnostic_keys,
        observers=observers,
    )
    log = runner.run(duration, initial_state=initial, rotor_speeds=w0)
    verdict = evaluate_perch(log, scenario_plant)
    log.metadata["perching"] = {
        "plan": plan.summary(),
        "verdict": verdict.to_dict(),
        "planned_touchdown_s": reference.t_touchdown_planned,
    }
    return log, verdict
