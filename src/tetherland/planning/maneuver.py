"""The tethered landing and takeoff maneuvers: boundary states, limits and the OCP (6.21).

:class:`ManeuverSpec` gathers the numbers of one maneuver from a scenario (docs/theory.md
sections 3, 4, 6): the planar model, the taut start hover and the landed hover, the
rotor and tension limits, the duration and the cost gains. :func:`build_ocp` states the
optimal control problem (6.21) for it as an :class:`~tetherland.planning.ocp.OcpProblem`;
:func:`precheck` finds the infeasible cases that need no solver.

Landing starts from the taut inclined hover at phi0 = phi* + ``start_elevation_offset``
with tension ``start_tension`` (theta_A0 from :func:`hover_tilt_for_tension`) and ends at
the landed inclined hover (phi*, theta_A* = beta); takeoff goes the other way. Both ends
are at rest: zero rates, constant thrusts (f' = 0), thrusts f = G [f_R, 0].

Final conditions are hard terminal constraints: phi(t_L) = phi_f, theta_A(t_L) = theta_A,f,
phi'(t_L) = theta_A'(t_L) = 0, and the hover wrench reached with zero rate (f_R = f_R,f,
tau_y = 0, f_R' = tau_y' = 0), i.e. the whole extended state equals the final hover.
The landing conditions (1)-(4) are equalities the controller needs exactly at touchdown:
a penalty (the chapter's J5) could only approach them, with a residual that depends on
the other gains and the slope. J5 stays in the cost, as in the chapter, and is zero at
the optimum.
"""

from __future__ import annotations

import enum
import functools
import math
from dataclasses import dataclass, replace
from typing import Literal

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from tetherland.analysis.statics import hover_tilt_for_tension, inclined_hover
from tetherland.config import PlannerWeights, Scenario
from tetherland.errors import SingularityError
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.models.planar import (
    CASADI,
    NUMPY,
    ExtendedPlanarModel,
    PlanarParams,
    hover_torque,
    offset_arms,
    planar_across_torque,
    rotor_form_rhs,
    rotor_form_terms,
    wrench_form_rhs,
    wrench_form_terms,
)
from tetherland.planning.ground_effect import SIZE as GROUND_EFFECT_SIZE
from tetherland.planning.ground_effect import PlannedGroundEffect, factors_expr
from tetherland.planning.ocp import OcpProblem

StateForm = Literal["wrench", "rotor"]
MIN_REMAINDER = 0.1
"""Shortest rest of a maneuver a re-plan accepts (:meth:`ManeuverSpec.remainder`) [s]."""
_WEIGHT_NAMES = (
    "k_phi", "k_theta", "k_phi_dot", "k_theta_dot", "k_phi_ddot", "k_theta_ddot",
    "k_theta_near", "k_rates_near", "k_thrust_accel", "k_final_theta_dot", "k_final_phi_dot",
)  # fmt: skip


class Maneuver(enum.Enum):
    """Which way the tethered maneuver goes."""

    LANDING = "landing"
    TAKEOFF = "takeoff"


