"""The believed ground effect along a planned tethered path (issue 23 item 4, an option).

The rotors' limits [f_min, f_max] are limits of the rotor speed, c_f w^2. Near a surface a
rotor's acting thrust is f = k c_f w^2 with k >= 1 the ground-effect factor (docs/aero.md),
and ``controller.ground_effect_compensation`` commands c_f w^2 = f / k for a wanted acting
thrust f, with k of the *believed* surface. The tethered plan is a plan of acting thrusts
(its dynamics are the planar model's); with ``planner.model_ground_effect`` its rotor
bounds hold the commands f_i / k_i, k_i along the planned path, instead of the acting
thrusts f_i. Nothing else of the statement depends on the command: the dynamics, the cost
(f'') and the terminal hover are written in acting thrusts.

The factor is the belief's (:class:`~tetherland.estimation.ground_effect.
BelievedGroundEffect`: the believed surface, the believed rotor disks and radius, its
disk samples, the same bound z_min), written in CasADi as a function of the planar state
(phi, theta_A): the pose is the link end p_A + R_WA l d(phi) less the attachment offset
R_WB r_att, R_WB = R_WA R_y(theta_A) R_z(psi*) (docs/theory.md sections 4 and 6). Each
disk sample casts a ray along the wake -z_B to

- a plane (``surface.kind = "plane"``): the believed patch's top face, taken without its
  edges (the default patch reaches 3 m from its origin, beyond any tethered swing);
- a pipe: the believed cylinder, taken without its end caps.

The belief also takes every factor as 1 beyond
:data:`~tetherland.estimation.ground_effect.FAR_RATIO` rotor radii; here the factor goes on
falling there, within 1 / (1 - (1/(4 FAR_RATIO))^2) - 1 = 1.6e-4 of 1 (no jump in the
statement). Everything the robot does not know is not read: the plant's ``[aero]`` never.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from tetherland.estimation.ground_effect import BelievedGroundEffect
from tetherland.geometry import FloatArray, LandingGeometry, surface_from_config
from tetherland.models.aero import CHEESEMAN_BENNETT

if TYPE_CHECKING:
    from tetherland.config import Scenario

SurfaceKind = Literal["plane", "pipe"]

# Fields of the packed data (:attr:`PlannedGroundEffect.values`), in order, and their sizes.
_FIELDS = (
    ("p_A", 3), ("R_WA", 9), ("length", 1), ("heading", 1), ("r_att_B", 3),
    ("centres_B", 12), ("radius", 1), ("z_min", 1), ("origin", 3), ("z_S", 3), ("x_S", 3),
    ("pipe_radius", 1),
)  # fmt: skip
SIZE = sum(n for _, n in _FIELDS)
"""Number of parameters of the planned ground effect [-]."""
_SLICES = {
    name: slice(start, start + n)
    for (name, n), start in zip(
        _FIELDS, np.cumsum([0] + [n for _, n in _FIELDS[:-1]]).tolist(), strict=True
    )
}
_TINY = 1e-12
"""Guard of the divisions by a ray's approach rate (a ray that does not approach misses)."""


@dataclass(frozen=True)
class PlannedGroundEffect:
    """The believed ground effect a tethered plan models (``planner.model_ground_effect``).

    Attributes
    ----------
    kind : {"plane", "pipe"}
        The believed surface: a plane's top face or a pipe's cylinder.
    samples : (S, 2) array
        The belief's unit-disk samples (:func:`~tetherland.models.aero.disk_samples`):
        they are part of the statement, not of its numbers.
    values : (SIZE,) array
        The numbers: anchor p_A [m], R_WA (row-major), link length l + s [m], heading
        psi* [rad], attachment offset r_att in F_B [m], rotor disk centres in F_B (4, 3)
        [m], rotor radius R [m], z_min [m], the surface origin P_S [m], normal z_S and
        axis x_S [-], the pipe radius [m] (0 for a plane).
    """

    kind: SurfaceKind
    samples: FloatArray
    values: FloatArray

    @classmethod
    def from_scenario(
        cls, scenario: Scenario, geometry: LandingGeometry, length: float, heading: float
    ) -> PlannedGroundEffect:
        """The believed ground effect of the (believed) ``scenario`` for a maneuver on the
        link of ``length`` l + s [m] at ``heading`` psi* [rad]."""
        model, surf = BelievedGroundEffect(scenario).model, surface_from_config(scenario)
        kind: SurfaceKind = "pipe" if surf.kind == "pipe" else "plane"
        parts = {
            "p_A": geometry.p_A, "R_WA": np.asarray(geometry.R_WA).reshape(-1),
            "length": length, "heading": heading,
            "r_att_B": scenario.vehicle.cable_attachment,
            "centres_B": np.asarray(model.rotor_centres_B).reshape(-1),
            "radius": model.radius, "z_min": model.z_min_ratio * model.radius,
            "origin": surf.origin, "z_S": surf.z_S, "x_S": surf.x_S,
            "pipe_radius": surf.pipe_radius if kind == "pipe" else 0.0,
        }  # fmt: skip
        values = np.concatenate([np.atleast_1d(np.asarray(parts[n], float)) for n, _ in _FIELDS])
        samples = np.array(model.samples, dtype=float)
        return cls(kind=kind, samples=samples, values=values)

    @property
    def key(self) -> tuple[str, bytes]:
        """What the statement depends on: the surface kind and the disk samples."""
        return self.kind, self.samples.tobytes()

    def factors(self, phi: ArrayLike, theta_A: ArrayLike) -> FloatArray:
        """Believed factor k_i of each rotor at the planar states (phi, theta_A) [rad],
        (n, 4) for n states [-]."""
        phi = np.atleast_1d(np.asarray(phi, dtype=float))
        theta = np.atleast_1d(np.asarray(theta_A, dtype=float))
        fn = _factor_function(*self.key).map(phi.size)
        k = fn(phi[None, :], theta[None, :], np.repeat(self.values[:, None], phi.size, axis=1))
        return np.asarray(k, dtype=float).T

    def commands(self, thrusts: FloatArray, phi: ArrayLike, theta_A: ArrayLike) -> FloatArray:
        """The rotor commands c_f w^2 = f_i / k_i of acting thrusts ``thrusts`` (n, 4) [N]
        at the planar states (phi, theta_A) (n,) [rad] [N]."""
        return np.asarray(thrusts, dtype=float) / self.factors(phi, theta_A)


