"""The landing analysis of a scenario and its Table 6.1, generated from its numbers."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from tetherland import GRAVITY
from tetherland.analysis.feasibility import (
    Check,
    ContactFreeAnalysis,
    Infeasibility,
    TetheredAnalysis,
    VehicleLimits,
    analyze_free_flight,
    analyze_tethered,
    free_hover,
)
from tetherland.config import Scenario
from tetherland.geometry import LandingGeometry


@dataclass(frozen=True)
class TableRow:
    """One row of Table 6.1: a property and its value for each method."""

    label: str
    free_flight: str
    tethered: str


@dataclass(frozen=True)
class LandingAnalysis:
    """Both landing methods analysed for one scenario (chapter section 6.4), after the
    hover in free flight that both need (:func:`~tetherland.analysis.free_hover`)."""

    scenario: Scenario
    geometry: LandingGeometry
    limits: VehicleLimits
    tethered: TetheredAnalysis
    free_flight: ContactFreeAnalysis
    hover: Check
    """Hover in free flight with the control margin (reason ``cannot_hover``)."""

    def table(self) -> list[TableRow]:
        """Table 6.1 for this scenario's numbers (corrected formulas, docs/theory.md section 5)."""
        s, t, f = self.geometry.surface, self.tethered, self.free_flight
        beta = math.degrees(s.slope)
        m_g = self.limits.mass * GRAVITY
        yes = {True: "yes", False: "no"}
        ff_bound = (
            "none (frictionless slope)"
            if f.max_touchdown_thrust is None
            else f"{f.max_touchdown_thrust:.2f} N"
        )

        def slope(value: float | None, binding: Infeasibility | None = None) -> str:
            text = "none" if value is None else f"{math.degrees(value):.1f} deg"
            return text if binding is None else f"{text} (then {binding.value})"

        twr = (
            f"{yes[self.hover.ok]} (thrust-to-weight {self.limits.thrust_to_weight():.2f}, "
            f"needs >= {self.limits.hover_thrust_to_weight:.2f})"
        )
        return [
            TableRow("Hovers in free flight", twr, twr),
            TableRow("Surface slope", f"{beta:.1f} deg", f"{beta:.1f} deg"),
            TableRow(
                "Condition (4) attainable",
                yes[f.condition4_possible] + " (only on horizontal ground)",
                yes[t.condition4_possible] + " (inclined hovering at p~_L)",
            ),
            TableRow(
                "Surface orientations",
                f"|x_S.z_W| m g <= f_S_max: {abs(s.x_S[2]) * m_g:.2f} N vs "
                f"{s.friction * max(m_g * s.z_S[2] - s.f_N_min, 0.0):.2f} N (motors off)",
                "any (y_S.d~ = 0, so (6.16) always holds)",
            ),
            TableRow("Anchor position", "-", "any: p_A = p*_L + h_att z_S - l d~ (6.13)"),
            TableRow(
                "Landing position",
                "any",
                "p~_L = [" + ", ".join(f"{x:.3f}" for x in t.landing_point) + "] m",
            ),
            TableRow("Max f_R at t_L+", ff_bound, f"{t.max_touchdown_thrust:.2f} N (6.15)"),
            TableRow(
                "Thrust at touchdown",
                f">= {f.min_touchdown_thrust:.2f} N (n (f_min + margin))",
                f"{t.hover_thrust:.2f} N (inclined hovering), tension {t.hover_tension:.2f} N",
            ),
            TableRow(
                "Condition (5), motors off",
                yes[f.condition5_holds_motors_off],
                yes[t.condition5_holds] + f" (f_N = {t.rest_normal_force:.2f} N)",
            ),
            TableRow(
                "Steepest feasible slope",
                slope(f.max_slope_rad),
                slope(t.max_slope_rad, t.max_slope_binding),
            ),
            TableRow("Feasible here", yes[f.feasible], yes[t.feasible]),
        ]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready document (SI units, radians, vectors in F_W)."""
        s, t, f = self.geometry.surface, self.tethered, self.free_flight
        return {
            "hover": {
                "ok": self.hover.ok,
                "margin_N": self.hover.margin,
                "thrust_to_weight": self.limits.thrust_to_weight(),
                "thrust_to_weight_needed": self.limits.hover_thrust_to_weight,
                "message": self.hover.message,
            },
            "surface": {
                "kind": s.kind,
                "slope_rad": s.slope,
                "slope_deg": math.degrees(s.slope),
                "x_S": s.x_S,
                "y_S": s.y_S,
                "z_S": s.z_S,
                "origin": s.origin,
                "friction": s.friction,
                "f_N_min": s.f_N_min,
            },
            "tethered": {
                "c": t.c,
                "gamma": t.gamma,
                "d_tilde": t.d_tilde,
                "landing_point": t.landing_point,
                "anchor_point": t.anchor_point,
                "h_R": self.geometry.h_R,
                "h_att": self.geometry.h_att,
                "h_A": self.geometry.h_A,
                "phi_star": t.phi_star,
                "theta_A_star": t.theta_A_star,
                "hover_thrust": t.hover_thrust,
                "hover_rotor_thrust": t.hover_thrust / self.limits.n_rotors,
                "hover_rotor_thrusts": t.hover_rotor_thrusts,
                "hover_tension": t.hover_tension,
                "max_touchdown_thrust": t.max_touchdown_thrust,
                "rest_tension": t.rest_tension,
                "rest_normal_force": t.rest_normal_force,
                "condition4_possible": t.condition4_possible,
                "condition5_holds": t.condition5_holds,
                "thrust_within_limits": t.thrust_within_limits,
                "feasible": t.feasible,
                "max_slope_rad": t.max_slope_rad,
                "max_slope_binding": t.max_slope_binding,
                "binding": t.binding,
                "reasons": list(t.reasons),
                "checks": [
                    {"reason": c.reason, "margin_N": c.margin, "ok": c.ok, "message": c.message}
                    for c in t.checks
                ],
            },
            "free_flight": {
                "condition4_possible": f.condition4_possible,
                "condition5_holds_motors_off": f.condition5_holds_motors_off,
                "max_touchdown_thrust": f.max_touchdown_thrust,
                "min_touchdown_thrust": f.min_touchdown_thrust,
                "max_slope_rad": f.max_slope_rad,
                "feasible": f.feasible,
                "binding": f.binding,
                "reasons": list(f.reasons),
            },
            "vehicle": {
                "mass": self.limits.mass,
                "f_min": self.limits.f_min,
                "f_max": self.limits.f_max,
                "control_margin": self.limits.margin,
            },
            "table_6_1": [
                {"property": r.label, "free_flight": r.free_flight, "tethered": r.tethered}
                for r in self.table()
            ],
        }


def analyze(scenario: Scenario) -> LandingAnalysis:
    """Analyse both landing methods for a scenario."""
    geometry = LandingGeometry.from_scenario(scenario)
    limits = VehicleLimits.from_scenario(scenario)
    return LandingAnalysis(
        scenario=scenario,
        geometry=geometry,
        limits=limits,
        tethered=analyze_tethered(geometry, limits),
        free_flight=analyze_free_flight(geometry.surface, limits),
        hover=free_hover(limits),
    )
