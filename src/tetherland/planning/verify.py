"""Independent check of a planned trajectory before it is handed out.

The trajectory is sampled densely (a :class:`ShootingTrajectory` *is* the fine
re-simulation of the OCP's inputs, not the solver's node values) and checked against
the maneuver: final state, rotor thrust bounds, cable tension bound (6.21d) and the
surface (phi >= phi*).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tetherland.planning.maneuver import ManeuverSpec
from tetherland.planning.trajectory import Trajectory

CHECK_STEP = 1e-3
"""Sampling step of the checks [s] (node times are added)."""


@dataclass(frozen=True)
class Tolerances:
    """How far a planned trajectory may miss its conditions.

    Attributes
    ----------
    angle : float
        Final |phi - phi_f| and |theta_A - theta_A,f| [rad].
    rate : float
        Final |phi'| and |theta_A'| [rad/s].
    thrust : float
        Rotor thrusts beyond the planned bounds [f_min + margin, f_max - margin] [N]
        (the vehicle's own limits [f_min, f_max] are never exceeded by more than this).
    tension : float
        Tension below the bound f_L_min(t) [N].
    surface : float
        phi below phi* [rad].
    """

    angle: float = 1e-4
    rate: float = 1e-4
    thrust: float = 1e-6
    tension: float = 1e-2
    surface: float = 1e-4


@dataclass(frozen=True)
class Verification:
    """Result of :func:`verify`.

    Attributes
    ----------
    final_error : dict
        ``phi_rad``, ``theta_A_rad``, ``phi_rate``, ``theta_A_rate``: final value minus
        target [rad, rad/s].
    min_tension : float
        Least f_L along the trajectory [N].
    tension_margin : float
        min over t of f_L(t) - f_L_min(t) [N] (negative: the bound is violated).
    min_rotor_thrust, max_rotor_thrust : float
        Extreme rotor thrusts [N].
    surface_margin : float
        min over t of phi - phi* [rad].
    problems : tuple of str
        What is out of tolerance (empty when the trajectory is accepted).
    """

    final_error: dict[str, float]
    min_tension: float
    tension_margin: float
    min_rotor_thrust: float
    max_rotor_thrust: float
    surface_margin: float
    problems: tuple[str, ...]

    @property
    def ok(self) -> bool:
        return not self.problems


def verify(
    trajectory: Trajectory, spec: ManeuverSpec, tol: Tolerances | None = None
) -> Verification:
    """Sample ``trajectory`` every :data:`CHECK_STEP` (and at its nodes) and check it."""
    tol = tol or Tolerances()
    T = trajectory.duration
    times = np.linspace(0.0, T, max(2, math.ceil(T / CHECK_STEP) + 1))
    nodes = getattr(trajectory, "times", None)
    if nodes is not None:
        times = np.union1d(times, nodes)
    s = trajectory.sample(times)
    end = trajectory.sample([T])
    err = {
        "phi_rad": float(end.phi[0, 0] - spec.phi_final),
        "theta_A_rad": float(end.theta_A[0, 0] - spec.theta_final),
        "phi_rate": float(end.phi[0, 1]),
        "theta_A_rate": float(end.theta_A[0, 1]),
    }
    problems = []
    if max(abs(err["phi_rad"]), abs(err["theta_A_rad"])) > tol.angle:
        problems.append(
            f"final angle error phi {err['phi_rad']:.2e} rad, theta_A {err['theta_A_rad']:.2e} rad "
            f"(tolerance {tol.angle:g})"
        )
    if max(abs(err["phi_rate"]), abs(err["theta_A_rate"])) > tol.rate:
        problems.append(
            f"final rates phi' {err['phi_rate']:.2e}, theta_A' {err['theta_A_rate']:.2e} rad/s "
            f"(tolerance {tol.rate:g})"
        )
    f_lo, f_hi = float(s.thrusts.min()), float(s.thrusts.max())
    if f_lo < spec.f_lo - tol.thrust or f_hi > spec.f_hi + tol.thrust:
        i = int(np.argmax(np.maximum(spec.f_lo - s.thrusts, s.thrusts - spec.f_hi).max(axis=1)))
        problems.append(
            f"rotor thrusts {f_lo:.3f}..{f_hi:.3f} N leave [{spec.f_lo:g}, {spec.f_hi:g}] N "
            f"(f_min/f_max with the control margin) near t = {s.t[i]:.2f} s"
        )
    margin = s.tension - spec.tension_floor(s.t)
    if margin.min() < -tol.tension:
        i = int(np.argmin(margin))
        problems.append(
            f"cable tension {s.tension[i]:.3f} N below its bound "
            f"{spec.tension_floor(s.t[i]):.3f} N at t = {s.t[i]:.2f} s (6.21d)"
        )
    surface = s.phi[:, 0] - spec.phi_surface
    if surface.min() < -tol.surface:
        i = int(np.argmin(surface))
        problems.append(
            f"link below the landing elevation phi* by {-surface[i]:.2e} rad at t = {s.t[i]:.2f} s"
        )
    if not np.all(np.isfinite(s.thrusts)) or not np.all(np.isfinite(s.phi)):
        problems.append("trajectory contains NaN or infinite values")
    return Verification(
        final_error=err,
        min_tension=float(s.tension.min()),
        tension_margin=float(margin.min()),
        min_rotor_thrust=f_lo,
        max_rotor_thrust=f_hi,
        surface_margin=float(surface.min()),
        problems=tuple(problems),
    )