@dataclass(frozen=True)
class ManeuverSpec:
    """Everything the planner needs to know about one maneuver (SI units, radians).

    Attributes
    ----------
    maneuver : Maneuver
    scenario_name : str
    params : PlanarParams
        Planar model constants.
    duration : float
        t_L - t_0 [s].
    phi_start, theta_start, phi_final, theta_final : float
        Boundary outputs [rad].
    phi_surface, theta_surface : float
        phi* and theta_A* = beta of the landed state (bump centre, surface bound) [rad].
    phi_max : float
        Largest elevation with the link end above the surface, pi - gamma - beta [rad].
    f_lo, f_hi : float
        Planned rotor thrust bounds: [f_min, f_max] narrowed by ``control_margin`` [N].
    f_min, f_max : float
        The vehicle's rotor limits [N].
    min_tension : float
        f_L_min (6.21d) [N].
    tension_ramp : float
        Fraction of the duration over which the tension bound relaxes to a lower
        boundary tension [-].
    weights : PlannerWeights
    bump_width : float
        w of h(phi) [rad].
    start_state : (12,) array or None
        Rotor-form extended state the maneuver starts from when it is not the start
        hover: the rest of a maneuver re-planned from the current state (:meth:`remainder`).
    ground_effect : PlannedGroundEffect or None
        The believed ground effect whose factors k_i divide the rotor thrusts in the
        rotor bounds (``planner.model_ground_effect``): the bounds hold the commands
        f_i / k_i. None: they hold the acting thrusts f_i (the default).
    """

    maneuver: Maneuver
    scenario_name: str
    params: PlanarParams
    duration: float
    phi_start: float
    theta_start: float
    phi_final: float
    theta_final: float
    phi_surface: float
    theta_surface: float
    phi_max: float
    f_lo: float
    f_hi: float
    f_min: float
    f_max: float
    min_tension: float
    tension_ramp: float
    weights: PlannerWeights
    bump_width: float
    start_state: FloatArray | None = None
    ground_effect: PlannedGroundEffect | None = None

    @classmethod
    def from_scenario(
        cls,
        scenario: Scenario,
        maneuver: Maneuver | str = Maneuver.LANDING,
        geometry: LandingGeometry | None = None,
    ) -> ManeuverSpec:
        """The maneuver of ``scenario`` (``planner`` section, vehicle, cable and surface);
        ``geometry``: its :class:`LandingGeometry` when the caller has it."""
        maneuver = Maneuver(maneuver)
        cfg, v = scenario.planner, scenario.vehicle
        geo = geometry or LandingGeometry.from_scenario(scenario)
        params = PlanarParams.from_scenario(scenario, math.radians(cfg.heading_deg), geo)
        phi_s, theta_s = geo.phi_star, geo.theta_A_star
        phi_0 = phi_s + math.radians(cfg.start_elevation_offset_deg)
        theta_0 = hover_tilt_for_tension(phi_0, cfg.start_tension, v.mass, params.gravity)
        landing = maneuver is Maneuver.LANDING
        start = (phi_0, theta_0) if landing else (phi_s, theta_s)
        final = (phi_s, theta_s) if landing else (phi_0, theta_0)
        return cls(
            maneuver=maneuver,
            scenario_name=scenario.name,
            params=params,
            duration=cfg.landing_duration if landing else cfg.takeoff_duration,
            phi_start=start[0],
            theta_start=start[1],
            phi_final=final[0],
            theta_final=final[1],
            phi_surface=phi_s,
            theta_surface=theta_s,
            phi_max=math.pi - geo.gamma - geo.surface.slope,
            f_lo=v.f_min + v.control_margin,
            f_hi=v.f_max - v.control_margin,
            f_min=v.f_min,
            f_max=v.f_max,
            min_tension=cfg.min_tension,
            tension_ramp=cfg.tension_ramp,
            weights=cfg.weights,
            bump_width=math.radians(cfg.weights.bump_width_deg),
            ground_effect=PlannedGroundEffect.from_scenario(
                scenario, geo, params.length, params.heading
            )
            if cfg.model_ground_effect
            else None,
        )

    @property
    def model(self) -> ExtendedPlanarModel:
        return ExtendedPlanarModel(self.params)

    @property
    def x_start(self) -> FloatArray:
        """Rotor-form extended state (12,) of the start hover (or ``start_state``)."""
        if self.start_state is not None:
            return self.start_state.copy()
        return self.model.hover_state(self.phi_start, self.theta_start)

    @functools.cached_property
    def start_tension(self) -> float:
        """f_L at the start: of the start hover, or of ``start_state`` [N] (computed once)."""
        if self.start_state is None:
            return self.hover("start")[1]
        return float(self.model.tension(self.start_state))

    def remainder(self, x0: ArrayLike, elapsed: float) -> ManeuverSpec:
        """The rest of this maneuver from the state ``x0`` reached ``elapsed`` s after its
        start: same final hover, limits and gains, duration T - elapsed.

        The tension bound keeps its absolute ramp length ``tension_ramp`` T at the end,
        and ramps from the tension of ``x0`` when that is below f_L_min (as from a
        boundary hover).

        Parameters
        ----------
        x0 : (12,) array
            Rotor-form extended state [phi, theta_A, phi', theta_A', f, f'] [rad, rad/s,
            N, N/s].
        elapsed : float
            Time since the start of this maneuver [s], in [0, T - MIN_REMAINDER].
        """
        x = np.asarray(x0, dtype=float).reshape(-1)
        if x.shape != (12,) or not np.all(np.isfinite(x)):
            raise ValueError(f"x0 must be 12 finite numbers (rotor-form state), got {x.shape}")
        if not 0.0 <= elapsed <= self.duration - MIN_REMAINDER:
            raise ValueError(
                f"elapsed must be in [0, {self.duration - MIN_REMAINDER:g}] s (the maneuver "
                f"lasts {self.duration:g} s; at least {MIN_REMAINDER:g} s must remain), "
                f"got {elapsed:g}"
            )
        rest = self.duration - elapsed
        return replace(
            self, duration=rest, phi_start=float(x[0]), theta_start=float(x[1]),
            start_state=x, tension_ramp=self.tension_ramp * self.duration / rest,
        )  # fmt: skip

    @property
    def x_final(self) -> FloatArray:
        """Rotor-form extended state of the final hover (12,)."""
        return self.model.hover_state(self.phi_final, self.theta_final)

    def outputs(self, which: Literal["start", "final"]) -> tuple[float, float]:
        """(phi, theta_A) of the start or final hover [rad]."""
        if which == "start":
            return self.phi_start, self.theta_start
        return self.phi_final, self.theta_final

    def hover(self, which: Literal["start", "final"]) -> tuple[float, float]:
        """(f_R, f_L) of the start or final inclined hover [N]."""
        phi, theta = self.outputs(which)
        return inclined_hover(phi, theta, self.params.mass, self.params.gravity)

    def hover_torque(self, which: Literal["start", "final"]) -> float:
        """Rotor torque tau_y about y_A of the start or final hover: it holds the cable
        torque of the attachment offset, b f_L (docs/theory.md (4.17)) [N m]."""
        phi, theta = self.outputs(which)
        return hover_torque(phi, theta, self.hover(which)[1], self.params)

    def hover_rotor_thrusts(self, which: Literal["start", "final"]) -> FloatArray:
        """Rotor thrusts of the start or final hover with the whole offset torque: the
        planar G [f_R, tau_y] plus the torque about x_A and z_A of an offset across the
        plane (docs/theory.md (4.18)) [N]."""
        p = self.params
        phi, theta = self.outputs(which)
        f_R, f_L = self.hover(which)
        f = p.G @ np.array([f_R, self.hover_torque(which)])  # net torque 0, rotors b f_L
        if p.offset_across != 0.0:
            t_x, t_z = planar_across_torque(phi, theta, f_L, p.offset_across, NUMPY)
            c_t, s_t, c_p, s_p = (
                math.cos(theta),
                math.sin(theta),
                math.cos(p.heading),
                math.sin(p.heading),
            )
            R_AB = np.array([[c_t, 0, s_t], [0, 1, 0], [-s_t, 0, c_t]]) @ np.array(
                [[c_p, -s_p, 0], [s_p, c_p, 0], [0, 0, 1]]
            )
            tau_B = R_AB.T @ np.array([t_x, 0.0, t_z])
            f = f + np.linalg.inv(p.allocation)[:, 1:4] @ tau_B
        return f

    def rotor_commands(self, thrusts: FloatArray, phi: ArrayLike, theta_A: ArrayLike) -> FloatArray:
        """What the rotor bounds hold of acting rotor ``thrusts`` (n, 4) [N] at the planar
        states (phi, theta_A) (n,) [rad]: the commands f_i / k_i with
        :attr:`ground_effect`, else ``thrusts`` themselves (the same array) [N]."""
        if self.ground_effect is None:
            return thrusts
        return self.ground_effect.commands(thrusts, phi, theta_A)

    def tension_floor(self, t: FloatArray | float) -> FloatArray:
        """Lower bound on f_L at time ``t`` [N]: f_L_min, ramped near a boundary whose
        hover tension is lower (linearly over ``tension_ramp`` of the duration)."""
        t = np.asarray(t, dtype=float)
        a0 = max(0.0, self.min_tension - self.start_tension)
        aT = max(0.0, self.min_tension - self.hover("final")[1])
        ramp = self.tension_ramp * self.duration
        return (
            self.min_tension
            - a0 * np.maximum(0.0, 1.0 - t / ramp)
            - aT * np.maximum(0.0, 1.0 - (self.duration - t) / ramp)
        )