def factors_expr(
    phi: ca.SX, theta_A: ca.SX, g: ca.SX, kind: SurfaceKind, samples: FloatArray
) -> ca.SX:
    """The believed factors (4,) at the planar state (phi, theta_A), CasADi, on the packed
    data ``g`` (:attr:`PlannedGroundEffect.values`) [-]."""

    def field(name: str) -> ca.SX:
        return g[_SLICES[name]]

    R_WA = ca.reshape(field("R_WA"), 3, 3).T  # row-major values
    c_t, s_t = ca.cos(theta_A), ca.sin(theta_A)
    c_p, s_p = ca.cos(field("heading")), ca.sin(field("heading"))
    R_y = ca.vertcat(ca.horzcat(c_t, 0, s_t), ca.horzcat(0, 1, 0), ca.horzcat(-s_t, 0, c_t))
    R_z = ca.vertcat(ca.horzcat(c_p, -s_p, 0), ca.horzcat(s_p, c_p, 0), ca.horzcat(0, 0, 1))
    R_WB = R_WA @ R_y @ R_z
    d_A = ca.vertcat(ca.cos(phi), 0, ca.sin(phi))
    p_W = field("p_A") + R_WA @ (field("length") * d_A) - R_WB @ field("r_att_B")
    u = -R_WB[:, 2]  # the wake
    R, z_min = field("radius"), field("z_min")
    centres = ca.reshape(field("centres_B"), 3, 4)  # column i: rotor i (row-major values)
    k = []
    for i in range(4):
        total = 0
        for sx, sy in samples:
            q = p_W + R_WB @ (centres[:, i] + R * ca.DM([sx, sy, 0.0]))
            hit, z = _ray(q, u, g, kind)
            z = ca.fmax(z, z_min)
            total += ca.if_else(hit, 1 / (1 - CHEESEMAN_BENNETT * (R / z) ** 2), 1)
        k.append(total / len(samples))
    return ca.vertcat(*k)


def _ray(q: ca.SX, u: ca.SX, g: ca.SX, kind: SurfaceKind) -> tuple[ca.SX, ca.SX]:
    """(hit, distance) along the unit ray q + t u, t >= 0, to the believed surface; a
    point inside the surface is at distance 0 [m]."""
    o, n = g[_SLICES["origin"]], g[_SLICES["z_S"]]
    if kind == "plane":
        height, approach = ca.dot(n, q - o), -ca.dot(n, u)
        return ca.logic_or(height <= 0, approach > 0), ca.fmax(height, 0) / ca.fmax(approach, _TINY)
    r, a = g[_SLICES["pipe_radius"]], g[_SLICES["x_S"]]
    w = q - (o - r * n)  # from a point of the pipe's axis
    wa, ua = ca.dot(w, a), ca.dot(u, a)
    rho2 = ca.dot(w, w) - wa**2  # squared distance from the axis
    across = 1 - ua**2  # |u across the axis|^2
    half = ca.dot(w, u) - wa * ua
    disc = half**2 - across * (rho2 - r**2)
    t = (-half - ca.sqrt(ca.fmax(disc, 0))) / ca.fmax(across, _TINY)
    inside = rho2 <= r**2
    side = ca.logic_and(ca.logic_and(across > _TINY, disc >= 0), t >= 0)
    return ca.logic_or(inside, side), ca.if_else(inside, 0, t)


@functools.cache
def _factor_function(kind: SurfaceKind, samples: bytes) -> ca.Function:
    """k(phi, theta_A, values) as a CasADi Function (built once per kind and samples)."""
    phi, theta, g = ca.SX.sym("phi"), ca.SX.sym("theta_A"), ca.SX.sym("g", SIZE)
    pts = np.frombuffer(samples, dtype=float).reshape(-1, 2)
    return ca.Function(
        "planned_ground_effect", [phi, theta, g], [factors_expr(phi, theta, g, kind, pts)],
        ["phi", "theta_A", "g"], ["k"],
    )  # fmt: skip


def factor_function(effect: PlannedGroundEffect) -> ca.Function:
    """:func:`factors_expr` of ``effect``'s kind and samples as a CasADi Function of
    (phi, theta_A, g) (built once)."""
    return _factor_function(*effect.key)


__all__ = ["SIZE", "PlannedGroundEffect", "factor_function", "factors_expr"]
