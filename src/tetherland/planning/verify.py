"""Independent check of a planned trajectory before it is handed out.

The trajectory is sampled densely (a :class:`ShootingTrajectory` *is* the fine
re-simulation of the OCP's inputs, not the solver's node values) and checked against
the maneuver: final state, rotor thrust bounds, cable tension bound (6.21d) and the
surface (phi >= phi*). The generic parts are :mod:`.checks`; :func:`verify_nodes` is the
cheap check of the solver's nodes for online re-planning.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tetherland.geometry import FloatArray
from tetherland.planning import kernels
from tetherland.planning.checks import (
    CHECK_STEP,
    CheckResult,
    CheckScope,
    check_times,
    collect,
    finite_problem,
    floor_problem,
    thrust_problem,
    tolerance_problem,
)
from tetherland.planning.maneuver import ManeuverSpec
from tetherland.planning.trajectory import Trajectory

__all__ = ["CHECK_STEP", "Tolerances", "Verification", "verify", "verify_nodes"]


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
        Rotor thrusts (or commands, see :class:`Verification`) beyond the planned bounds
        [f_min + margin, f_max - margin] [N]
        (the vehicle's own limits [f_min, f_max] are never exceeded by more than this).
    tension : float
        Tension below the bound f_L_min(t) [N].
    surface : float
        phi below phi* [rad].
    gap : float
        Node check only: largest shooting gap |x_{k+1} - F(x_k, u_k)| [state units].
    """

    angle: float = 1e-4
    rate: float = 1e-4
    thrust: float = 1e-6
    tension: float = 1e-2
    surface: float = 1e-4
    gap: float = 1e-6


@dataclass(frozen=True)
class Verification(CheckResult):
    """Result of :func:`verify` (or of :func:`verify_nodes`, ``scope`` NODES).

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
        Extreme rotor thrusts [N]: what the rotor bounds hold, the commands f_i / k_i
        when the plan models the believed ground effect (``planner.model_ground_effect``).
    surface_margin : float
        min over t of phi - phi* [rad].

    With ``problems`` and ``scope`` of :class:`~tetherland.planning.checks.CheckResult`.
    """

    final_error: dict[str, float]
    min_tension: float
    tension_margin: float
    min_rotor_thrust: float
    max_rotor_thrust: float
    surface_margin: float


def _final_error(spec: ManeuverSpec, x_end: FloatArray) -> dict[str, float]:
    return {
        "phi_rad": float(x_end[0] - spec.phi_final),
        "theta_A_rad": float(x_end[1] - spec.theta_final),
        "phi_rate": float(x_end[2]),
        "theta_A_rate": float(x_end[3]),
    }


def _check(
    spec: ManeuverSpec,
    tol: Tolerances,
    t: FloatArray,
    phi: FloatArray,
    tension: FloatArray,
    thrust_t: FloatArray,
    thrusts: FloatArray,
    err: dict[str, float],
    scope: CheckScope,
    extra: str | None = None,
) -> Verification:
    """The tethered criteria: phi and tension sampled at times ``t`` (n,), rotor thrusts
    (m, 4) at ``thrust_t`` (m,)."""
    tension_margin, tension_issue = floor_problem(
        "cable tension (6.21d)", tension, spec.tension_floor(t), t, tol.tension, "N"
    )
    surface_margin, surface_issue = floor_problem(
        "link elevation phi", phi, spec.phi_surface, t, tol.surface, "rad"
    )
    problems = collect(
        tolerance_problem(
            "final angle error", {"phi": err["phi_rad"], "theta_A": err["theta_A_rad"]},
            tol.angle, "rad",
        ),
        tolerance_problem(
            "final rates", {"phi'": err["phi_rate"], "theta_A'": err["theta_A_rate"]},
            tol.rate, "rad/s",
        ),
        thrust_problem(thrusts, thrust_t, spec.f_lo, spec.f_hi, tol.thrust),
        tension_issue,
        surface_issue,
        extra,
        finite_problem(thrusts, phi),
    )  # fmt: skip
    return Verification(
        final_error=err,
        min_tension=float(tension.min()),
        tension_margin=tension_margin,
        min_rotor_thrust=float(thrusts.min()),
        max_rotor_thrust=float(thrusts.max()),
        surface_margin=surface_margin,
        problems=problems,
        scope=scope,
    )


