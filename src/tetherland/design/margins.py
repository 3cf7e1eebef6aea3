"""Rotor margins of a design: at the landed hover (analysis) and over its planned maneuvers.

The rotor margin of a set of rotor thrusts is min_i min(f_i - f_min, f_max - f_i) [N]:
how far the closest rotor is from either limit of the vehicle. A feasible design keeps
at least ``vehicle.control_margin`` everywhere.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from tetherland.config import Scenario
from tetherland.models.flatness import FlatnessMap
from tetherland.planning import PlanResult

SAMPLE_STEP = 0.01
"""Sampling step of a planned trajectory for its rotor margin [s] (its nodes are added)."""


def rotor_margin(thrusts: ArrayLike, f_min: float, f_max: float) -> float:
    """min over rotors (and samples) of min(f_i - f_min, f_max - f_i) [N]."""
    f = np.asarray(thrusts, dtype=float)
    return float(np.minimum(f - f_min, f_max - f).min())


def plan_rotor_margin(scenario: Scenario, plans: Sequence[PlanResult]) -> float:
    """Rotor margin over the planned maneuvers, the cable-offset torque included [N].

    The OCP plans with the chapter's model (cable at the centre of mass). The rotors of
    a vehicle with the attachment offset r_att must also cancel the cable torque
    r_att x (f_L d) (6.6.5); the flatness map with ``with_cable_offset`` gives those
    thrusts (:func:`plan_thrust_range`).
    """
    v = scenario.vehicle
    f_low, f_high = plan_thrust_range(scenario, plans)
    return rotor_margin([f_low, f_high], v.f_min, v.f_max)


def plan_thrust_range(scenario: Scenario, plans: Sequence[PlanResult]) -> tuple[float, float]:
    """Least and largest rotor thrust over the planned maneuvers [N], the cable-offset
    torque included: the flatness map with ``with_cable_offset`` on the planned output,
    sampled every :data:`SAMPLE_STEP` and at the nodes."""
    flat = FlatnessMap.from_scenario(scenario, with_cable_offset=True)
    low, high = math.inf, -math.inf
    for plan in plans:
        traj = plan.require()
        T = traj.duration
        times = np.linspace(0.0, T, max(2, math.ceil(T / SAMPLE_STEP) + 1))
        nodes = getattr(traj, "times", None)
        if nodes is not None:
            times = np.union1d(times, nodes)
        thrusts = flat.evaluate_many(traj.sample(times).outputs())["rotor_thrusts"]
        low, high = min(low, float(np.min(thrusts))), max(high, float(np.max(thrusts)))
    return low, high