def precheck(spec: ManeuverSpec) -> list[str]:
    """Reasons why the maneuver is infeasible before any solve (empty list: none found).

    Checks the boundary hovers exist with a non-negative tension and rotor thrusts in
    [f_min + margin, f_max - margin] (the commands f_i / k_i with
    :attr:`ManeuverSpec.ground_effect`), that the start elevation is below the vertical,
    and that the tension bound is not beyond what the rotors and the swing can hold.
    """
    reasons: list[str] = []
    p, margin = spec.params, spec.f_max - spec.f_hi
    if spec.maneuver is Maneuver.LANDING:
        names = {"start": "taut start hover", "final": "landed inclined hover"}
    else:
        names = {"start": "landed inclined hover", "final": "taut end hover"}
    taut_phi = spec.phi_start if spec.maneuver is Maneuver.LANDING else spec.phi_final
    if taut_phi >= math.pi / 2 - 1e-6:
        reasons.append(
            f"the taut hover elevation phi* + planner.start_elevation_offset_deg = "
            f"{math.degrees(taut_phi):.1f} deg is not below the vertical (90 deg)"
        )
        return reasons
    for which in ("start", "final"):
        try:
            f_R, f_L = spec.hover(which)
        except SingularityError as err:
            reasons.append(f"{names[which]}: {err}")
            continue
        phi, theta = spec.outputs(which)
        per_rotor = spec.rotor_commands(spec.hover_rotor_thrusts(which)[None, :], phi, theta)[0]
        command = "rotor command (believed ground effect) " if spec.ground_effect else ""
        torque = spec.hover_torque(which)
        why = (
            f" (with the cable-offset torque {torque:+.3f} N m the rotors hold: too steep for "
            "this attachment)"
            if abs(torque) > 1e-12 or p.offset_across != 0.0
            else ""
        )
        if f_R <= 0 or f_L < -1e-9:
            reasons.append(f"{names[which]} does not exist (f_R = {f_R:.3g} N, f_L = {f_L:.3g} N)")
        elif per_rotor.max() > spec.f_hi + 1e-9:
            reasons.append(
                f"rotor f_max too low for this slope: the {names[which]} needs f_R = {f_R:.2f} N, "
                f"{per_rotor.max():.2f} N {command}per rotor > vehicle.f_max - control_margin = "
                f"{spec.f_max:g} - {margin:g} N{why}"
            )
        elif per_rotor.min() < spec.f_lo - 1e-9:
            reasons.append(
                f"rotor f_min too high for this slope: the {names[which]} needs f_R = {f_R:.2f} N, "
                f"{per_rotor.min():.2f} N {command}per rotor < vehicle.f_min + control_margin = "
                f"{spec.f_min:g} + {margin:g} N{why}"
            )
    # Tension bound: f_L <= f_R + m g + m l phi'^2 with f_R <= 4 f_hi. On the middle part of
    # the maneuver, where the bound is f_L_min, phi' cannot change sign (at phi' = 0 the
    # static part alone must hold f_L_min) and phi stays in [phi*, phi_max], so some
    # |phi'| <= (phi_max - phi*)/t_mid.
    t_mid = spec.duration * (1.0 - 2.0 * spec.tension_ramp)
    static_cap = 4.0 * spec.f_hi + p.mass * p.gravity
    if t_mid > 0:
        swing = (spec.phi_max - spec.phi_surface) / t_mid
        cap = static_cap + p.mass * p.length * swing**2
        if spec.min_tension > cap:
            reasons.append(
                f"planner.min_tension = {spec.min_tension:g} N cannot be held: the rotors and the "
                f"swing of the cable give at most {cap:.2f} N"
            )
    return reasons