def verify(
    trajectory: Trajectory, spec: ManeuverSpec, tol: Tolerances | None = None
) -> Verification:
    """Sample ``trajectory`` every :data:`CHECK_STEP` (and at its nodes) and check it."""
    tol = tol or Tolerances()
    times = check_times(trajectory.duration, getattr(trajectory, "times", None))
    x = trajectory.states_at(times)
    x_end = trajectory.states_at([trajectory.duration])[0]
    model = spec.model
    tension = np.asarray(model.tension(x.T))
    thrusts = model.rotor_thrusts(x.T, tension).T  # with the offset's b f_L
    thrusts = spec.rotor_commands(thrusts, x[:, 0], x[:, 1])  # (f / k: the ground effect)
    return _check(
        spec, tol, times, x[:, 0], tension, times, thrusts, _final_error(spec, x_end),
        CheckScope.RESIMULATION,
    )  # fmt: skip


def verify_nodes(
    spec: ManeuverSpec,
    times: FloatArray,
    X: FloatArray,
    U: FloatArray,
    steps: int,
    tol: Tolerances | None = None,
) -> Verification:
    """The cheap check of a solver's nodes (online re-planning; scope NODES).

    Parameters
    ----------
    spec : ManeuverSpec
    times : (N+1,) array
        Node times [s].
    X : (N+1, 12) array
        Rotor-form node states.
    U : (N, 4) array
        Rotor thrust accelerations f'' held on each interval [N/s^2].
    steps : int
        RK4 steps per interval of the transcription that produced the nodes.

    Checks, at the nodes: the final conditions, the tension floor (6.21d) and the
    surface; the rotor thrusts on each whole interval through the Bernstein coefficients
    f_k, f_k + f_k' h/2, f_{k+1} of the quadratic arc (its hull bounds the arc exactly);
    and that every shooting gap x_{k+1} - F(x_k, u_k) is closed, F being ``steps`` RK4
    steps of the rotor-form model (6.20) (:func:`~tetherland.planning.kernels.interval_ends`,
    apart from the OCP's own transcription, which integrates the wrench form). About
    0.1 ms.
    """
    tol = tol or Tolerances()
    X = np.ascontiguousarray(X, dtype=float)
    U = np.ascontiguousarray(U, dtype=float)
    h = np.diff(times)
    ends = kernels.interval_ends(X, U, h, steps, spec.params.coefficients)
    gap = float(np.max(np.abs(ends - X[1:])))
    gap_issue = (
        f"shooting gaps up to {gap:.2e} (tolerance {tol.gap:g}): the solver's nodes are not "
        f"one motion"
        if not gap <= tol.gap
        else None
    )
    tension = np.asarray(spec.model.tension(X.T))
    share = spec.model.rotor_thrusts(X.T, tension).T - X[:, 4:8]  # the offset's G [0, b f_L]
    f0, df0 = X[:-1, 4:8] + share[:-1], X[:-1, 8:12]
    arcs = np.stack((f0, f0 + 0.5 * h[:, None] * df0, X[1:, 4:8] + share[1:]), axis=1)
    # (with the believed ground effect: the commands f / k, k of each interval's first node)
    arcs = spec.rotor_commands(
        arcs.reshape(-1, 4), np.repeat(X[:-1, 0], 3), np.repeat(X[:-1, 1], 3)
    )
    return _check(
        spec, tol, times, X[:, 0], tension, np.repeat(times[:-1], 3), arcs,
        _final_error(spec, X[-1]), CheckScope.NODES, extra=gap_issue,
    )  # fmt: skip
