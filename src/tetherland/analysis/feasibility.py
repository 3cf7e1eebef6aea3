"""Contact-free versus tethered landing: feasibility and slope limits (chapter 6.4).

For the scenario's vehicle and surface this module answers, for each method, which
landing conditions can be met, the largest thrust allowed at touchdown, and the steepest
slope the vehicle can take, counting rotor limits f_min <= f_i <= f_max with the
``control_margin`` kept per rotor for attitude control.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from tetherland import GRAVITY
from tetherland.analysis.statics import (
    contact_forces,
    free_flight_max_touchdown_thrust,
    landing_hover,
    tethered_max_touchdown_thrust,
    tethered_rest_tension,
)
from tetherland.config import Scenario
from tetherland.geometry import (
    FloatArray,
    LandingGeometry,
    Surface,
    inclined_hover_direction,
    normal_from_slope,
    surface_frame,
)
from tetherland.models.quadrotor import RotorLayout

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


@dataclass(frozen=True)
class TetheredAnalysis:
    """Tethered landing at the inclined-hovering point p~_L (6.8)-(6.16).

    Attributes
    ----------
    c, gamma : float
        c = (h_R - h_A)/l (6.9) and gamma = asin(c) [rad].
    d_tilde, landing_point, anchor_point : (3,) arrays
        d~ (6.12), p~_L and p_A in F_W [-, m, m].
    phi_star, theta_A_star : float
        Final output: link elevation and robot tilt at landing [rad].
    hover_thrust, hover_tension : float
        Inclined hovering at p~_L: f_R and f_L [N].
    hover_rotor_thrusts : (n,) array
        Rotor thrusts of that hover, cancelling the cable-offset torque [N].
    max_touchdown_thrust : float
        fbar_R of (6.15), corrected [N].
    rest_tension, rest_normal_force : float
        f_L (6.14) and f_N with the motors off [N].
    condition4_possible : bool
        Inclined hovering exists at p~_L with f_L >= 0.
    condition5_holds : bool
        Condition (5) with the motors off, by force balance.
    thrust_within_limits : bool
        The hover thrust per rotor lies in [f_min + margin, f_max - margin].
    feasible : bool
        All of the above.
    max_slope_rad : float or None
        Steepest slope for which the tethered landing is feasible (None: none is).
    reasons : tuple of str
        Why it is infeasible (empty when feasible).
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
    reasons: tuple[str, ...]


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
        The least controllable touchdown thrust keeps condition (5).
    max_slope_rad : float or None
        Steepest feasible slope for this vehicle and friction.
    reasons : tuple of str
    """

    condition4_possible: bool
    condition5_holds_motors_off: bool
    max_touchdown_thrust: float | None
    min_touchdown_thrust: float
    feasible: bool
    max_slope_rad: float | None
    reasons: tuple[str, ...]


def _surface_at(template: Surface, slope: float, azimuth: float = 0.0) -> Surface:
    return Surface(
        origin=template.origin,
        R_WS=surface_frame(normal_from_slope(slope, azimuth)),
        kind=template.kind,
        pipe_radius=template.pipe_radius,
        friction=template.friction,
        f_N_min=template.f_N_min,
    )


def _tethered_margins(
    surface: Surface, c: float, limits: VehicleLimits, g: float
) -> dict[str, float]:
    """Signed margins (>= 0 feasible) of every tethered requirement [N]."""
    beta = surface.slope
    f_R, f_L = landing_hover(beta, c, limits.mass, g)
    d = inclined_hover_direction(surface.R_WS, c)
    rest = contact_forces(
        surface,
        limits.mass,
        0.0,
        surface.z_S,
        tethered_rest_tension(surface, d, limits.mass, g),
        d,
        g,
    )
    rotors = limits.landed_hover_rotor_thrusts(c, f_R, f_L)
    return {
        "rotor_low": float(rotors.min()) - (limits.f_min + limits.margin),
        "rotor_high": (limits.f_max - limits.margin) - float(rotors.max()),
        "tension": f_L,
        "normal": rest.f_N - surface.f_N_min,
        "friction": rest.friction_margin,
    }


def _free_flight_margin(surface: Surface, limits: VehicleLimits, g: float) -> float:
    bound = free_flight_max_touchdown_thrust(surface, limits.mass, g)
    return -math.inf if bound is None else bound - limits.min_controllable_thrust


def landed_hover_rotor_reason(scenario: Scenario, g: float = GRAVITY) -> str | None:
    """Why the rotors cannot hold the landed inclined hover (cable torque included), or None.

    The same check as :func:`analyze_tethered`, without the slope search: used by the
    planner so that planning and analysis agree on what is feasible.
    """
    geometry = LandingGeometry.from_scenario(scenario)
    limits = VehicleLimits.from_scenario(scenario)
    f_R, f_L = landing_hover(geometry.surface.slope, geometry.c, limits.mass, g)
    rotors = limits.landed_hover_rotor_thrusts(geometry.c, f_R, f_L)
    if rotors.min() < limits.f_min + limits.margin - _TOL:
        return (
            f"the landed inclined hover needs a rotor thrust of {rotors.min():.3f} N (thrust "
            f"{f_R:.2f} N, cable-offset torque cancelled) < vehicle.f_min + control_margin = "
            f"{limits.f_min + limits.margin:.3f} N: slope too steep for this vehicle"
        )
    if rotors.max() > limits.f_max - limits.margin + _TOL:
        return (
            f"the landed inclined hover needs a rotor thrust of {rotors.max():.3f} N > "
            f"vehicle.f_max - control_margin = {limits.f_max - limits.margin:.3f} N: "
            "rotor f_max too low for this slope"
        )
    return None


def max_feasible_slope(margin: Callable[[float], float], samples: int = 181) -> float | None:
    """Steepest slope in [0, pi/2] with ``margin(slope) >= 0`` [rad], or None.

    The margin is sampled on a grid and the last sign change refined with Brent's method.
    """
    grid = np.linspace(0.0, math.pi / 2, samples)
    values = np.array([margin(float(b)) for b in grid])
    ok = np.flatnonzero(values >= -_TOL)
    if ok.size == 0:
        return None
    k = int(ok[-1])
    if k == samples - 1:
        return math.pi / 2
    lo, hi = float(grid[k]), float(grid[k + 1])
    if not np.isfinite(values[k + 1]):
        return lo
    return float(brentq(margin, lo, hi, xtol=1e-10))


def analyze_tethered(
    geometry: LandingGeometry, limits: VehicleLimits, g: float = GRAVITY
) -> TetheredAnalysis:
    """Feasibility of the tethered landing at p~_L for this geometry and vehicle."""
    surface = geometry.surface
    beta = surface.slope
    f_R, f_L = landing_hover(beta, geometry.c, limits.mass, g)
    d = geometry.d_tilde
    rest_tension = tethered_rest_tension(surface, d, limits.mass, g)
    rest = contact_forces(surface, limits.mass, 0.0, surface.z_S, rest_tension, d, g)
    margins = _tethered_margins(surface, geometry.c, limits, g)
    reasons = []
    rotors = limits.landed_hover_rotor_thrusts(geometry.c, f_R, f_L)
    if margins["rotor_low"] < -_TOL:
        reasons.append(
            f"inclined hovering at the landing point needs a rotor thrust of {rotors.min():.3f} N"
            f" (thrust {f_R:.2f} N, cable-offset torque cancelled), below f_min + control_margin"
            f" = {limits.f_min + limits.margin:.3f} N: slope too steep for this vehicle"
        )
    if margins["rotor_high"] < -_TOL:
        reasons.append(
            f"inclined hovering at the landing point needs a rotor thrust of {rotors.max():.3f} N,"
            f" above f_max - control_margin = {limits.f_max - limits.margin:.3f} N:"
            " rotor f_max too low"
        )
    if f_L < -_TOL:
        reasons.append("inclined hovering needs a negative cable tension")
    if not rest.holds:
        reasons.append(
            f"with the motors off the contact forces are not admissible (f_N = {rest.f_N:.3f} N,"
            f" friction margin {rest.friction_margin:.3f} N)"
        )
    thrust_ok = margins["rotor_low"] >= -_TOL and margins["rotor_high"] >= -_TOL
    cond4 = f_L >= -_TOL
    return TetheredAnalysis(
        c=geometry.c,
        gamma=geometry.gamma,
        d_tilde=d,
        landing_point=geometry.p_L,
        anchor_point=geometry.p_A,
        phi_star=geometry.phi_star,
        theta_A_star=geometry.theta_A_star,
        hover_thrust=f_R,
        hover_tension=f_L,
        hover_rotor_thrusts=rotors,
        max_touchdown_thrust=tethered_max_touchdown_thrust(surface, d, limits.mass, g),
        rest_tension=rest_tension,
        rest_normal_force=rest.f_N,
        condition4_possible=cond4,
        condition5_holds=rest.holds,
        thrust_within_limits=thrust_ok,
        feasible=thrust_ok and cond4 and rest.holds,
        max_slope_rad=max_feasible_slope(
            lambda b: min(
                _tethered_margins(_surface_at(surface, b), geometry.c, limits, g).values()
            )
        ),
        reasons=tuple(reasons),
    )


def analyze_free_flight(
    surface: Surface, limits: VehicleLimits, g: float = GRAVITY
) -> ContactFreeAnalysis:
    """Feasibility of a contact-free (perching) landing on this surface."""
    bound = free_flight_max_touchdown_thrust(surface, limits.mass, g)
    motors_off = contact_forces(surface, limits.mass, 0.0, surface.z_S, g=g).holds
    reasons = []
    horizontal = surface.is_horizontal or surface.slope < 1e-9
    if not horizontal:
        reasons.append("condition (4) cannot hold on a sloped surface without a tether")
    if bound is None:
        reasons.append("frictionless sloped surface: nothing holds the robot after touchdown")
        feasible = False
    else:
        feasible = bound >= limits.min_controllable_thrust - _TOL
        if not feasible:
            reasons.append(
                f"condition (5) needs f_R(t_L+) <= {bound:.3f} N but the least controllable"
                f" thrust is {limits.min_controllable_thrust:.3f} N"
                + (" (it slides even with the motors off)" if not motors_off else "")
            )
    return ContactFreeAnalysis(
        condition4_possible=horizontal,
        condition5_holds_motors_off=motors_off,
        max_touchdown_thrust=bound,
        min_touchdown_thrust=limits.min_controllable_thrust,
        feasible=feasible,
        max_slope_rad=max_feasible_slope(
            lambda b: _free_flight_margin(_surface_at(surface, b), limits, g)
        ),
        reasons=tuple(reasons),
    )