_PARAM_NAMES = (
    "mass", "length", "inertia", "gravity", "torque_row", "G", "phi_f", "theta_f", "phi_s",
    "theta_s", "width", "f_R_f", "f_L_min", "a0", "aT", "ramp", *_WEIGHT_NAMES,
    "offset",
)  # fmt: skip
_PARAM_SIZES = {"torque_row": 4, "G": 8, "offset": 2}
_PARAM_OFFSETS = {
    name: int(sum(_PARAM_SIZES.get(n, 1) for n in _PARAM_NAMES[:i]))
    for i, name in enumerate(_PARAM_NAMES)
}


def _param_values(spec: ManeuverSpec) -> dict[str, float | FloatArray]:
    """The OCP's parameters (symbols in the statement, so one solver serves all scenarios)."""
    p = spec.params
    f_R_final, f_L_final = spec.hover("final")
    values: dict[str, float | FloatArray] = {
        "mass": p.mass, "length": p.length, "inertia": p.inertia, "gravity": p.gravity,
        "torque_row": p.torque_row, "G": p.G.reshape(-1),
        "phi_f": spec.phi_final, "theta_f": spec.theta_final,
        "phi_s": spec.phi_surface, "theta_s": spec.theta_surface, "width": spec.bump_width,
        "f_R_f": f_R_final, "f_L_min": spec.min_tension,
        "a0": max(0.0, spec.min_tension - spec.start_tension),
        "aT": max(0.0, spec.min_tension - f_L_final),
        "ramp": spec.tension_ramp,
        "offset": np.asarray(p.offset, dtype=float),
    }  # fmt: skip
    values.update({name: getattr(spec.weights, name) for name in _WEIGHT_NAMES})
    return values


