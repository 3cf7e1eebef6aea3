"""Contact-free versus tethered landing: feasibility and slope limits (chapter 6.4).

For the scenario's vehicle and surface this module answers, for each method, which
landing conditions can be met, the largest thrust allowed at touchdown, and the steepest
slope the vehicle can take, counting rotor limits f_min <= f_i <= f_max with the
``control_margin`` kept per rotor for attitude control.

Hover first: both methods fly free before and after the landing (take-off, approach,
hooking pass, return), so every analysis checks before anything else that the vehicle
can hover in free flight with the control margin (:func:`free_hover`); a vehicle that
cannot is infeasible on every slope, with ``cannot_hover`` binding.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from tetherland import GRAVITY
from tetherland.analysis.statics import (
    contact_forces,
    free_flight_max_touchdown_thrust,
    landing_hover,
    tethered_max_touchdown_thrust,
    tethered_rest_tension,
)
from tetherland.config import Scenario
from tetherland.geometry import FloatArray, LandingGeometry, inclined_hover_direction
from tetherland.models.quadrotor import RotorLayout
from tetherland.surface import Surface, surface_frame_from_slope

_TOL = 1e-9


@dataclass(frozen=True)
class VehicleLimits:
    """Mass, rotor limits and geometry that decide feasibility.

    Attributes
    ----------
    mass : float
        [kg]
    f_min, f_max : float
        Per-rotor thrust limits [N].
    margin : float
        Per-rotor thrust kept free for attitude control on both sides [N].
    n_rotors : int
    allocation_inverse : (n, 4) array or None
        Gamma^-1 (6.19); None treats the thrust as shared equally (no torque).
    r_att_B : (3,) array
        Cable attachment offset in F_B [m]; its torque must be cancelled by the rotors
        (6.6.5), which shifts the rotor thrusts at the landing hover.
    heading : float
        psi of the landed vehicle, rotation of x_B from x_S about z_S [rad].
    """

    mass: float
    f_min: float
    f_max: float
    margin: float
    n_rotors: int = 4
    allocation_inverse: FloatArray | None = None
    r_att_B: FloatArray = field(default_factory=lambda: np.zeros(3))
    heading: float = 0.0

    @classmethod
    def from_scenario(cls, scenario: Scenario) -> VehicleLimits:
        v = scenario.vehicle
        return cls(
            v.mass,
            v.f_min,
            v.f_max,
            v.control_margin,
            allocation_inverse=RotorLayout.from_config(v).allocation_inverse,
            r_att_B=np.asarray(v.cable_attachment, dtype=float),
            heading=math.radians(scenario.planner.heading_deg),
        )

    def free_hover_rotor_thrusts(self, g: float = GRAVITY) -> FloatArray:
        """Rotor thrusts of the hover in free flight: total m g, no torque [N]."""
        if self.allocation_inverse is None:
            return np.full(self.n_rotors, self.mass * g / self.n_rotors)
        return self.allocation_inverse @ np.array([self.mass * g, 0.0, 0.0, 0.0])

    def thrust_to_weight(self, g: float = GRAVITY) -> float:
        """n f_max / (m g) [-]."""
        return self.n_rotors * self.f_max / (self.mass * g)

    @property
    def hover_thrust_to_weight(self) -> float:
        """Least thrust-to-weight ratio that hovers with the control margin kept,
        f_max / (f_max - margin) [-] (the heavy side of :func:`free_hover`)."""
        return self.f_max / (self.f_max - self.margin)

    @property
    def min_controllable_thrust(self) -> float:
        """n (f_min + margin): least total thrust leaving attitude authority [N]."""
        return self.n_rotors * (self.f_min + self.margin)

    @property
    def max_controllable_thrust(self) -> float:
        """n (f_max - margin) [N]."""
        return self.n_rotors * (self.f_max - self.margin)

    def landed_hover_rotor_thrusts(self, c: float, f_R: float, f_L: float) -> FloatArray:
        """Rotor thrusts of inclined hovering at p~_L, cancelling the cable-offset torque.

        With z_B = z_S and x_B turned by ``heading`` from x_S, d~ in F_B is
        R_z(-psi) [sqrt(1 - c^2), 0, c]; the rotors must add tau = r_att x (f_L d_B).
        """
        if self.allocation_inverse is None:
            return np.full(self.n_rotors, f_R / self.n_rotors)
        ch, sh = math.cos(self.heading), math.sin(self.heading)
        s = math.sqrt(1.0 - c * c)
        d_B = np.array([ch * s, -sh * s, c])
        tau = np.cross(self.r_att_B, f_L * d_B)
        return self.allocation_inverse @ np.array([f_R, *tau])


class Infeasibility(enum.Enum):
    """Why a landing is infeasible: the requirement that fails (docs/theory.md sections 5, 13).

    For both methods the free hover binds first (:attr:`CANNOT_HOVER`); then, for the
    tethered landing at p~_L, the others in the order in which they bind (the first one
    failing is :attr:`TetheredAnalysis.binding`), and the contact-free ones last.
    """

    CANNOT_HOVER = "cannot_hover"
    """The vehicle cannot hover in free flight keeping the control margin: the hover's
    rotor thrusts (m g / n each) lie outside [f_min + control_margin, f_max -
    control_margin] (:func:`free_hover`). Every mission flies free before and after the
    landing, so no slope is feasible."""

    NO_INCLINED_HOVER = "no_inclined_hover"
    """beta >= 90 deg + gamma: the landed inclined hover would need f_R =
    m g cos(beta - gamma)/cos(gamma) <= 0, so none exists."""
    ROTOR_FLOOR = "rotor_floor"
    """The landed hover thrust per rotor f_R/n is below f_min + control_margin (too small
    or negative): slope too steep for this vehicle."""
    ROTOR_CEILING = "rotor_ceiling"
    """The landed hover thrust per rotor is above f_max - control_margin."""
    OFFSET_TORQUE = "offset_torque"
    """The thrust fits on average, but cancelling the cable-offset torque
    r_att x (f_L d) (6.6.5) pushes a rotor out of [f_min + margin, f_max - margin]."""
    NORMAL_FORCE = "normal_force"
    """Motors off: the surface would have to pull, f_N < f_N_min."""
    FRICTION_MOTORS_OFF = "friction_motors_off"
    """Motors off: the shear force exceeds mu (f_N - f_N_min), the robot slides."""
    NO_CONDITION_4 = "no_condition_4"
    """Contact-free only: condition (4) cannot hold on a sloped surface (section 6.4.1)."""
    TOUCHDOWN_THRUST = "touchdown_thrust"
    """Contact-free only: condition (5) needs a touchdown thrust below the least
    controllable thrust n (f_min + margin)."""


@dataclass(frozen=True)
class Check:
    """One feasibility requirement, its signed margin and a one-line explanation.

    Attributes
    ----------
    reason : Infeasibility
        What fails when the margin is negative.
    margin : float
        Signed margin of the requirement [N]; >= 0 when it holds (inf: nothing to check,
        e.g. no cable-offset torque).
    message : str
        Numbers behind the check (one line).
    """

    reason: Infeasibility
    margin: float
    message: str

    @property
    def ok(self) -> bool:
        return bool(self.margin >= -_TOL)


@dataclass(frozen=True)
class LandedHover:
    """The landed inclined hover at p~_L and the rest with the motors off, checked.

    Attributes
    ----------
    slope, c, gamma : float
        beta [rad], c = (h_att - h_A)/l [-] and gamma = asin(c) [rad].
    thrust, tension : float
        f_R = m g cos(beta - gamma)/cos(gamma), f_L = m g sin(beta)/cos(gamma) [N].
    rotor_thrusts : (n,) array
        Rotor thrusts of that hover, cancelling the cable-offset torque [N].
    rest_tension, rest_normal_force, rest_friction_margin : float
        Motors off: f_L (6.14), f_N and f_S_max - ||f_S|| [N] (the friction check uses
        mu max(f_N - f_N_min, 0): a surface that would have to pull fails on its normal force).
    checks : tuple of Check
        Every requirement in :data:`binding order <Infeasibility>`.
    """

    slope: float
    c: float
    gamma: float
    thrust: float
    tension: float
    rotor_thrusts: FloatArray
    rest_tension: float
    rest_normal_force: float
    rest_friction_margin: float
    checks: tuple[Check, ...]

    @property
    def findings(self) -> tuple[Check, ...]:
        """The failed checks, the binding one first (empty when feasible)."""
        return tuple(c for c in self.checks if not c.ok)

    @property
    def feasible(self) -> bool:
        return not self.findings

    @property
    def binding(self) -> Infeasibility | None:
        """The requirement that binds (None when feasible)."""
        failed = self.findings
        return failed[0].reason if failed else None

    @property
    def margin(self) -> float:
        """Smallest signed margin of all checks [N] (>= 0 when feasible)."""
        return min(c.margin for c in self.checks)


def free_hover(limits: VehicleLimits, g: float = GRAVITY) -> Check:
    """Can the vehicle hover in free flight with the control margin kept on both sides?

    The rule: hovering needs the total thrust m g with no torque, f = Gamma^-1 [m g, 0, 0,
    0] (m g / n per rotor), and every rotor must stay in [f_min + control_margin, f_max -
    control_margin], the band in which the attitude controller keeps its authority (the
    same band as every other check here). Above it the vehicle is too heavy, m g > n
    (f_max - control_margin): its thrust-to-weight ratio n f_max / (m g) is below
    f_max / (f_max - control_margin); below it the rotors cannot throttle down to the
    weight. This is the least a mission needs: climbing, turning and the pull that
    stretches the cable need more.

    Returns
    -------
    Check
        Reason :attr:`Infeasibility.CANNOT_HOVER`, margin min_i min(f_i - f_min - margin,
        f_max - margin - f_i) [N] (>= 0: it can hover).
    """
    thrusts = limits.free_hover_rotor_thrusts(g)
    lo, hi = limits.f_min + limits.margin, limits.f_max - limits.margin
    weight = limits.mass * g
    margin = min(float(thrusts.min()) - lo, hi - float(thrusts.max()))
    if margin >= -_TOL:
        lo_f, hi_f = f"{thrusts.min():.3f}", f"{thrusts.max():.3f}"
        message = (
            f"the vehicle hovers: m g = {weight:.2f} N needs "
            f"{lo_f if lo_f == hi_f else f'{lo_f}-{hi_f}'} N per rotor, inside [f_min + "
            f"control_margin, f_max - control_margin] = [{lo:.3f}, {hi:.3f}] N"
        )
    elif hi - float(thrusts.max()) <= float(thrusts.min()) - lo:
        message = (
            f"the vehicle cannot hover: m g = {weight:.2f} N needs {thrusts.max():.3f} N per "
            f"rotor, above f_max - control_margin = {hi:.3f} N (thrust-to-weight ratio "
            f"{limits.thrust_to_weight(g):.2f}, needs >= {limits.hover_thrust_to_weight:.2f} "
            f"with the control margin): lighten it below {limits.n_rotors * hi / g:.3g} kg or "
            "raise vehicle.f_max"
        )
    else:
        message = (
            f"the vehicle cannot hover: m g = {weight:.2f} N needs {thrusts.min():.3f} N per "
            f"rotor, below f_min + control_margin = {lo:.3f} N: the rotors cannot throttle "
            "down to its weight (lower vehicle.f_min or vehicle.control_margin)"
        )
    return Check(Infeasibility.CANNOT_HOVER, margin, message)


def landed_hover(
    surface: Surface, c: float, limits: VehicleLimits, g: float = GRAVITY
) -> LandedHover:
    """Check the landed inclined hover at p~_L on ``surface`` for any slope in [0, pi].

    With the cable in the fall-line plane (d = d~, c = sin(gamma)), the landed hover
    needs f_R = m g cos(beta - gamma)/cos(gamma) and f_L = m g sin(beta)/cos(gamma); with
    the motors off f_N = f_R (the same number, (6.14)) and the shear force is zero, so
    both exist exactly while beta < 90 deg + gamma (docs/theory.md section 13).
    """
    beta = surface.slope
    gamma = math.asin(c)
    f_R, f_L = landing_hover(beta, c, limits.mass, g)
    d = inclined_hover_direction(surface.R_WS, c)
    rest_tension = tethered_rest_tension(surface, d, limits.mass, g)
    rest = contact_forces(surface, limits.mass, 0.0, surface.z_S, rest_tension, d, g)
    rotors = limits.landed_hover_rotor_thrusts(c, f_R, f_L)
    lo, hi = limits.f_min + limits.margin, limits.f_max - limits.margin
    even = f_R / limits.n_rotors
    shear = float(np.linalg.norm(rest.f_S))
    b, lim = math.degrees(beta), math.degrees(math.pi / 2 + gamma)
    checks = (
        free_hover(limits, g),
        Check(
            Infeasibility.NO_INCLINED_HOVER,
            f_R,
            f"beta = {b:.1f} deg >= 90 deg + gamma = {lim:.1f} deg: no inclined hover exists "
            f"at the landing point (it would need f_R = {f_R:.2f} N <= 0)",
        ),
        Check(
            Infeasibility.ROTOR_FLOOR,
            even - lo,
            f"inclined hovering at the landing point needs f_R = {f_R:.2f} N, {even:.3f} N per "
            f"rotor, below f_min + control_margin = {lo:.3f} N: slope too steep for this vehicle",
        ),
        Check(
            Infeasibility.ROTOR_CEILING,
            hi - even,
            f"inclined hovering at the landing point needs f_R = {f_R:.2f} N, {even:.3f} N per "
            f"rotor, above f_max - control_margin = {hi:.3f} N: rotor f_max too low",
        ),
        Check(
            Infeasibility.OFFSET_TORQUE,
            # without a torque (r_att parallel to d~, or at the CoM) the split is even and
            # the floor and ceiling checks already say everything: nothing to add
            min(float(rotors.min()) - lo, hi - float(rotors.max()))
            if float(np.ptp(rotors)) > 1e-12
            else math.inf,
            f"cancelling the cable-offset torque at the landing point needs rotor thrusts "
            f"{rotors.min():.3f}..{rotors.max():.3f} N (f_R = {f_R:.2f} N) outside "
            f"[f_min + control_margin, f_max - control_margin] = [{lo:.3f}, {hi:.3f}] N: "
            "slope too steep for this cable attachment",
        ),
        Check(
            Infeasibility.NORMAL_FORCE,
            rest.f_N - surface.f_N_min,
            f"with the motors off the surface would have to pull: f_N = {rest.f_N:.3f} N < "
            f"f_N_min = {surface.f_N_min:g} N",
        ),
        Check(
            Infeasibility.FRICTION_MOTORS_OFF,
            surface.friction * max(rest.f_N - surface.f_N_min, 0.0) - shear,
            f"with the motors off the robot slides: shear {shear:.3f} N > "
            f"f_S_max = {rest.f_S_max:.3f} N",
        ),
    )
    return LandedHover(
        slope=beta,
        c=c,
        gamma=gamma,
        thrust=f_R,
        tension=f_L,
        rotor_thrusts=rotors,
        rest_tension=rest_tension,
        rest_normal_force=rest.f_N,
        rest_friction_margin=rest.friction_margin,
        checks=checks,
    )


@dataclass(frozen=True)
class TetheredAnalysis:
    """Tethered landing at the inclined-hovering point p~_L (6.8)-(6.16).

    Attributes
    ----------
    c, gamma : float
        c = (h_att - h_A)/l (6.9) and gamma = asin(c) [rad].
    d_tilde, landing_point, anchor_point : (3,) arrays
        d~ (6.12), p~_L and p_A in F_W [-, m, m].
    phi_star, theta_A_star : float
        Final output: link elevation gamma - beta and robot tilt beta at landing [rad].
    hover_thrust, hover_tension : float
        Inclined hovering at p~_L: f_R and f_L [N].
    hover_rotor_thrusts : (n,) array
        Rotor thrusts of that hover, cancelling the cable-offset torque [N].
    max_touchdown_thrust : float
        fbar_R of (6.15), corrected [N].
    rest_tension, rest_normal_force : float
        f_L (6.14) and f_N with the motors off [N].
    condition4_possible : bool
        Inclined hovering exists at p~_L (f_R > 0, f_L >= 0).
    condition5_holds : bool
        Condition (5) with the motors off, by force balance.
    thrust_within_limits : bool
        The hover rotor thrusts lie in [f_min + margin, f_max - margin].
    feasible : bool
        The vehicle can hover in free flight (:func:`free_hover`) and all of the above.
    max_slope_rad : float or None
        Steepest slope in [0, pi] for which the tethered landing is feasible (None: none is).
    max_slope_binding : Infeasibility or None
        What binds just beyond ``max_slope_rad`` (None: feasible up to pi, or nowhere).
    checks : tuple of Check
        Every requirement with its signed margin, in binding order.
    """

    c: float
    gamma: float
    d_tilde: FloatArray
    landing_point: FloatArray
    anchor_point: FloatArray
    phi_star: float
    theta_A_star: float
    hover_thrust: float
    hover_tension: float
    hover_rotor_thrusts: FloatArray
    max_touchdown_thrust: float
    rest_tension: float
    rest_normal_force: float
    condition4_possible: bool
    condition5_holds: bool
    thrust_within_limits: bool
    feasible: bool
    max_slope_rad: float | None
    max_slope_binding: Infeasibility | None
    checks: tuple[Check, ...]

    @property
    def findings(self) -> tuple[Check, ...]:
        """The failed checks, the binding one first (empty when feasible)."""
        return tuple(c for c in self.checks if not c.ok)

    @property
    def binding(self) -> Infeasibility | None:
        """The requirement that binds here (None when feasible)."""
        failed = self.findings
        return failed[0].reason if failed else None

    @property
    def reasons(self) -> tuple[str, ...]:
        """One line per failed check, the binding one first (empty when feasible)."""
        return tuple(c.message for c in self.findings)


@dataclass(frozen=True)
class ContactFreeAnalysis:
    """Contact-free (perching) landing (6.6)-(6.7), corrected.

    Attributes
    ----------
    condition4_possible : bool
        Only on a horizontal surface (section 6.4.1).
    condition5_holds_motors_off : bool
        The robot stays put with f_R = 0: tan(beta) <= mu for a plain surface.
    max_touchdown_thrust : float or None
        Largest f_R(t_L+) keeping condition (5) [N]; None if no thrust works (mu = 0 on
        a slope). Negative: even with the motors off it slides or lifts.
    min_touchdown_thrust : float
        Least controllable thrust at touchdown, n (f_min + margin) [N].
    feasible : bool
        The vehicle can hover in free flight (:func:`free_hover`) and the least
        controllable touchdown thrust keeps condition (5).
    max_slope_rad : float or None
        Steepest feasible slope for this vehicle and friction.
    findings : tuple of Check
        What fails (condition (4) on a slope is listed but does not decide ``feasible``:
        the perching comparison lands without it); the binding one first.
    """

    condition4_possible: bool
    condition5_holds_motors_off: bool
    max_touchdown_thrust: float | None
    min_touchdown_thrust: float
    feasible: bool
    max_slope_rad: float | None
    findings: tuple[Check, ...]

    @property
    def binding(self) -> Infeasibility | None:
        """What makes the contact-free landing infeasible (None when feasible)."""
        fatal = [c for c in self.findings if c.reason is not Infeasibility.NO_CONDITION_4]
        return fatal[0].reason if fatal and not self.feasible else None

    @property
    def reasons(self) -> tuple[str, ...]:
        return tuple(c.message for c in self.findings)


def _surface_at(template: Surface, slope: float, azimuth: float = 0.0) -> Surface:
    return Surface(
        origin=template.origin,
        R_WS=surface_frame_from_slope(slope, azimuth),
        kind=template.kind,
        pipe_radius=template.pipe_radius,
        friction=template.friction,
        f_N_min=template.f_N_min,
    )


def landed_hover_at(
    template: Surface, slope: float, c: float, limits: VehicleLimits, g: float = GRAVITY
) -> LandedHover:
    """:func:`landed_hover` on a copy of ``template`` tilted to ``slope`` in [0, pi] [rad]."""
    return landed_hover(_surface_at(template, slope), c, limits, g)


def _free_flight_margin(surface: Surface, limits: VehicleLimits, g: float) -> float:
    bound = free_flight_max_touchdown_thrust(surface, limits.mass, g)
    touchdown = -math.inf if bound is None else bound - limits.min_controllable_thrust
    return min(touchdown, free_hover(limits, g).margin)


_ROTOR_REASONS = (
    Infeasibility.CANNOT_HOVER,
    Infeasibility.NO_INCLINED_HOVER,
    Infeasibility.ROTOR_FLOOR,
    Infeasibility.ROTOR_CEILING,
    Infeasibility.OFFSET_TORQUE,
)


def anchor_height_range(
    slope: float, h_att: float, link_length: float, limits: VehicleLimits, g: float = GRAVITY
) -> tuple[float, float] | None:
    """Anchor heights h_A whose landed inclined hover keeps every rotor in [f_min +
    control_margin, f_max - control_margin], the cable-offset torque included [m].

    With t = tan(gamma) and c = sin(gamma) = (h_att - h_A)/l (6.9), the landed hover of
    :func:`landed_hover` needs f_R = m g cos(beta - gamma)/cos(gamma) = m g (cos(beta) +
    t sin(beta)) and f_L d~ = m g sin(beta)/cos(gamma) [cos(gamma), 0, sin(gamma)] =
    m g sin(beta) [1, 0, t] (z_B = z_S, heading psi turning x_B from x_S), so the rotor
    thrusts Gamma^-1 [f_R, r_att x f_L d~_B] are affine in t: u_i = a_i + b_i t. Each
    rotor bound keeps t on one side of a value; their intersection is an interval [t_lo,
    t_hi], and h_A = h_att - l t / sqrt(1 + t^2) falls as t rises. The anchor's height
    above the surface (a bar's standoff) therefore bounds the slope through the offset
    torque: a higher anchor tilts the cable away from the surface (gamma < 0), which
    lowers f_R, while the torque a m g sin(beta) of an attachment a below the centre of
    mass does not depend on gamma. With f_N_min no larger than n (f_min + margin) these
    are all of :func:`landed_hover`'s landed checks (the motors-off rest has f_N = f_R
    and no shear), the free hover aside.

    Parameters
    ----------
    slope : float
        beta in (0, pi) [rad].
    h_att : float
        Height of the cable attachment above the surface when landed
        (:func:`tetherland.geometry.attachment_height`) [m].
    link_length : float
        The landed link: the cable length l, or l + s for an elastic cable [m].
    limits : VehicleLimits
    g : float
        [m/s^2].

    Returns
    -------
    (h_lo, h_hi) or None
        The closed interval of anchor heights [m] (None: no anchor height lands; a bound is
        h_att -+ l where the rotors bound t on one side only).
    """
    sb, cb = math.sin(slope), math.cos(slope)
    if not sb > 0.0:
        raise ValueError(f"slope = {slope!r} rad must be in (0, pi)")
    ch, sh = math.cos(limits.heading), math.sin(limits.heading)
    w = limits.mass * g

    def rotors(t: float) -> FloatArray:
        if limits.allocation_inverse is None:
            return np.full(limits.n_rotors, w * (cb + t * sb) / limits.n_rotors)
        tau = np.cross(limits.r_att_B, w * sb * np.array([ch, -sh, t]))
        return limits.allocation_inverse @ np.array([w * (cb + t * sb), *tau])

    a = rotors(0.0)
    b = rotors(1.0) - a
    lo_u, hi_u = limits.f_min + limits.margin, limits.f_max - limits.margin
    t_lo, t_hi = -math.inf, math.inf
    for ai, bi in zip(a, b, strict=True):
        for bound, below in ((lo_u, False), (hi_u, True)):
            # a_i + b_i t >= lo_u (below False) or <= hi_u (below True)
            if abs(bi) < 1e-15:
                if (ai > bound) if below else (ai < bound):
                    return None
                continue
            t_star = (bound - ai) / bi
            if (bi > 0.0) != below:
                t_lo = max(t_lo, t_star)
            else:
                t_hi = min(t_hi, t_star)
    if t_lo > t_hi:
        return None

    def height(t: float) -> float:
        c = math.copysign(1.0, t) if math.isinf(t) else t / math.sqrt(1.0 + t * t)
        return h_att - link_length * c

    return float(height(t_hi)), float(height(t_lo))


def landed_hover_rotor_reason(
    scenario: Scenario, g: float = GRAVITY, rotor_bounds: bool = True
) -> str | None:
    """Why the rotors cannot hold the landed inclined hover (cable torque included), or None.

    The rotor checks of :func:`landed_hover` (hover in free flight, no inclined hover,
    rotor floor and ceiling, offset torque), without the slope search: used by the
    planner so that planning and analysis agree on what is feasible. ``rotor_bounds``
    false leaves out the floor and the ceiling (a planner that bounds the rotor commands
    under the believed ground effect checks them itself).
    """
    geometry = LandingGeometry.from_scenario(scenario)
    hover = landed_hover(geometry.surface, geometry.c, VehicleLimits.from_scenario(scenario), g)
    reasons = _ROTOR_REASONS if rotor_bounds else _ROTOR_REASONS[:2] + _ROTOR_REASONS[4:]
    for check in hover.findings:
        if check.reason in reasons:
            return check.message
    return None


@dataclass(frozen=True)
class SlopeLimit:
    """Steepest feasible slope and what binds beyond it.

    Attributes
    ----------
    max_slope_rad : float or None
        Steepest slope in [0, pi] with a non-negative margin [rad]; None if none has.
    binding : Infeasibility or None
        The binding reason just beyond ``max_slope_rad`` (None when it is pi or None).
    """

    max_slope_rad: float | None
    binding: Infeasibility | None


def max_feasible_slope(
    margin: Callable[[float], float], samples: int = 181, upper: float = math.pi
) -> float | None:
    """Steepest slope in [0, ``upper``] with ``margin(slope) >= 0`` [rad], or None.

    The margin is sampled on a grid (every degree by default) and the last sign change
    refined with Brent's method.
    """
    grid = np.linspace(0.0, upper, samples)
    values = np.array([margin(float(b)) for b in grid])
    ok = np.flatnonzero(values >= -_TOL)
    if ok.size == 0:
        return None
    k = int(ok[-1])
    if k == samples - 1:
        return upper
    lo, hi = float(grid[k]), float(grid[k + 1])
    if not np.isfinite(values[k + 1]):
        return lo
    # margin + tol changes sign on [lo, hi] (a margin of exactly zero, such as the shear
    # of a frictionless tethered rest, counts as met up to rounding)
    from scipy.optimize import brentq  # 0.5 s to import: only where it is needed

    return float(brentq(lambda b: margin(b) + _TOL, lo, hi, xtol=1e-10))


def tethered_slope_limit(
    template: Surface,
    c: float | Callable[[float], float],
    limits: VehicleLimits,
    g: float = GRAVITY,
) -> SlopeLimit:
    """Steepest slope in [0, pi] at which the landed hover of :func:`landed_hover` is
    feasible for this cable geometry and vehicle, and what binds beyond it.

    ``c`` is (h_att - h_A)/l, or a function of the slope [rad] for an elastic cable, whose
    landed link l + s stretches with the slope's f_L (:meth:`LandingGeometry.cosine_at`).
    """
    c_at = c if callable(c) else (lambda _b: c)
    beta = max_feasible_slope(lambda b: landed_hover_at(template, b, c_at(b), limits, g).margin)
    if beta is None or beta >= math.pi - 1e-12:
        return SlopeLimit(beta, None)
    b = min(beta + 1e-6, math.pi)
    beyond = landed_hover_at(template, b, c_at(b), limits, g)
    return SlopeLimit(beta, beyond.binding)


def analyze_tethered(
    geometry: LandingGeometry, limits: VehicleLimits, g: float = GRAVITY
) -> TetheredAnalysis:
    """Feasibility of the tethered landing at p~_L for this geometry and vehicle."""
    surface = geometry.surface
    hover = landed_hover(surface, geometry.c, limits, g)
    by_reason = {c.reason: c for c in hover.checks}
    thrust_ok = all(by_reason[r].ok for r in _ROTOR_REASONS[2:])
    cond4 = by_reason[Infeasibility.NO_INCLINED_HOVER].ok and hover.tension >= -_TOL
    cond5 = (
        by_reason[Infeasibility.NORMAL_FORCE].ok and by_reason[Infeasibility.FRICTION_MOTORS_OFF].ok
    )
    limit = tethered_slope_limit(
        surface, lambda b: geometry.cosine_at(b, limits.mass, g), limits, g
    )
    return TetheredAnalysis(
        c=geometry.c,
        gamma=geometry.gamma,
        d_tilde=geometry.d_tilde,
        landing_point=geometry.p_L,
        anchor_point=geometry.p_A,
        phi_star=geometry.phi_star,
        theta_A_star=geometry.theta_A_star,
        hover_thrust=hover.thrust,
        hover_tension=hover.tension,
        hover_rotor_thrusts=hover.rotor_thrusts,
        max_touchdown_thrust=tethered_max_touchdown_thrust(
            surface, geometry.d_tilde, limits.mass, g
        ),
        rest_tension=hover.rest_tension,
        rest_normal_force=hover.rest_normal_force,
        condition4_possible=cond4,
        condition5_holds=cond5,
        thrust_within_limits=thrust_ok,
        feasible=hover.feasible,
        max_slope_rad=limit.max_slope_rad,
        max_slope_binding=limit.binding,
        checks=hover.checks,
    )


def analyze_free_flight(
    surface: Surface, limits: VehicleLimits, g: float = GRAVITY
) -> ContactFreeAnalysis:
    """Feasibility of a contact-free (perching) landing on this surface (any slope in [0, pi])."""
    bound = free_flight_max_touchdown_thrust(surface, limits.mass, g)
    motors_off = contact_forces(surface, limits.mass, 0.0, surface.z_S, g=g)
    hover = free_hover(limits, g)
    findings = [] if hover.ok else [hover]
    horizontal = surface.is_horizontal or surface.slope < 1e-9
    if not horizontal:
        findings.append(
            Check(
                Infeasibility.NO_CONDITION_4,
                -math.inf,
                "condition (4) cannot hold on a sloped surface without a tether",
            )
        )
    m_g = limits.mass * g
    if motors_off.f_N < surface.f_N_min - _TOL:
        findings.append(
            Check(
                Infeasibility.NORMAL_FORCE,
                motors_off.f_N - surface.f_N_min,
                f"the surface faces down: with the motors off f_N = m g z_S.z_W = "
                f"{motors_off.f_N:.3f} N < f_N_min = {surface.f_N_min:g} N",
            )
        )
    if bound is None:
        findings.append(
            Check(
                Infeasibility.FRICTION_MOTORS_OFF,
                -m_g * abs(float(surface.x_S[2])),
                "frictionless sloped surface: nothing holds the robot after touchdown",
            )
        )
        feasible = False
    else:
        feasible = bound >= limits.min_controllable_thrust - _TOL and hover.ok
        if not motors_off.holds and motors_off.f_N >= surface.f_N_min - _TOL:
            findings.append(
                Check(
                    Infeasibility.FRICTION_MOTORS_OFF,
                    motors_off.friction_margin,
                    "it slides even with the motors off: m g |x_S.z_W| = "
                    f"{np.linalg.norm(motors_off.f_S):.3f} N > "
                    f"f_S_max = {motors_off.f_S_max:.3f} N",
                )
            )
        if bound < limits.min_controllable_thrust - _TOL:
            findings.append(
                Check(
                    Infeasibility.TOUCHDOWN_THRUST,
                    bound - limits.min_controllable_thrust,
                    f"condition (5) needs f_R(t_L+) <= {bound:.3f} N but the least controllable"
                    f" thrust is {limits.min_controllable_thrust:.3f} N",
                )
            )
    return ContactFreeAnalysis(
        condition4_possible=horizontal,
        condition5_holds_motors_off=motors_off.holds,
        max_touchdown_thrust=bound,
        min_touchdown_thrust=limits.min_controllable_thrust,
        feasible=feasible,
        max_slope_rad=max_feasible_slope(
            lambda b: _free_flight_margin(_surface_at(surface, b), limits, g)
        ),
        findings=tuple(findings),
    )
