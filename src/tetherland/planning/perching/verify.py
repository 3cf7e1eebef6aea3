"""Independent check of a perching trajectory before it is handed out.

The trajectory (the fine re-simulation of the solver's inputs) is sampled every
:data:`CHECK_STEP` and checked against the request: touchdown pose, velocity, body rate
and thrust, rotor thrust bounds, and the clearance of the landers and rotor guards above
the surface before t_L.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from tetherland.planning.perching.model import PerchSpec
from tetherland.planning.perching.trajectory import FreeFlightTrajectory

CHECK_STEP = 1e-3
"""Sampling step of the checks [s] (node times are added)."""


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
class PerchVerification:
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
    problems : tuple of str
        What is out of tolerance (empty when accepted).
    """

    position_error: float
    attitude_error: float
    speed_error: float
    rate_error: float
    touchdown_thrust: float
    min_rotor_thrust: float
    max_rotor_thrust: float
    min_clearance: float
    problems: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return not self.problems

    def to_dict(self) -> dict[str, object]:
        d = asdict(self)
        d["problems"] = list(self.problems)
        return d


def verify_perch(
    trajectory: FreeFlightTrajectory, spec: PerchSpec, tol: PerchTolerances | None = None
) -> PerchVerification:
    """Sample ``trajectory`` every :data:`CHECK_STEP` (and at its nodes) and check it."""
    tol = tol or PerchTolerances()
    T = trajectory.duration
    times = np.union1d(np.linspace(0.0, T, max(2, math.ceil(T / CHECK_STEP) + 1)), trajectory.times)
    X, _ = trajectory.states(times)
    end = X[-1]
    pos_err = float(np.linalg.norm(end[0:2] - spec.p_landed))
    att_err = abs(end[2] - spec.beta)
    speed_err = float(np.linalg.norm(end[3:5] - spec.v_final))
    rate_err = abs(float(end[5]))
    f = spec.rotor_thrusts(X)
    # Clearance before t_L: at t_L the landers touch (zero clearance) by construction.
    clear = spec.clearances(X[times < T - 1e-9]).min()
    problems = []
    if pos_err > tol.position:
        problems.append(f"touchdown position error {pos_err:.2e} m (tolerance {tol.position:g})")
    if att_err > tol.attitude:
        problems.append(f"touchdown attitude error {att_err:.2e} rad (tolerance {tol.attitude:g})")
    if speed_err > tol.speed:
        problems.append(f"touchdown velocity error {speed_err:.2e} m/s (tolerance {tol.speed:g})")
    if rate_err > tol.rate:
        problems.append(f"touchdown body rate {rate_err:.2e} rad/s (tolerance {tol.rate:g})")
    f_lo, f_hi = float(f.min()), float(f.max())
    if f_lo < spec.f_lo - tol.thrust or f_hi > spec.f_hi + tol.thrust:
        problems.append(
            f"rotor thrusts {f_lo:.3f}..{f_hi:.3f} N leave [{spec.f_lo:g}, {spec.f_hi:g}] N"
        )
    if clear < spec.clearance_margin - tol.clearance:
        i = int(np.argmin(spec.clearances(X[times < T - 1e-9]).min(axis=1)))
        problems.append(
            f"the vehicle penetrates the surface by {spec.clearance_margin - clear:.2e} m "
            f"at t = {times[i]:.3f} s"
        )
    if not np.all(np.isfinite(X)):
        problems.append("trajectory contains NaN or infinite values")
    return PerchVerification(
        position_error=pos_err,
        attitude_error=att_err,
        speed_error=speed_err,
        rate_error=rate_err,
        touchdown_thrust=float(end[6]),
        min_rotor_thrust=f_lo,
        max_rotor_thrust=f_hi,
        min_clearance=float(clear),
        problems=tuple(problems),
    )