def _numbers(spec: ManeuverSpec, form: StateForm) -> dict[str, object]:
    """The numerical data of the OCP of ``spec`` (everything but the statement)."""
    nx = 8 if form == "wrench" else 12
    x_lb, x_ub = np.full(nx, -np.inf), np.full(nx, np.inf)
    x_lb[0], x_ub[0] = spec.phi_surface, spec.phi_max
    path_lb, path_ub = [0.0] + [spec.f_lo] * 8, [np.inf] + [spec.f_hi] * 8
    x0 = spec.model.to_wrench_form(spec.x_start) if form == "wrench" else spec.x_start
    values = _param_values(spec)
    p_value = [np.atleast_1d(np.asarray(values[n], dtype=float)) for n in _PARAM_NAMES]
    if spec.ground_effect is not None:  # appended: the offsets of the others stay
        p_value.append(spec.ground_effect.values)
    return {
        "duration": spec.duration,
        "x0": x0,
        "p_value": np.concatenate(p_value),
        "path_lb": np.array(path_lb),
        "path_ub": np.array(path_ub),
        "x_lb": x_lb,
        "x_ub": x_ub,
        "u_lb": np.full(2, -np.inf),
        "u_ub": np.full(2, np.inf),
    }


def build_ocp(
    spec: ManeuverSpec, form: StateForm = "wrench", template: OcpProblem | None = None
) -> OcpProblem:
    """The optimal control problem (6.21) of a maneuver.

    Parameters
    ----------
    spec : ManeuverSpec
    form : {"wrench", "rotor"}
        State coordinates of the extension (6.20): ``rotor`` is the chapter's
        x = [phi, theta_A, phi', theta_A', f, f'] with u = f'' restricted to the planar
        directions u = G v; ``wrench`` (default, a third smaller) uses [f_R, tau_y] and
        their rates instead of the four thrusts, f = G [f_R, tau_y]. Both state the same
        problem; the rotor bounds become linear path constraints in the wrench form.
    template : OcpProblem, optional
        A problem previously built for the same ``form`` and the same
        :func:`statement_key` of ``spec``: its symbolic statement is reused (every number
        of ``spec`` enters as data), which skips rebuilding it.

    Cost (section 6.5.2), with h(phi) = exp(-((phi - phi*)/w)^4):
      J1 = k_phi (phi - phi_f)^2 + k_theta (theta_A - theta_A,f)^2 + k_phi' phi'^2
           + k_theta' theta_A'^2 + k_phi'' phi''^2 + k_theta'' theta_A''^2
      J2 = k_theta,near h(phi) (theta_A - theta_A*)^2
      J3 = k_rates,near h(phi) (phi'^2 + theta_A'^2)
      J4 = k_u sum f_i''^2
      J5 = k_tL,theta theta_A'(t_L)^2 + k_tL,phi phi'(t_L)^2
    Constraints: (6.20) dynamics, initial hover, f_L >= f_L_min(t) (6.21d), rotor thrusts
    in [f_min + margin, f_max - margin] at the nodes and between them (6.21c),
    phi* <= phi <= pi - gamma - beta (above the surface), terminal hover.
    With ``spec.ground_effect`` the rotor bounds hold the commands (f_i + share_i) / k_i,
    k_i the believed ground-effect factor at the node (on an interval's Bernstein middle
    coefficient too, the factor of its first node: between the nodes the fine check
    :func:`~tetherland.planning.verify.verify` holds them with the factor of each time).
    """
    if form not in ("wrench", "rotor"):
        raise ValueError(f"form must be 'wrench' or 'rotor', got {form!r}")
    numbers = _numbers(spec, form)
    if template is not None:
        if template.nx != (8 if form == "wrench" else 12):
            raise ValueError(f"template is not a {form}-form problem")
        if template.p.numel() != numbers["p_value"].size:  # type: ignore[union-attr]
            raise ValueError("template is a problem with another ground-effect model")
        return template.with_numbers(**numbers)
    effect = spec.ground_effect
    return OcpProblem(**_statement(form, None if effect is None else effect.key), **numbers)


