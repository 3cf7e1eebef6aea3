"""Independent check of a perching trajectory before it is handed out.

The trajectory (the fine re-simulation of the solver's inputs) is sampled every
:data:`CHECK_STEP` and checked against the request: touchdown pose, velocity, body rate
and thrust, rotor thrust bounds, and the clearance of the landers and rotor guards above
the surface before t_L. The generic parts are :mod:`tetherland.planning.checks`.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from tetherland.planning.checks import (
    CHECK_STEP,
    CheckResult,
    check_times,
    collect,
    finite_problem,
    floor_problem,
    thrust_problem,
    tolerance_problem,
)
from tetherland.planning.perching.model import PerchSpec
from tetherland.planning.perching.trajectory import FreeFlightTrajectory

__all__ = ["CHECK_STEP", "PerchTolerances", "PerchVerification", "verify_perch"]


@dataclass(frozen=True)
class PerchTolerances:
    """How far a planned perching trajectory may miss its conditions.

    Attributes
    ----------
    position : float
        ||p(t_L) - (p*_L + h_R z_S)|| [m].
    attitude : float
        Angle between z_B(t_L) and z_S [rad].
    speed : float
        ||p'(t_L) + v_n z_S|| [m/s].
    rate : float
        |omega(t_L)| [rad/s].
    thrust : float
        Rotor thrusts beyond the planned bounds [f_min + margin, f_max - margin] [N].
    clearance : float
        Lander or guard clearance below ``clearance_margin`` before t_L [m].
    """

    position: float = 1e-3
    attitude: float = 1e-3
    speed: float = 1e-3
    rate: float = 1e-3
    thrust: float = 1e-6
    clearance: float = 1e-3


@dataclass(frozen=True)
class PerchVerification(CheckResult):
    """Result of :func:`verify_perch`.

    Attributes
    ----------
    position_error, attitude_error, speed_error, rate_error : float
        At t_L [m, rad, m/s, rad/s].
    touchdown_thrust : float
        f_R(t_L) [N].
    min_rotor_thrust, max_rotor_thrust : float
        Extreme rotor thrusts [N].
    min_clearance : float
        Least clearance of landers and guards before t_L [m].

    With ``problems`` and ``scope`` of :class:`~tetherland.planning.checks.CheckResult`.
    """

    position_error: float
    attitude_error: float
    speed_error: float
    rate_error: float
    touchdown_thrust: float
    min_rotor_thrust: float
    max_rotor_thrust: float
    min_clearance: float

    def to_dict(self) -> dict[str, object]:
        d = asdict(self)
        d["problems"] = list(self.problems)
        d["scope"] = self.scope.value
        return d


def verify_perch(
    trajectory: FreeFlightTrajectory, spec: PerchSpec, tol: PerchTolerances | None = None
) -> PerchVerification:
    """Sample ``trajectory`` every :data:`CHECK_STEP` (and at its nodes) and check it."""
    tol = tol or PerchTolerances()
    T = trajectory.duration
    times = check_times(T, trajectory.times)
    X, _ = trajectory.states(times)
    end = X[-1]
    pos_err = float(np.linalg.norm(end[0:2] - spec.p_landed))
    att_err = abs(float(end[2] - spec.beta))
    speed_err = float(np.linalg.norm(end[3:5] - spec.v_final))
    rate_err = abs(float(end[5]))
    f = spec.rotor_thrusts(X)
    # Clearance before t_L: at t_L the landers touch (zero clearance) by construction.
    before = times < T - 1e-9
    clear, clear_issue = floor_problem(
        "lander/guard clearance above the surface", spec.clearances(X[before]).min(axis=1),
        spec.clearance_margin, times[before], tol.clearance, "m",
    )  # fmt: skip
    problems = collect(
        tolerance_problem("touchdown position error", pos_err, tol.position, "m"),
        tolerance_problem("touchdown attitude error", att_err, tol.attitude, "rad"),
        tolerance_problem("touchdown velocity error", speed_err, tol.speed, "m/s"),
        tolerance_problem("touchdown body rate", rate_err, tol.rate, "rad/s"),
        thrust_problem(f, times, spec.f_lo, spec.f_hi, tol.thrust),
        clear_issue,
        finite_problem(X),
    )
    return PerchVerification(
        position_error=pos_err,
        attitude_error=att_err,
        speed_error=speed_err,
        rate_error=rate_err,
        touchdown_thrust=float(end[6]),
        min_rotor_thrust=float(f.min()),
        max_rotor_thrust=float(f.max()),
        min_clearance=clear + spec.clearance_margin,
        problems=problems,
    )
