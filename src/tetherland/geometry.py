"""Frames and landing geometry (docs/theory.md section 3, chapter sections 6.2 and 6.4.2).

Frames: F_W (world, z_W up), F_S (surface, x_S downhill), F_A (anchor: z_A = z_W,
y_A = y_S, x_A horizontal and downhill), F_L (link), F_B (body, z_B the thrust axis).
``R_XY`` maps coordinates in Y to coordinates in X; columns of ``R_WS`` are x_S, y_S, z_S.
All lengths in metres, angles in radians. The surface P_S and its frame F_S
(:class:`Surface`, :func:`surface_frame`, ...) are stated in :mod:`tetherland.surface`,
below the configuration; the landing geometry here reads scenarios.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from tetherland import GRAVITY
from tetherland.errors import SingularityError
from tetherland.surface import Z_W, FloatArray, Surface, pipe_sag, surface_frame_of, unit

if TYPE_CHECKING:
    from tetherland.config import Scenario


def anchor_frame(R_WS: FloatArray) -> FloatArray:
    """Rotation R_WA of the anchor frame: z_A = z_W, y_A = y_S, x_A = y_A x z_A.

    y_S is horizontal for every slope (0 to pi), so x_A is the horizontal direction of
    the slope's azimuth: downhill for beta < pi/2, away from the surface for an overhang.
    """
    y_A = R_WS[:, 1]
    x_A = np.cross(y_A, Z_W)
    x_A /= np.linalg.norm(x_A)
    return np.column_stack((x_A, y_A, Z_W))


def link_direction(phi: float, delta: float) -> FloatArray:
    """d_A(phi, delta) = [cos(delta) cos(phi), -sin(delta), cos(delta) sin(phi)] in F_A."""
    cp, sp, cd, sd = math.cos(phi), math.sin(phi), math.cos(delta), math.sin(delta)
    return np.array([cd * cp, -sd, cd * sp])


def approach_at_elevation_A(elevation: float) -> tuple[float, float, float]:
    """The hooking approach n_A = (-cos e, 0, -sin e) in F_A, toward the surface, ``e``
    [rad] below the level approach (pi/2 - slope: along the surface's inward normal),
    rounded as an override is written (6 significant digits, no negative zero) [-]."""
    n = [float(f"{v:.6g}") + 0.0 for v in (-math.cos(elevation), 0.0, -math.sin(elevation))]
    return n[0], n[1], n[2]


def link_frame(phi: float, delta: float) -> FloatArray:
    """R_AL = [x_L y_L z_L] in F_A: x_L = d_A, d(d_A)/dphi = cos(delta) z_L,
    d(d_A)/ddelta = -y_L (docs/theory.md section 3)."""
    cp, sp, cd, sd = math.cos(phi), math.sin(phi), math.cos(delta), math.sin(delta)
    return np.array(
        [
            [cd * cp, cp * sd, -sp],
            [-sd, cd, 0.0],
            [cd * sp, sp * sd, cp],
        ]
    )


def link_jacobian(phi: float, delta: float, length: float) -> FloatArray:
    """J_q = d(l d_A)/d(phi, delta), a 3x2 matrix in F_A [m/rad] (section 6.2.2)."""
    R_AL = link_frame(phi, delta)
    return length * np.column_stack((math.cos(delta) * R_AL[:, 2], -R_AL[:, 1]))


def link_angles(d_A: ArrayLike) -> tuple[float, float]:
    """Elevation and azimuth (phi, delta) of a link direction given in F_A.

    phi = atan2(z_A.d, x_A.d); delta = atan2(-y_A.d, sqrt((x_A.d)^2 + (z_A.d)^2)).
    (The chapter's section 6.5.1 prints +y_A.d, inconsistent with its own d_A; the sign
    here inverts :func:`link_direction`.) For |delta| < pi/2 the inverse is exact.
    """
    d = unit(d_A, "link direction")
    horizontal = math.hypot(d[0], d[2])
    if horizontal < 1e-12:
        raise SingularityError("link direction is along y_A (|delta| = 90 deg): phi undefined")
    return math.atan2(d[2], d[0]), math.atan2(-d[1], horizontal)


def theta_A_from_z_B(z_B_A: ArrayLike, phi: float, delta: float) -> float:
    """Robot tilt theta_A from the thrust axis z_B given in F_A (docs/theory.md section 7).

    alpha is z_B projected on the plane P_L = span(x_L, z_L); theta_A = atan2(x_A.alpha,
    z_A.alpha): the tilt of the thrust axis from vertical towards x_A (downhill).
    """
    z_B = np.asarray(z_B_A, dtype=float)
    y_L = link_frame(phi, delta)[:, 1]
    alpha = z_B - (y_L @ z_B) * y_L
    if math.hypot(alpha[0], alpha[2]) < 1e-12:
        raise SingularityError("thrust axis is perpendicular to the link plane: theta_A undefined")
    return math.atan2(alpha[0], alpha[2])


def theta_A_from_z_B_many(z_B_A: ArrayLike, phi: ArrayLike, delta: ArrayLike) -> FloatArray:
    """:func:`theta_A_from_z_B` of n thrust axes (n, 3) and link angles (n,) [rad], NaN
    where it raises: the same operations in the same order (the same bits), the products
    vectorised, the functions of ``math`` per value (numpy's may differ in the last bit)."""
    z = np.asarray(z_B_A, dtype=float).reshape(-1, 3)
    phi, delta = np.asarray(phi, dtype=float).tolist(), np.asarray(delta, dtype=float).tolist()
    cp, sp = np.array(list(map(math.cos, phi))), np.array(list(map(math.sin, phi)))
    cd, sd = np.array(list(map(math.cos, delta))), np.array(list(map(math.sin, delta)))
    y0, y1, y2 = cp * sd, cd, sp * sd  # y_L, the middle column of link_frame
    along = y0 * z[:, 0] + y1 * z[:, 1] + y2 * z[:, 2]
    a0, a2 = (z[:, 0] - along * y0).tolist(), (z[:, 2] - along * y2).tolist()
    theta = np.array(list(map(math.atan2, a0, a2)))
    theta[np.array(list(map(math.hypot, a0, a2))) < 1e-12] = math.nan
    return theta.reshape(-1)


def lander_point(p_R: ArrayLike, z_B: ArrayLike, h_R: float) -> FloatArray:
    """p_RL = p_R - h_R z_B: the projection of the centre of mass on the landers plane [m]."""
    return np.asarray(p_R, dtype=float) - h_R * np.asarray(z_B, dtype=float)


def hover_cosine(h_R: float, h_A: float, length: float) -> float:
    """c = (h_R - h_A)/l = z_S . d~ (6.9); requires |c| < 1 (P_xy^S d != 0, (6.11))."""
    c = (h_R - h_A) / length
    if not abs(c) < 1.0:
        raise SingularityError(
            f"|h_R - h_A| = {abs(h_R - h_A):g} m must be < l = {length:g} m for inclined hovering"
        )
    return c


def inclined_hover_direction(R_WS: FloatArray, c: float) -> FloatArray:
    """d~ = sqrt(1 - c^2) x_S + c z_S in F_W (6.12): the unique link direction of condition (4)."""
    return math.sqrt(1.0 - c * c) * R_WS[:, 0] + c * R_WS[:, 2]


def inclined_landing_point(
    p_A: ArrayLike,
    R_WS: FloatArray,
    c: float,
    length: float,
    h_R: float,
    r_par_W: ArrayLike | None = None,
) -> FloatArray:
    """p~_L = p_A + l d~ - h_R z_S - r_par (after (6.12), docs/theory.md (3.7)) [m].

    ``r_par_W`` is the part of the landed attachment offset R_WB r_att parallel to the
    surface (default 0, the chapter's cable at the centre of mass); ``h_R`` is then the
    attachment height h_att.
    """
    p = np.asarray(p_A, dtype=float) + length * inclined_hover_direction(R_WS, c) - h_R * R_WS[:, 2]
    return p if r_par_W is None else p - np.asarray(r_par_W, dtype=float)


def anchor_for_landing_point(
    p_L: ArrayLike,
    R_WS: FloatArray,
    c: float,
    length: float,
    h_R: float,
    r_par_W: ArrayLike | None = None,
) -> FloatArray:
    """p~_A = p*_L + h_R z_S + r_par - l d~ (6.13), (3.8): anchor placement for a desired
    landing point [m] (``r_par_W`` as in :func:`inclined_landing_point`)."""
    p = np.asarray(p_L, dtype=float) + h_R * R_WS[:, 2] - length * inclined_hover_direction(R_WS, c)
    return p if r_par_W is None else p + np.asarray(r_par_W, dtype=float)


def landed_rotation(R_WS: FloatArray, heading: float = 0.0) -> FloatArray:
    """R_WB of the landed vehicle: z_B = z_S (condition (2)) and x_B at ``heading`` psi*
    from x_S about z_S, R_WB = R_WS R_z(psi*) [-]."""
    c, s = math.cos(heading), math.sin(heading)
    return R_WS @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def attachment_in_plane(R_WS: FloatArray, r_att_B: ArrayLike, heading: float = 0.0) -> FloatArray:
    """r_par = R_WB r_att - (z_S . R_WB r_att) z_S: the landed attachment offset parallel to
    the surface, in F_W [m] (zero for an offset along z_B only)."""
    r_W = landed_rotation(R_WS, heading) @ np.asarray(r_att_B, dtype=float)
    z_S = R_WS[:, 2]
    return r_W - float(z_S @ r_W) * z_S


@dataclass(frozen=True)
class LandingGeometry:
    """Everything section 6.4.2 derives from the scenario's geometry.

    Attributes
    ----------
    surface : Surface
    R_WA : (3, 3) array
        Anchor frame rotation.
    p_A : (3,) array
        Anchor point in F_W [m].
    length : float
        Cable length l [m].
    h_R : float
        Centre-of-mass height above the surface when landed [m] (on a pipe: the
        vehicle's h_R minus :func:`pipe_sag`).
    h_att : float
        Height of the cable attachment point above the surface when landed,
        h_R + z_B.r_att [m]. The link (phi, delta, l) ends at this point; with the
        attachment at the centre of mass (the chapter's assumption) h_att = h_R.
    h_A : float
        Anchor height above the surface [m].
    c : float
        (h_att - h_A)/l (6.9).
    d_tilde : (3,) array
        Inclined-hovering link direction d~ in F_W (6.12).
    p_L : (3,) array
        Landing point p~_L = p*_L in F_W [m].
    phi_star, delta_star, theta_A_star : float
        Final desired output (section 6.5.1) [rad]: phi* = gamma - beta, delta* = 0,
        theta_A* = beta.
    """

    surface: Surface
    R_WA: FloatArray
    p_A: FloatArray
    length: float
    h_R: float
    h_att: float
    h_A: float
    c: float
    d_tilde: FloatArray
    p_L: FloatArray
    phi_star: float
    delta_star: float
    theta_A_star: float
    r_par_W: FloatArray = field(default_factory=lambda: np.zeros(3))
    """Landed attachment offset parallel to the surface, R_WB r_att less its z_S part, in
    F_W [m] (:func:`attachment_in_plane`; zero for an offset along z_B): the attachment
    point is p~_L + h_att z_S + r_par (docs/theory.md section 3.4)."""
    stretch: float = 0.0
    """Elongation s of an elastic cable at the landed hover's tension [m]: the landed link
    is l + s long, and c, d~, phi*, p_L (or the anchor placed for p*_L) are those of
    l + s (:func:`stretched_landing`; 0 for an inextensible cable). ``length`` stays l."""
    axial_stiffness: float | None = None
    """Effective EA of the cable [N] that ``stretch`` was solved for (None: inextensible),
    kept so that the analysis can re-solve the stretch at other slopes (:meth:`cosine_at`)."""

    @property
    def link_length(self) -> float:
        """Length of the taut link in the tethered phase, l + s [m]: the cable stretched by
        the landed hover's tension f_L (docs/theory.md section 4.2; l when inextensible).
        Every model of the taut link (planner, flatness map, controllers) uses it."""
        return self.length + self.stretch

    def cosine_at(self, slope: float, mass: float, g: float = GRAVITY) -> float:
        """c = (h_att - h_A)/(l + s) of this cable on a ``slope`` [rad] holding ``mass``
        [kg] in the landed hover (s re-solved there by :func:`stretched_link_length`;
        :attr:`c` at the surface's own slope, and for an inextensible cable) [-]."""
        if self.axial_stiffness is None:
            return self.c
        h = self.h_att - self.h_A
        return h / stretched_link_length(h, self.length, slope, mass, self.axial_stiffness, g)

    @property
    def gamma(self) -> float:
        """gamma = asin(c): elevation of d~ above the surface [rad]."""
        return math.asin(self.c)

    @property
    def p_R_landed(self) -> FloatArray:
        """Centre of mass when landed, p~_L + h_R z_S [m]."""
        return self.p_L + self.h_R * self.surface.z_S

    @property
    def p_att_landed(self) -> FloatArray:
        """Cable attachment point when landed, p~_L + h_att z_S + r_par = p_A + (l + s) d~
        [m]."""
        return self.p_L + self.h_att * self.surface.z_S + self.r_par_W

    def to_anchor(self, v_W: ArrayLike) -> FloatArray:
        """Express a world vector in F_A."""
        return self.R_WA.T @ np.asarray(v_W, dtype=float)

    def link_end(self, phi: float, delta: float) -> FloatArray:
        """End of the taut link, p_A + (l + s) R_WA d_A(phi, delta): the attachment point
        [m]."""
        return self.p_A + self.link_length * (self.R_WA @ link_direction(phi, delta))

    @classmethod
    def from_scenario(cls, scenario: Scenario) -> LandingGeometry:
        """Build the landing geometry of a (validated) scenario."""
        surface = surface_from_config(scenario)
        kwargs = dict(
            length=scenario.tether.length,
            h_R=effective_h_R(scenario),
            h_att=attachment_height(scenario),
            h_A=scenario.anchor.h_A,
            anchor=scenario.anchor.position,
            landing_point=scenario.anchor.landing_point,
            r_par_W=attachment_in_plane(
                surface.R_WS,
                scenario.vehicle.cable_attachment,
                math.radians(scenario.planner.heading_deg),
            ),
        )
        rigid = landing_geometry(surface, **kwargs)  # type: ignore[arg-type]
        EA = scenario.tether.effective_axial_stiffness
        if EA is None:
            return rigid
        s = stretched_landing(rigid, scenario.vehicle.mass, EA).stretch
        return landing_geometry(
            surface, stretch=s, axial_stiffness=EA, **kwargs  # type: ignore[arg-type]
        )


def landing_geometry(
    surface: Surface,
    *,
    length: float,
    h_R: float,
    h_A: float,
    h_att: float | None = None,
    anchor: ArrayLike | None = None,
    landing_point: ArrayLike | None = None,
    r_par_W: ArrayLike | None = None,
    stretch: float = 0.0,
    axial_stiffness: float | None = None,
) -> LandingGeometry:
    """Landing geometry from an explicit anchor or a desired landing point (6.8)-(6.13).

    With ``anchor`` given, the landing point is p~_L; otherwise the anchor is p~_A placed
    for ``landing_point`` (default: the surface origin). ``h_att`` (default ``h_R``) is
    the height of the cable attachment point when landed; the chapter's formulas use
    h_R because its cable is attached at the centre of mass. ``stretch`` s [m] makes the
    landed link l + s long (an elastic cable at the landed hover's tension, docs/theory.md
    section 13.2: c, d~, phi* and p~_L or p~_A are those of l + s); ``axial_stiffness``
    EA [N] is only recorded (:meth:`LandingGeometry.cosine_at`).
    """
    h_att = h_R if h_att is None else h_att
    radius = length + stretch  # the landed link: l, or l + s for a stretched elastic cable
    c = hover_cosine(h_att, h_A, radius)
    R_WS = surface.R_WS
    r_par = np.zeros(3) if r_par_W is None else np.asarray(r_par_W, dtype=float)
    if anchor is not None:
        p_A = np.asarray(anchor, dtype=float)
        p_L = inclined_landing_point(p_A, R_WS, c, radius, h_att, r_par)
    else:
        p_L = np.asarray(surface.origin if landing_point is None else landing_point, dtype=float)
        p_L = surface.project(p_L)
        p_A = anchor_for_landing_point(p_L, R_WS, c, radius, h_att, r_par)
    R_WA = anchor_frame(R_WS)
    d_tilde = inclined_hover_direction(R_WS, c)
    # In F_A, x_S = [cos(beta), 0, -sin(beta)] and z_S = [sin(beta), 0, cos(beta)], so
    # d~ = [cos(gamma - beta), 0, sin(gamma - beta)]: phi* = gamma - beta, delta* = 0
    # (section 6.5.1), taken on this branch rather than atan2's (-pi, pi] so that it stays
    # continuous past beta = pi/2 + gamma; theta_A* = beta in [0, pi].
    beta = surface.slope
    phi_star, delta_star = math.asin(c) - beta, 0.0
    theta_A_star = beta
    return LandingGeometry(
        surface=surface,
        R_WA=R_WA,
        p_A=p_A,
        length=length,
        h_R=h_R,
        h_att=h_att,
        h_A=h_A,
        c=c,
        d_tilde=d_tilde,
        p_L=p_L,
        phi_star=phi_star,
        delta_star=delta_star,
        theta_A_star=theta_A_star,
        r_par_W=r_par,
        stretch=stretch,
        axial_stiffness=axial_stiffness,
    )


def surface_from_config(scenario: Scenario) -> Surface:
    """The :class:`Surface` described by a scenario's ``[surface]`` section."""
    cfg = scenario.surface
    return Surface(
        origin=np.asarray(cfg.origin, dtype=float),
        R_WS=surface_frame_of(
            cfg.normal, math.radians(cfg.slope_deg), math.radians(cfg.azimuth_deg)
        ),
        kind=cfg.kind,
        pipe_radius=cfg.pipe_radius if cfg.kind == "pipe" else 0.0,
        friction=cfg.friction,
        f_N_min=cfg.f_N_min,
    )


def effective_h_R(scenario: Scenario) -> float:
    """h_R of the landed vehicle above P_S: the vehicle's h_R, less the sag on a pipe [m]."""
    v = scenario.vehicle
    h_R = v.h_R
    if scenario.surface.kind == "pipe":
        h_R -= pipe_sag(scenario.surface.pipe_radius, v.lander_half_width, v.lander_radius)
    return h_R


def attachment_height(scenario: Scenario) -> float:
    """Height of the cable attachment point above P_S when landed with z_B = z_S [m].

    h_att = effective h_R + r_att,z. The offset across z_B does not change this height;
    it shifts the landing point by -r_par (:func:`attachment_in_plane`).
    """
    return effective_h_R(scenario) + scenario.vehicle.cable_attachment[2]


# -- elastic cable: the stretch at the landed hover (docs/tether.md) ----------------------

STRETCH_ITERATIONS = 50
"""Fixed-point iterations of :func:`stretched_landing` (converges in a few)."""


def cable_stretch(tension: float, length: float, axial_stiffness: float | None) -> float:
    """Static elongation s = f_L l / EA of a cable of unstretched length ``length`` [m]
    under ``tension`` [N] (0 for an inextensible cable, EA None, or a slack one) [m]."""
    if axial_stiffness is None or tension <= 0.0:
        return 0.0
    return tension * length / axial_stiffness


def landed_hover_tension(slope: float, c: float, mass: float, g: float) -> float:
    """f_L = m g sin(beta)/cos(gamma), gamma = asin(c): the tension of inclined hovering at
    the landing point with the cable in the fall-line plane (docs/theory.md section 13) [N]."""
    return mass * g * math.sin(slope) / math.sqrt(1.0 - c * c)


@dataclass(frozen=True)
class StretchedLanding:
    """Where an elastic cable puts the touchdown (docs/tether.md).

    At the landed hover the cable holds f_L and is l + s long, s = f_L l/EA, so the link
    elevation is phi*' = asin(c') - beta with c' = (h_att - h_A)/(l + s): the touchdown
    point moves by about s along the cable, downhill. Feed-forward: plan for ``phi_star``
    (the rigid model of length l ends s short along d~, 0.4 mm above the surface for
    gamma = 4 deg and s = 6 mm), and place the anchor at ``anchor_for_p_L`` for the
    stretched cable to land on p*_L.

    Attributes
    ----------
    tension : float
        f_L at the stretched landing point [N].
    stretch : float
        s [m].
    geometry : LandingGeometry
        The landing geometry with the same anchor and length l + s: its ``p_L``,
        ``d_tilde`` and ``phi_star`` are the real touchdown's.
    shift_W : (3,) array
        Touchdown point moved from the rigid cable's p~_L, in F_W [m].
    anchor_for_p_L : (3,) array
        Anchor (6.13) with the stretched length, which puts the touchdown at the rigid
        geometry's p_L [m].
    """

    tension: float
    stretch: float
    geometry: LandingGeometry
    shift_W: FloatArray
    anchor_for_p_L: FloatArray

    @classmethod
    def from_scenario(cls, scenario: Scenario) -> StretchedLanding:
        """The stretched touchdown of a scenario's tether (stiffness, vehicle mass) at its
        landing geometry (:meth:`LandingGeometry.from_scenario`, which already places the
        anchor, or the touchdown, for the stretched cable: ``shift_W`` is then zero)."""

        return stretched_landing(
            LandingGeometry.from_scenario(scenario),
            scenario.vehicle.mass,
            scenario.tether.effective_axial_stiffness,
        )


def stretched_link_length(
    height: float,
    length: float,
    slope: float,
    mass: float,
    axial_stiffness: float | None,
    g: float = GRAVITY,
) -> float:
    """Length l + s [m] of a cable of unstretched ``length`` l [m] and stiffness EA =
    ``axial_stiffness`` [N] holding ``mass`` [kg] in the landed inclined hover on a
    ``slope`` [rad], its attachment ``height`` = h_att - h_A [m] above the anchor's height.

    Solves s = f_L(c') l/EA, c' = height/(l + s), f_L = m g sin(beta)/cos(gamma') (6.10)
    by fixed-point iteration (a contraction: ds'/ds = O(c^2 f_L/EA)); l for an
    inextensible cable (EA None) or a slack one (|c'| >= 1 leaves it to the caller).
    """
    if axial_stiffness is None:
        return length
    s = 0.0
    for _ in range(STRETCH_ITERATIONS):
        c = height / (length + s)
        if not abs(c) < 1.0:
            return length + s
        s_new = cable_stretch(landed_hover_tension(slope, c, mass, g), length, axial_stiffness)
        done = abs(s_new - s) <= 1e-15 * length
        s = s_new
        if done:
            break
    return length + s


def stretched_landing(
    geo: LandingGeometry, mass: float, axial_stiffness: float | None, g: float = GRAVITY
) -> StretchedLanding:
    """The touchdown of a cable with stiffness EA = ``axial_stiffness`` [N] holding a vehicle
    of ``mass`` [kg] in inclined hovering at the landing point of ``geo``.

    Solves s = f_L(c') l/EA with c' = (h_att - h_A)/(l + s) by fixed-point iteration
    (a contraction: ds'/ds = O(c^2 f_L/EA)). Inextensible (None): s = 0 and ``geo``.
    ``geo`` may already be stretched (:meth:`LandingGeometry.from_scenario` of an elastic
    tether): its anchor is kept, and its landing point is then the stretched touchdown.
    """
    h = geo.h_att - geo.h_A
    l = geo.length
    beta = geo.surface.slope
    s = stretched_link_length(h, l, beta, mass, axial_stiffness, g) - l
    f_L = landed_hover_tension(beta, h / (l + s), mass, g)
    stretched = landing_geometry(
        geo.surface,
        length=l,
        stretch=s,
        axial_stiffness=axial_stiffness,
        h_R=geo.h_R,
        h_A=geo.h_A,
        h_att=geo.h_att,
        anchor=geo.p_A,
        r_par_W=geo.r_par_W,
    )
    anchor = anchor_for_landing_point(
        geo.p_L, geo.surface.R_WS, stretched.c, l + s, geo.h_att, geo.r_par_W
    )
    return StretchedLanding(f_L, s, stretched, stretched.p_L - geo.p_L, anchor)