def statement_key(spec: ManeuverSpec) -> tuple[str, bytes] | None:
    """What the statement of ``spec`` depends on beyond the state form: None, or the
    believed ground effect's surface kind and disk samples (:attr:`PlannedGroundEffect.
    key`). Problems of equal keys (and form) share a statement and a compiled solver."""
    return None if spec.ground_effect is None else spec.ground_effect.key


def remainder_ocp(problem: OcpProblem, spec: ManeuverSpec) -> OcpProblem:
    """The OCP of ``spec``, the rest of the maneuver whose OCP is ``problem``
    (:meth:`ManeuverSpec.remainder`): only the duration, the initial state and the
    tension-ramp parameters change, so they are all that is recomputed (online re-plans).
    """
    x0 = spec.x_start
    if problem.nx == 8:
        G_M = spec.params.Gamma_M
        x0 = np.concatenate((x0[:4], G_M @ x0[4:8], G_M @ x0[8:12]))
    p_value = problem.p_value.copy()
    p_value[_PARAM_OFFSETS["a0"]] = max(0.0, spec.min_tension - spec.start_tension)
    p_value[_PARAM_OFFSETS["ramp"]] = spec.tension_ramp
    return problem.with_numbers(duration=spec.duration, x0=x0, p_value=p_value)


