"""Landing conditions (1)-(5) of chapter section 6.3 as predicates on states and logs.

Translated to our body frame: condition (2) ``z_R = -z_S`` reads ``z_B = z_S``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from tetherland.analysis.statics import ContactForces


@dataclass(frozen=True)
class LandingTolerances:
    """How close to the ideal each landing condition must be to count as met.

    Attributes
    ----------
    position : float
        Condition (1): ||p_RL - p*_L|| [m].
    attitude : float
        Condition (2): angle between z_B and z_S [rad].
    speed, angular_rate : float
        Condition (3): ||p'_R|| [m/s] and ||omega_B|| [rad/s] at t_L-.
    accel, angular_accel : float
        Condition (4): ||p''_R|| [m/s^2] and ||omega'_B|| [rad/s^2] at t_L-.
    slip : float
        Condition (5): displacement of p_RL while resting [m].
    rest_speed : float
        Condition (5): speed while resting [m/s].
    """

    position: float = 0.03
    attitude: float = math.radians(3.0)
    speed: float = 0.1
    angular_rate: float = 0.3
    accel: float = 1.0
    angular_accel: float = 10.0
    slip: float = 0.01
    rest_speed: float = 0.02


@dataclass(frozen=True)
class Measure:
    """One measured quantity of a condition, with its limit and unit."""

    name: str
    value: float
    limit: float
    unit: str

    @property
    def ok(self) -> bool:
        return bool(self.value <= self.limit)


@dataclass(frozen=True)
class ConditionResult:
    """Outcome of one landing condition.

    ``holds`` is true when every measure is within its limit (or, for the force-balance
    form of condition (5), when the contact forces are admissible).
    """

    number: int
    holds: bool
    measures: tuple[Measure, ...] = field(default=())
    note: str = ""

    def to_dict(self) -> dict[str, object]:
        return {
            "holds": self.holds,
            "note": self.note,
            **{m.name: m.value for m in self.measures},
        }


def _result(number: int, *measures: Measure, note: str = "") -> ConditionResult:
    return ConditionResult(number, all(m.ok for m in measures), tuple(measures), note)


def _norm(v: ArrayLike) -> float:
    return float(np.linalg.norm(np.asarray(v, dtype=float)))


def condition_1(p_RL: ArrayLike, p_L_star: ArrayLike, tol: LandingTolerances) -> ConditionResult:
    """(1) p_RL(t_L) = p*_L."""
    err = _norm(np.asarray(p_RL, dtype=float) - np.asarray(p_L_star, dtype=float))
    return _result(1, Measure("position_error", err, tol.position, "m"))


def attitude_error(z_B: ArrayLike, z_S: ArrayLike) -> float:
    """Angle between z_B and z_S [rad] (robust near 0 and pi)."""
    a, b = np.asarray(z_B, dtype=float), np.asarray(z_S, dtype=float)
    return math.atan2(_norm(np.cross(a, b)), float(a @ b))


def condition_2(z_B: ArrayLike, z_S: ArrayLike, tol: LandingTolerances) -> ConditionResult:
    """(2) z_B(t_L) = z_S: the landers plane parallel to the surface."""
    return _result(2, Measure("attitude_error", attitude_error(z_B, z_S), tol.attitude, "rad"))


def condition_3(v_W: ArrayLike, omega_B: ArrayLike, tol: LandingTolerances) -> ConditionResult:
    """(3) p'_R(t_L-) = 0 and omega(t_L-) = 0."""
    return _result(
        3,
        Measure("speed", _norm(v_W), tol.speed, "m/s"),
        Measure("angular_rate", _norm(omega_B), tol.angular_rate, "rad/s"),
    )


def condition_4(a_W: ArrayLike, omega_dot_B: ArrayLike, tol: LandingTolerances) -> ConditionResult:
    """(4) p''_R(t_L-) = 0 and omega'(t_L-) = 0."""
    return _result(
        4,
        Measure("accel", _norm(a_W), tol.accel, "m/s^2"),
        Measure("angular_accel", _norm(omega_dot_B), tol.angular_accel, "rad/s^2"),
    )


