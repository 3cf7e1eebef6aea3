"""Static force balances: inclined hovering and resting in contact (chapter 6.3-6.4).

Sign convention: thrust is +f_R z_B (the chapter writes -f_R z_R with z_R = -z_B), the
cable pulls the robot towards the anchor with -f_L d (d from anchor to robot), the
surface pushes with f_N z_S + f_S (6.3)/(6.5).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland import GRAVITY
from tetherland.errors import SingularityError
from tetherland.geometry import FloatArray
from tetherland.surface import Surface

_COS_EPS = 1e-9


def inclined_hover(
    phi: float, theta_A: float, mass: float, g: float = GRAVITY
) -> tuple[float, float]:
    """Thrust and tension holding the planar model (6.18) still at (phi, theta_A).

    f_R = m g cos(phi)/cos(phi + theta_A),  f_L = m g sin(theta_A)/cos(phi + theta_A).

    Returns
    -------
    (f_R, f_L) : tuple of float
        Total thrust and cable tension [N]; f_L < 0 means the cable would have to push.

    Raises
    ------
    SingularityError
        When the thrust axis is parallel to the link (cos(phi + theta_A) = 0).
    """
    den = math.cos(phi + theta_A)
    if abs(den) < _COS_EPS:
        raise SingularityError(
            "thrust axis parallel to the link (phi + theta_A = "
            f"{math.degrees(phi + theta_A):.3f} deg): no inclined hovering"
        )
    return mass * g * math.cos(phi) / den, mass * g * math.sin(theta_A) / den


def hover_tilt_for_tension(phi: float, tension: float, mass: float, g: float = GRAVITY) -> float:
    """theta_A of the inclined hover at elevation ``phi`` with cable tension ``tension`` [rad].

    Inverts :func:`inclined_hover`: tan(theta_A) = f_L cos(phi) / (m g + f_L sin(phi)).
    """
    return math.atan2(tension * math.cos(phi), mass * g + tension * math.sin(phi))


def landing_hover(beta: float, c: float, mass: float, g: float = GRAVITY) -> tuple[float, float]:
    """Thrust and tension of inclined hovering at the landing point p~_L.

    f_R = m g cos(beta - gamma)/cos(gamma), f_L = m g sin(beta)/cos(gamma), gamma = asin(c).
    """
    gamma = math.asin(c)
    return (
        mass * g * math.cos(beta - gamma) / math.cos(gamma),
        mass * g * math.sin(beta) / math.cos(gamma),
    )


@dataclass(frozen=True)
class ContactForces:
    """Contact forces that keep a robot at rest on the surface, and whether they are admissible.

    Attributes
    ----------
    f_N : float
        Normal force along z_S [N].
    f_S : (3,) array
        Friction force in the surface plane, F_W [N].
    f_S_max : float
        Friction limit mu (f_N - f_N_min) [N].
    f_L : float
        Cable tension used in the balance [N].
    holds : bool
        f_N >= f_N_min and ||f_S|| <= f_S_max: condition (5) by force balance.
    """

    f_N: float
    f_S: FloatArray
    f_S_max: float
    f_L: float
    holds: bool

    @property
    def friction_margin(self) -> float:
        """f_S_max - ||f_S|| [N]; negative means the robot slides."""
        return self.f_S_max - float(np.linalg.norm(self.f_S))


def contact_forces(
    surface: Surface,
    mass: float,
    f_R: float,
    z_B: ArrayLike,
    f_L: float = 0.0,
    d: ArrayLike | None = None,
    g: float = GRAVITY,
    tol: float = 1e-9,
) -> ContactForces:
    """Solve (6.5) with p''_R = 0 for the contact force, and check it is admissible.

    0 = -m g z_W + f_R z_B - f_L d + f_N z_S + f_S, with z_S.f_S = 0; admissible when
    f_N >= f_N_min and ||f_S|| <= mu (f_N - f_N_min).
    """
    z_S = surface.z_S
    f_c = mass * g * np.array([0.0, 0.0, 1.0]) - f_R * np.asarray(z_B, dtype=float)
    if f_L != 0.0:
        if d is None:
            raise ValueError("d is required when f_L != 0")
        f_c = f_c + f_L * np.asarray(d, dtype=float)
    f_N = float(z_S @ f_c)
    f_S = f_c - f_N * z_S
    f_S_max = surface.friction * (f_N - surface.f_N_min)
    holds = f_N >= surface.f_N_min - tol and float(np.linalg.norm(f_S)) <= f_S_max + tol
    return ContactForces(f_N=f_N, f_S=f_S, f_S_max=f_S_max, f_L=f_L, holds=bool(holds))


def tethered_rest_tension(surface: Surface, d: ArrayLike, mass: float, g: float = GRAVITY) -> float:
    """Cable tension holding a landed robot, (6.14): f_L = -m g (x_S.z_W)/(x_S.d).

    Valid when (x_S.z_W)(x_S.d) < 0 (landing spot below the anchor); otherwise the cable
    cannot help and the tension is 0 (the contact-free conditions (6.7) apply).
    """
    d = np.asarray(d, dtype=float)
    xz = float(surface.x_S[2])
    xd = float(surface.x_S @ d)
    if xz * xd < 0.0:
        return -mass * g * xz / xd
    return 0.0


def tethered_max_touchdown_thrust(
    surface: Surface, d: ArrayLike, mass: float, g: float = GRAVITY
) -> float:
    """fbar_R of (6.15), corrected: the largest f_R(t_L+) keeping f_N >= f_N_min.

    fbar_R = m g [z_S.z_W - (x_S.z_W)(z_S.d)/(x_S.d)] - f_N_min, with the tension of
    (6.14); for a landing spot not below the anchor it is the contact-free bound (6.7).
    """
    d = np.asarray(d, dtype=float)
    f_L = tethered_rest_tension(surface, d, mass, g)
    return mass * g * float(surface.z_S[2]) + f_L * float(surface.z_S @ d) - surface.f_N_min


def free_flight_max_touchdown_thrust(
    surface: Surface, mass: float, g: float = GRAVITY
) -> float | None:
    """Largest f_R(t_L+) with which a robot without cable stays put (6.6)-(6.7), corrected.

    With z_B = z_S: f_N = m g z_S.z_W - f_R >= f_N_min and m g |x_S.z_W| <= mu (f_N - f_N_min),
    so f_R <= m g z_S.z_W - f_N_min - m g |x_S.z_W|/mu. Returns ``None`` when no thrust
    works because the surface is frictionless and sloped (mu = 0, no division by zero).
    """
    cos_b = float(surface.z_S[2])
    sin_b = abs(float(surface.x_S[2]))
    bound = mass * g * cos_b - surface.f_N_min
    if sin_b <= 1e-12:
        return bound
    if surface.friction <= 0.0:
        return None
    return bound - mass * g * sin_b / surface.friction