def _statement(
    form: StateForm, ground_effect: tuple[str, bytes] | None = None
) -> dict[str, object]:
    """The symbolic statement of (6.21) in the given state coordinates; ``ground_effect``:
    the believed ground effect's :attr:`PlannedGroundEffect.key` (the rotor bounds then
    hold the commands), None for the acting thrusts."""
    s = {name: ca.SX.sym(name, _PARAM_SIZES.get(name, 1)) for name in _PARAM_NAMES}
    P = ca.vertcat(*s.values())
    if ground_effect is not None:
        g = ca.SX.sym("ground_effect", GROUND_EFFECT_SIZE)
        P = ca.vertcat(P, g)
    c = _Coefficients(s)
    t, T, h = ca.SX.sym("t"), ca.SX.sym("T"), ca.SX.sym("h")
    G = ca.reshape(s["G"], 2, 4).T  # (4, 2), row-major values
    if form == "wrench":
        x, u = ca.SX.sym("z", 8), ca.SX.sym("v", 2)
        ode = wrench_form_rhs(x, u, c, CASADI)
        terms = wrench_form_terms(x, None, c, CASADI)
        u_f = G @ u
        thrusts = G @ x[4:6]
        thrusts_mid = G @ (x[4:6] + 0.5 * h * x[6:8])
        terminal_wrench = ca.vertcat(x[4] - s["f_R_f"], x[5], x[6], x[7])
        state_names: tuple[str, ...] = ("phi", "theta_A", "phi_dot", "theta_A_dot")
        state_names += ("f_R", "tau_y", "f_R_dot", "tau_y_dot")
    else:
        x, u = ca.SX.sym("x", 12), ca.SX.sym("v", 2)
        u_f = G @ u
        ode = rotor_form_rhs(x, u_f, c, CASADI)
        terms = rotor_form_terms(x, None, c, CASADI)
        thrusts = x[4:8]
        thrusts_mid = x[4:8] + 0.5 * h * x[8:12]
        row = s["torque_row"]
        terminal_wrench = ca.vertcat(
            ca.sum1(x[4:8]) - s["f_R_f"],
            ca.dot(row, x[4:8]),
            ca.sum1(x[8:12]),
            ca.dot(row, x[8:12]),
        )
        rotors = tuple(f"f{i}{d}" for d in ("", "_dot") for i in range(1, 5))
        state_names = ("phi", "theta_A", "phi_dot", "theta_A_dot", *rotors)
    phi, theta, dphi, dtheta = x[0], x[1], x[2], x[3]
    bump = ca.exp(-(((phi - s["phi_s"]) / s["width"]) ** 4))
    L = (
        s["k_phi"] * (phi - s["phi_f"]) ** 2
        + s["k_theta"] * (theta - s["theta_f"]) ** 2
        + s["k_phi_dot"] * dphi**2
        + s["k_theta_dot"] * dtheta**2
        + s["k_phi_ddot"] * terms["phi_ddot"] ** 2
        + s["k_theta_ddot"] * terms["theta_ddot"] ** 2
        + s["k_theta_near"] * bump * (theta - s["theta_s"]) ** 2
        + s["k_rates_near"] * bump * (dphi**2 + dtheta**2)
        + s["k_thrust_accel"] * ca.sumsqr(u_f)
    )
    E = s["k_final_theta_dot"] * dtheta**2 + s["k_final_phi_dot"] * dphi**2
    ramp = s["ramp"] * T
    floor = (
        s["f_L_min"] - s["a0"] * ca.fmax(0, 1 - t / ramp) - s["aT"] * ca.fmax(0, 1 - (T - t) / ramp)
    )
    # Rotor thrusts are quadratic in t on each interval (f'' held): f_k, f_k + f_k' h/2 and
    # f_{k+1} are their Bernstein coefficients, whose hull contains the whole arc. Bounding
    # them bounds the thrusts between the nodes too, not only at the nodes.
    # The rotors also cancel the offset's cable moment -b f_L: they carry G [0, b f_L] on
    # top of the planned net wrench (docs/theory.md (4.22)), bounded at every node (and
    # added, from the node, to the interval's Bernstein middle coefficient).
    share = G[:, 1] * (offset_arms(phi, theta, c.offset, CASADI)[1] * terms["tension"])
    path = [terms["tension"] - floor, thrusts_mid + share, thrusts + share]
    if ground_effect is not None:  # the commands f_i / k_i (the interval's first node's k)
        kind, samples = ground_effect
        pts = np.frombuffer(samples, dtype=float).reshape(-1, 2)
        k = factors_expr(phi, theta, g, kind, pts)  # type: ignore[arg-type]
        path = [path[0], path[1] / k, path[2] / k]
    terminal = ca.vertcat(phi - s["phi_f"], theta - s["theta_f"], dphi, dtheta, terminal_wrench)
    return {
        "x": x, "u": u, "p": P, "t": t, "T": T, "h": h,
        "ode": ode, "stage_cost": L, "terminal_cost": E, "path": ca.vertcat(*path),
        "terminal": terminal, "state_names": state_names,
        "input_names": ("f_R_ddot", "tau_y_ddot"),
    }  # fmt: skip


class _Coefficients:
    """Model constants as symbols, in the shape :mod:`tetherland.models.planar` expects."""

    def __init__(self, s: dict[str, ca.SX]) -> None:
        self.mass, self.length = s["mass"], s["length"]
        self.inertia, self.gravity = s["inertia"], s["gravity"]
        self.torque_row = [s["torque_row"][i] for i in range(4)]
        self.offset = (s["offset"][0], s["offset"][1])