def condition_5_static(contact: ContactForces) -> ConditionResult:
    """(5) by force balance: the contact forces keeping the robot still are admissible."""
    return ConditionResult(
        5,
        contact.holds,
        (
            Measure("normal_force", contact.f_N, math.inf, "N"),
            Measure("friction_margin", contact.friction_margin, math.inf, "N"),
        ),
        note="force balance (6.5) at rest",
    )


def condition_5_observed(
    p_RL: ArrayLike, v_W: ArrayLike, tol: LandingTolerances, z_S: ArrayLike | None = None
) -> ConditionResult:
    """(5) observed: while resting, p_RL does not slide (slip) and the speed stays near zero.

    Parameters
    ----------
    p_RL : (n, 3) array
        Lander point over the resting interval [m].
    v_W : (n, 3) array
        Velocity over the same interval [m/s].
    z_S : (3,) array, optional
        Surface normal at the landing point. Given, the slip is the largest displacement
        of p_RL *along the surface* (sliding), and the displacement along the normal (the
        vehicle settling onto all its landers when the thrust goes) is reported apart as
        ``settle``; without it, the whole displacement counts as slip.
    """
    p = np.asarray(p_RL, dtype=float).reshape(-1, 3)
    v = np.asarray(v_W, dtype=float).reshape(-1, 3)
    d = p - p[0] if len(p) else np.zeros((0, 3))
    settle = 0.0 if len(p) else math.inf
    if z_S is not None and len(p):
        n = np.asarray(z_S, dtype=float)
        n = n / np.linalg.norm(n)
        along = d @ n
        settle = float(np.max(np.abs(along)))
        d = d - np.outer(along, n)
    slip = float(np.max(np.linalg.norm(d, axis=1))) if len(p) else math.inf
    speed = float(np.max(np.linalg.norm(v, axis=1))) if len(v) else math.inf
    return _result(
        5,
        Measure("slip", slip, tol.slip, "m"),
        Measure("rest_speed", speed, tol.rest_speed, "m/s"),
        Measure("settle", settle, math.inf, "m"),
        note="observed while resting",
    )


@dataclass(frozen=True)
class LandingVerdict:
    """All five conditions for one landing."""

    conditions: tuple[ConditionResult, ...]

    @property
    def all_hold(self) -> bool:
        return all(c.holds for c in self.conditions)

    def holds(self, number: int) -> bool:
        return next(c.holds for c in self.conditions if c.number == number)

    def to_dict(self) -> dict[str, bool]:
        return {str(c.number): c.holds for c in self.conditions}


def evaluate_landing(
    *,
    p_RL: ArrayLike,
    z_B: ArrayLike,
    v_W: ArrayLike,
    omega_B: ArrayLike,
    a_W: ArrayLike,
    omega_dot_B: ArrayLike,
    p_L_star: ArrayLike,
    z_S: ArrayLike,
    rest_p_RL: ArrayLike,
    rest_v_W: ArrayLike,
    tol: LandingTolerances | None = None,
) -> LandingVerdict:
    """Evaluate conditions (1)-(5) of one landing.

    The first six arguments describe the state at t_L- (just before contact); ``rest_*``
    are samples from the interval with the motors off, used for condition (5).
    """
    tol = tol or LandingTolerances()
    return LandingVerdict(
        (
            condition_1(p_RL, p_L_star, tol),
            condition_2(z_B, z_S, tol),
            condition_3(v_W, omega_B, tol),
            condition_4(a_W, omega_dot_B, tol),
            condition_5_observed(rest_p_RL, rest_v_W, tol, z_S),
        )
    )


def touchdown_index(heights: ArrayLike, threshold: float) -> int | None:
    """Index of the first sample whose height above the surface is <= ``threshold``.

    Used on logs: with ``heights`` the lander plane's clearance (z_S.(p_RL - O_S)),
    t_L- is the sample before the returned index.
    """
    h = np.asarray(heights, dtype=float)
    hits = np.flatnonzero(h <= threshold)
    return int(hits[0]) if hits.size else None
