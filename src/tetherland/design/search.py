"""Search cable length, attachment offset, anchor height and hooking approach for a slope.

Hover first: a vehicle that cannot hover in free flight with the control margin
(:func:`tetherland.analysis.free_hover`) has no design; nothing else is searched. Then
three stages, cheapest first:

1. **Analysis** on the whole grid of (l, r_att,z, h_A): the landed inclined hover of
   :func:`tetherland.analysis.landed_hover` (rotor floor and ceiling with the control
   margin, the cable-offset torque, the rest with the motors off).
2. **Hooking clearance** for the feasible ones, best landed-hover rotor margin first:
   every approach direction and hook drop of the space; the pass must keep the
   ``mission.hooking.min_clearance``, and the approach with the most clearance (counted up to
   ``target_clearance``, then the shorter hook drop) is kept.
3. **Planning** for the first ``shortlist`` of them (stopping once ``max_designs`` are
   verified): the landing and takeoff OCPs (6.21)
   solved and verified by the planner (re-simulation: final state, rotor bounds, tension
   bound), then the rotor margin over both maneuvers with the cable-offset torque
   (:func:`~tetherland.design.margins.plan_rotor_margin`), which must keep the control
   margin, then the mission's plan from the start pad
   (:func:`~tetherland.mission.plan.plan_mission`: take-up, legs, stretch tension,
   duration, the magnet's reach).

The bar and the magnet fix the anchor height and the approach (:func:`anchor_heights`,
:data:`BAR_APPROACH_A`, :func:`magnet_approach_A`); the magnet's cable must outreach its
boom (:func:`cable_lengths`).

Designs are ranked robust first (:func:`rank_key`): those that keep the control margin
and ``min_clearance`` when the belief is off by the campaign's error bounds
(:mod:`tetherland.design.robust`), then by the robust rotor margin, then by the robust
hooking clearance (counted up to ``target_clearance``). ``tetherland design --verify N``
then flies perturbed missions of the best (:mod:`tetherland.design.verify`).
"""

from __future__ import annotations

import enum
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from tetherland.analysis import (
    Infeasibility,
    LandedHover,
    SlopeLimit,
    VehicleLimits,
    anchor_height_range,
    free_hover,
    landed_hover,
    tethered_slope_limit,
)
from tetherland.config import Scenario, with_overrides
from tetherland.design.fixes import Fix, fast_space, find_fixes, fixes_message
from tetherland.design.margins import plan_thrust_range, rotor_margin
from tetherland.design.robust import (
    BeliefBounds,
    believed_hover_margin,
    robust_pass_clearance,
    robust_rotor_margin,
)
from tetherland.design.space import DesignPoint, DesignSpace
from tetherland.design.verification import Verification
from tetherland.errors import ConfigError
from tetherland.geometry import (
    LandingGeometry,
    attachment_in_plane,
    effective_h_R,
    landing_geometry,
    stretched_link_length,
)
from tetherland.mission.hooking import hooking_pass, hooking_pass_for, pass_clearance
from tetherland.mission.plan import MissionError, design_hint, plan_mission
from tetherland.models.hook import magnet_reach_margin
from tetherland.planning import Maneuver, Planner, PlanResult
from tetherland.sim.mjcf import SceneLayout
from tetherland.surface import Surface

_TOL = 1e-9


class DesignLimit(enum.Enum):
    """The stage at which every candidate of a design search failed."""

    CANNOT_HOVER = "cannot_hover"
    """The vehicle cannot hover in free flight with the control margin: checked before
    any candidate (:attr:`~tetherland.analysis.Infeasibility.CANNOT_HOVER`)."""
    LANDED_HOVER = "landed_hover"
    """The analysis: no candidate holds the landed hover (see ``analysis_binding``)."""
    HOOKING_CLEARANCE = "hooking_clearance"
    """Every hooking pass of the feasible candidates comes closer to the surface than
    ``mission.hooking.min_clearance``."""
    PLAN = "plan"
    """The planner found no verified landing and takeoff for the shortlisted candidates."""
    PLAN_ROTOR_MARGIN = "plan_rotor_margin"
    """The plans exist, but with the cable-offset torque a rotor leaves the control margin."""
    MISSION_PLAN = "mission_plan"
    """The plans keep the control margin, but the mission's plan refuses the design
    (:func:`~tetherland.mission.plan.plan_mission` from the start pad: e.g. the take-up or
    a free-flight leg too close to the surface, the magnet's face not beyond the frame)."""
    INVALID_CONFIG = "invalid_config"
    """The shortlisted candidates are not valid scenarios (a validator of the
    configuration refuses them, e.g. an attachment point below the landers)."""


@dataclass(frozen=True)
class Design:
    """A design verified by the analysis, the hooking clearance and the planner.

    Attributes
    ----------
    point : DesignPoint
    landed_rotor_margin : float
        Rotor margin of the landed inclined hover, cable-offset torque included [N].
    min_rotor_margin : float
        Rotor margin over the planned landing and takeoff, torque included [N].
    min_clearance : float
        Smallest distance of the vehicle from the surface on the hooking pass [m].
    landing, takeoff : PlanResult
        The verified plans.
    robust_rotor_margin : float
        Rotor margin over the plans with the thrusts commanded under the belief's mass and
        thrust-coefficient errors (:func:`~tetherland.design.robust.robust_rotor_margin`) [N].
    robust_clearance : float
        Clearance of the hooking pass from the true surface when the believed surface,
        anchor and mass are off by the error bounds
        (:func:`~tetherland.design.robust.robust_pass_clearance`) [m].
    believed_hover_margin : float
        Rotor margin beyond the control margin of the landing's boundary hovers as the
        robot computes them from a belief off by the error bounds
        (:func:`~tetherland.design.robust.believed_hover_margin`): below 0 the robot
        refuses to plan on part of the campaign's beliefs [N].
    verified : Verification or None
        Perturbed missions flown with the design (``design --verify``; None: not flown).
    """

    point: DesignPoint
    landed_rotor_margin: float
    min_rotor_margin: float
    min_clearance: float
    landing: PlanResult
    takeoff: PlanResult
    robust_rotor_margin: float
    robust_clearance: float
    believed_hover_margin: float
    verified: Verification | None = None

    @property
    def overrides(self) -> tuple[str, ...]:
        return self.point.overrides()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (the keys of ``tetherland design --json``)."""
        return {
            "overrides": list(self.overrides),
            "min_rotor_margin_N": self.min_rotor_margin,
            "min_clearance_m": self.min_clearance,
            "landed_rotor_margin_N": self.landed_rotor_margin,
            "robust_rotor_margin_N": self.robust_rotor_margin,
            "robust_clearance_m": self.robust_clearance,
            "believed_hover_margin_N": self.believed_hover_margin,
            "verified": None if self.verified is None else self.verified.to_dict(),
        }


@dataclass(frozen=True)
class DesignResult:
    """Outcome of :func:`search_designs`.

    Attributes
    ----------
    scenario : str
    slope_deg : float
        The slope searched for [deg].
    designs : tuple of Design
        Verified designs, best first (empty: infeasible).
    limit : DesignLimit or None
        Where every candidate failed (None when a design was found).
    analysis_binding : Infeasibility or None
        With ``limit`` LANDED_HOVER: the requirement that binds for the best candidate.
    reason : str
        One line: ``"ok"``, or why no design exists.
    landed_margin : float or None
        Best landed-hover rotor margin of the analysis over the grid, cable-offset torque
        included [N] (None: no grid point holds the landed hover).
    candidates : int
        Grid points (l, r_att,z, h_A) checked by the analysis.
    planned : int
        Candidates whose landing and takeoff were planned.
    wall_time_s : float
        Wall time of the search [s].
    fixes : tuple of Fix
        When infeasible and asked for (``search_designs(..., fixes=True)``): vehicle values
        with which a design exists (:mod:`tetherland.design.fixes`), also named in
        ``reason``.
    """

    scenario: str
    slope_deg: float
    designs: tuple[Design, ...]
    limit: DesignLimit | None
    analysis_binding: Infeasibility | None
    reason: str
    landed_margin: float | None
    candidates: int
    planned: int
    wall_time_s: float
    fixes: tuple[Fix, ...] = ()

    @property
    def feasible(self) -> bool:
        return bool(self.designs)

    @property
    def chosen(self) -> Design | None:
        """The best design (None when infeasible)."""
        return self.designs[0] if self.designs else None

    @property
    def binding(self) -> str | None:
        """The limit that binds, by name: an :class:`Infeasibility` value for the landed
        hover, else a :class:`DesignLimit` value (None when feasible)."""
        if self.limit is None:
            return None
        if self.limit is DesignLimit.LANDED_HOVER and self.analysis_binding is not None:
            return self.analysis_binding.value
        return self.limit.value

    def to_dict(self) -> dict[str, Any]:
        """The document ``tetherland design --json`` prints (without provenance)."""
        return {
            "scenario": self.scenario,
            "slope_deg": self.slope_deg,
            "feasible": self.feasible,
            "reason": self.reason,
            "binding": self.binding,
            "designs": [d.to_dict() for d in self.designs],
            "landed_margin_N": self.landed_margin,
            "candidates": self.candidates,
            "planned": self.planned,
            "wall_time_s": self.wall_time_s,
            "fixes": [f.to_dict() for f in self.fixes],
        }


@dataclass(frozen=True)
class _Candidate:
    """A grid point (l, r_att, h_A) and its landed hover."""

    length: float
    attachment: tuple[float, float, float]
    h_A: float
    hover: LandedHover
    landed_margin: float

    def describe(self) -> str:
        return (
            f"l = {self.length:g} m, attachment z = {self.attachment[2]:g} m, h_A = {self.h_A:g} m"
        )


@dataclass(frozen=True)
class _Hooking:
    approach_A: tuple[float, float, float]
    hook_drop: float
    clearance: float


def design_base(scenario: Scenario, slope_deg: float | None = None) -> Scenario:
    """The scenario at ``slope_deg`` (validated), checked to be one the search can vary.

    Raises
    ------
    ConfigError
        For a slope outside [0, 180] deg or not finite, a surface given by its normal,
        or an explicit anchor position (the search places the anchor by (6.13)).
    """
    if scenario.surface.normal is not None:
        raise ConfigError(
            "design varies surface.slope_deg: give the surface by slope_deg and azimuth_deg, "
            "not by surface.normal"
        )
    if scenario.anchor.position is not None:
        raise ConfigError(
            "design places the anchor by (6.13) for anchor.landing_point: remove anchor.position"
        )
    if slope_deg is None:
        return scenario
    return with_overrides(scenario, [f"surface.slope_deg={float(slope_deg)!r}"])


def search_designs(
    scenario: Scenario,
    slope_deg: float | None = None,
    space: DesignSpace | None = None,
    planner: Planner | None = None,
    fixes: bool = False,
) -> DesignResult:
    """Designs of ``scenario``'s vehicle that can land on and take off from ``slope_deg``.

    Parameters
    ----------
    scenario : Scenario
        Vehicle, surface kind and friction, mission settings (hooking pass), planner.
    slope_deg : float, optional
        Slope in [0, 180] [deg]; default the scenario's.
    space : DesignSpace, optional
        The grid searched (default :class:`DesignSpace`).
    planner : Planner, optional
        Reused for its compiled solvers.
    fixes : bool
        When no design exists, also search the vehicle values with which one does
        (:func:`~tetherland.design.fixes.find_fixes`: ``vehicle.f_max``, ``vehicle.mass``,
        ``vehicle.f_min``, else the slope), and name them in ``reason`` (slower: a search
        per value tried).

    Raises
    ------
    ConfigError
        On bad input (see :func:`design_base`).
    """
    t0 = time.perf_counter()
    result = _search(scenario, slope_deg, space, planner)
    if not fixes or result.feasible:
        return result
    space = space or DesignSpace()
    planner = planner or Planner()
    base = design_base(scenario, slope_deg)
    quick = fast_space(space)
    found = find_fixes(base, lambda sc: _search(sc, None, quick, planner).feasible)
    return replace(
        result, fixes=found, reason=f"{result.reason}; {fixes_message(found)}",
        wall_time_s=time.perf_counter() - t0,
    )  # fmt: skip


def _search(
    scenario: Scenario,
    slope_deg: float | None,
    space: DesignSpace | None,
    planner: Planner | None,
) -> DesignResult:
    """:func:`search_designs` without the fixes."""
    t0 = time.perf_counter()
    space = space or DesignSpace()
    planner = planner or Planner()
    base = design_base(scenario, slope_deg)
    B = float(base.surface.slope_deg)

    hover = free_hover(VehicleLimits.from_scenario(base))
    candidates = _analysis_stage(base, space) if hover.ok else []
    feasible = sorted((c for c in candidates if c.hover.feasible), key=lambda c: -c.landed_margin)

    def result(
        designs: Sequence[Design],
        limit: DesignLimit | None,
        binding: Infeasibility | None,
        reason: str,
        counted: int,
        planned: int,
    ) -> DesignResult:
        return DesignResult(
            scenario=base.name, slope_deg=B, designs=tuple(designs), limit=limit,
            analysis_binding=binding, reason=reason,
            landed_margin=feasible[0].landed_margin if feasible else None,
            candidates=counted, planned=planned, wall_time_s=time.perf_counter() - t0,
        )  # fmt: skip

    if not hover.ok:
        reason = f"no design lands on {B:g} deg: {hover.message}"
        return result((), DesignLimit.CANNOT_HOVER, None, reason, 0, 0)
    if not feasible:
        limit, binding, reason = _no_landed_hover(base, space, candidates)
        return result((), limit, binding, reason, len(candidates), 0)

    hooked: list[tuple[_Candidate, _Hooking]] = []
    closest: tuple[_Candidate, _Hooking] | None = None
    surface = LandingGeometry.from_scenario(base).surface
    for cand in feasible:
        best = _best_hooking(base, surface, space, cand)
        if best is None:
            continue
        if best.clearance >= base.mission.hooking.min_clearance - _TOL:
            hooked.append((cand, best))
            if len(hooked) >= space.shortlist:
                break
        elif closest is None or best.clearance > closest[1].clearance:
            closest = (cand, best)
    if not hooked:
        reason = f"no design lands on {B:g} deg: the hooking pass comes too close to the surface"
        if closest is not None:
            cand, hook = closest
            reason += (
                f" for every candidate whose landed hover is feasible; the best ({cand.describe()},"
                f" approach {list(hook.approach_A)}, hook_drop {hook.hook_drop:g} m) passes "
                f"{100 * hook.clearance:.1f} cm from it (needs mission.hooking.min_clearance = "
                f"{100 * base.mission.hooking.min_clearance:g} cm)"
            )
        return result((), DesignLimit.HOOKING_CLEARANCE, None, reason, len(candidates), 0)

    designs: list[Design] = []
    failures: list[tuple[DesignLimit, str]] = []
    planned = 0
    for cand, hook in hooked:
        point = DesignPoint(B, cand.length, cand.attachment, cand.h_A, hook.approach_A,
                            hook.hook_drop)  # fmt: skip
        try:
            sc = point.apply(base)
        except ConfigError as err:
            failures.append((DesignLimit.INVALID_CONFIG, f"{cand.describe()}: {err}"))
            continue
        planned += 1
        outcome = _plan_stage(sc, planner, cand, hook, point)
        if isinstance(outcome, Design):
            designs.append(outcome)
            if len(designs) >= space.max_designs:
                break
        else:
            failures.append(outcome)
    if not designs:
        # the best-ranked candidate that got furthest: its failure is what binds
        order = (DesignLimit.MISSION_PLAN, DesignLimit.PLAN_ROTOR_MARGIN, DesignLimit.PLAN,
                 DesignLimit.INVALID_CONFIG)  # fmt: skip
        limit, why = min(failures, key=lambda f: order.index(f[0]))
        reason = f"no design lands on {B:g} deg: {why}"
        return result((), limit, None, reason, len(candidates), planned)
    designs.sort(key=lambda d: rank_key(d, base, space))
    return result(designs[: space.max_designs], None, None, "ok", len(candidates), planned)


BAR_APPROACH_A = (0.0, 0.0, -1.0)
"""The bar's only hooking approach, in F_A: the hanging hook is lowered beside the bar."""


def magnet_approach_A(slope: float) -> tuple[float, float, float]:
    """The magnet's only hooking approach on a surface of slope ``slope`` [rad], in F_A:
    along the surface's normal, -z_S = (-cos(e), 0, -sin(e)) with e = pi/2 - slope
    (rounded to 1e-6 as written in an override) [-]. The pass presses the magnet's face,
    across the approach, on the plate until the plate stops it (the supervisor switches
    the EPM on only then); an oblique pass would slide the face along the plate once the
    tangential push exceeds the face's friction (0.25: 14 deg off the normal)."""
    e = 0.5 * math.pi - slope
    return (round(-math.cos(e), 6) + 0.0, 0.0, round(-math.sin(e), 6) + 0.0)


def anchor_heights(base: Scenario, space: DesignSpace) -> tuple[float, ...]:
    """Anchor heights the search tries [m]: the space's, or the one the mechanism fixes:
    for the bar ``mechanism.standoff`` (the bar's axis; the hook's geometry bounds it
    from below, docs/mechanism.md), for the magnet ``plate_thickness +
    magnet_thickness`` (the cable's eye on the held magnet), which the search keeps as
    built."""
    if base.mechanism.kind == "bar":
        return (float(base.mechanism.standoff),)
    if base.mechanism.kind == "magnet":
        return (float(base.mechanism.magnet_eye_height),)
    return tuple(float(h) for h in space.anchor_heights)


def cable_lengths(base: Scenario, space: DesignSpace) -> tuple[float, ...]:
    """Cable lengths the search tries [m]: the space's, for the magnet only those longer
    than its boom as built (``mechanism.boom_length``: the cable from the attachment to the
    clipped magnet must be slack, a check of the configuration)."""
    if base.mechanism.kind == "magnet":
        return tuple(float(v) for v in space.lengths if v > base.mechanism.boom_length)
    return tuple(float(v) for v in space.lengths)


def _analysis_stage(
    base: Scenario, space: DesignSpace, lengths: Sequence[float] | None = None
) -> list[_Candidate]:
    """The landed hover of every grid point; ``lengths`` [m] instead of
    :func:`cable_lengths`."""
    geo = LandingGeometry.from_scenario(base)
    limits0 = VehicleLimits.from_scenario(base)
    v = base.vehicle
    h_R = effective_h_R(base)
    rx, ry, _ = v.cable_attachment
    out = []
    for length in cable_lengths(base, space) if lengths is None else lengths:
        for z in space.attachment_z:
            for h_A in anchor_heights(base, space):
                h = h_R + z - h_A
                if not abs(h) < length:
                    continue
                c = h / _link_length(base, h, float(length), geo.surface.slope)
                attachment = (float(rx), float(ry), float(z))
                limits = replace(limits0, r_att_B=np.array(attachment))
                hover = landed_hover(geo.surface, c, limits)
                margin = rotor_margin(hover.rotor_thrusts, v.f_min, v.f_max)
                out.append(_Candidate(float(length), attachment, float(h_A), hover, margin))
    return out


def _no_landed_hover(
    base: Scenario, space: DesignSpace, candidates: list[_Candidate]
) -> tuple[DesignLimit, Infeasibility | None, str]:
    B = base.surface.slope_deg
    lengths = cable_lengths(base, space)
    if not lengths:
        return (
            DesignLimit.LANDED_HOVER,
            None,
            f"no design lands on {B:g} deg: no cable length searched "
            f"({min(space.lengths):g}-{max(space.lengths):g} m) is longer than the magnet's "
            f"mechanism.boom_length = {base.mechanism.boom_length:g} m",
        )
    span = f"{min(lengths):g}-{max(lengths):g} m"
    if not candidates:
        return (
            DesignLimit.LANDED_HOVER,
            None,
            f"no design lands on {B:g} deg: |h_att - h_A| >= l for every cable length searched "
            f"({span})",
        )
    best = max(candidates, key=lambda c: c.hover.margin)
    finding = best.hover.findings[0]
    reason = (
        f"no design lands on {B:g} deg: {finding.reason.value} binds for every cable length "
        f"({span}), attachment offset and anchor "
        f"height searched; the closest ({best.describe()}): {finding.message}"
    )
    if base.mechanism.kind == "bar":
        reason += _bar_standoff_note(base, space)
    if base.mechanism.kind == "magnet":
        reason += _magnet_boom_note(base, space)
    return DesignLimit.LANDED_HOVER, finding.reason, reason


def _magnet_boom_note(base: Scenario, space: DesignSpace) -> str:
    """For the magnet: the longest cable of the space whose landed hover holds (with the
    magnet's anchor height, any attachment offset of the space, cables as short as the
    boom included), against the boom, which the cable must outreach."""
    boom = base.mechanism.boom_length
    held = [c.length for c in _analysis_stage(base, space, space.lengths) if c.hover.feasible]
    prefix = (
        f"; the magnet's anchor height is mechanism.plate_thickness + magnet_thickness = "
        f"{base.mechanism.magnet_eye_height:g} m and the cable must be longer than its "
        f"mechanism.boom_length = {boom:g} m"
    )
    if not held:
        return f"{prefix}: no cable length searched holds the landed hover either"
    return (
        f"{prefix}: the longest cable searched that holds the landed hover is "
        f"{max(held):g} m (a shorter boom that still reaches beyond the frame, at a smaller "
        "boom_angle_deg, docs/mechanism.md)"
    )


def _bar_standoff_note(base: Scenario, space: DesignSpace) -> str:
    """For the bar: the highest anchor the rotors hold over the space's attachments (any
    cable length of the space, :func:`~tetherland.analysis.anchor_height_range`), against
    the bar's standoff."""
    limits0 = VehicleLimits.from_scenario(base)
    surface = LandingGeometry.from_scenario(base).surface
    rx, ry, _ = base.vehicle.cable_attachment
    notes = []
    for z in space.attachment_z:
        att = (float(rx), float(ry), float(z))
        limits = replace(limits0, r_att_B=np.array(att))
        h_att = effective_h_R(base) + z
        highest = [
            r[1]
            for length in space.lengths
            if (r := anchor_height_range(surface.slope, h_att, float(length), limits)) is not None
        ]
        notes.append(f"z = {z:g} m: {max(highest):.3f} m" if highest else f"z = {z:g} m: none")
    return (
        f"; the bar's mechanism.standoff = {base.mechanism.standoff:g} m is the anchor height, "
        f"and the highest anchor the rotors hold at {base.surface.slope_deg:g} deg is, by "
        f"attachment offset, {', '.join(notes)} (move the cable attachment toward "
        "the centre of mass, docs/mechanism.md)"
    )


def _link_length(base: Scenario, height: float, length: float, slope: float) -> float:
    """The landed link l + s of a candidate cable ``length`` [m] on ``slope`` [rad] (the
    base's material and vehicle; l when inextensible): :func:`stretched_link_length`."""
    return stretched_link_length(
        height, length, slope, base.vehicle.mass, base.tether.effective_axial_stiffness
    )


def _best_hooking(
    base: Scenario, surface: Surface, space: DesignSpace, cand: _Candidate
) -> _Hooking | None:
    """The hooking approach with the most clearance for this candidate (None: no valid
    hook drop, every one leaves the cable taut at capture)."""
    if base.mechanism.kind == "bar":
        return _bar_hooking(base, space, cand)
    if base.mechanism.kind == "magnet":
        return _magnet_hooking(base, cand)
    h_R = effective_h_R(base)
    h = h_R + cand.attachment[2] - cand.h_A
    geo = landing_geometry(
        surface,
        length=cand.length,
        stretch=_link_length(base, h, cand.length, surface.slope) - cand.length,
        h_R=h_R,
        h_att=h_R + cand.attachment[2],
        h_A=cand.h_A,
        landing_point=base.anchor.landing_point,
        r_par_W=attachment_in_plane(
            surface.R_WS, cand.attachment, math.radians(base.planner.heading_deg)
        ),
    )
    capture, cfg = base.tether.capture_radius, base.mission
    drops = [d for d in space.hook_drops if d + capture < cand.length]
    if not drops:
        return None

    def exact(approach: tuple[float, float, float], drop: float) -> _Hooking:
        hooking = hooking_pass_for(
            geo, approach_A=approach, hook_drop=drop, r_att_B=cand.attachment,
            approach_distance=cfg.hooking.approach_distance, hook_overshoot=cfg.hooking.overshoot,
        )  # fmt: skip
        return _Hooking(approach, float(drop), pass_clearance(base, geo, hooking))

    best: _Hooking | None = None
    for approach in space.approach_directions(geo.surface.slope):
        if geo.surface.kind == "plane":
            # The hook drop moves the whole level vehicle by -drop n, so every distance from
            # a plane changes by -drop (n . z_S): the clearance is affine in the drop.
            at_zero = exact(approach, 0.0).clearance
            n_W = geo.R_WA @ np.asarray(approach) / np.linalg.norm(approach)
            rate = -float(n_W @ geo.surface.z_S)
            drop = max(drops, key=lambda d: (min(at_zero + rate * d, space.target_clearance), -d))
            option = exact(approach, drop)
        else:
            option = None
            for drop in drops:
                trial = exact(approach, drop)
                if option is None or _hook_score(trial, space) > _hook_score(option, space):
                    option = trial
                if trial.clearance >= space.target_clearance:
                    break  # a longer hook of this approach scores lower
        if best is None or _hook_score(option, space) > _hook_score(best, space):
            best = option
    return best


def _bar_hooking(base: Scenario, space: DesignSpace, cand: _Candidate) -> _Hooking | None:
    """The bar's one hooking pass for this candidate: straight down, the hanging hook
    beside the bar, the mission's own pass (:func:`~tetherland.mission.hooking.hooking_pass`
    of the candidate's scenario). ``tether.hook_drop`` does not place the bar's hook; it
    stays the scenario's where the tether's check allows, else the longest one of the
    space that does (None: none does, or the candidate is not a valid scenario)."""
    capture = base.tether.capture_radius
    drops = [d for d in space.hook_drops if d + capture < cand.length]
    if base.tether.hook_drop + capture < cand.length:
        drop = float(base.tether.hook_drop)
    elif drops:
        drop = float(drops[-1])
    else:
        return None
    point = DesignPoint(float(base.surface.slope_deg), cand.length, cand.attachment, cand.h_A,
                        BAR_APPROACH_A, drop)  # fmt: skip
    try:
        sc = point.apply(base)
    except ConfigError:
        return None
    geo = LandingGeometry.from_scenario(sc)
    return _Hooking(BAR_APPROACH_A, drop, pass_clearance(sc, geo, hooking_pass(sc, geo)))


def _magnet_hooking(base: Scenario, cand: _Candidate) -> _Hooking | None:
    """The magnet's one hooking pass for this candidate: along the surface's normal
    (:func:`magnet_approach_A`), the unfolded boom's eye aimed at p_A, the mission's own
    pass (:func:`~tetherland.mission.hooking.hooking_pass`, ending ``press_depth`` beyond
    the anchor) of the candidate's scenario. ``tether.hook_drop`` does not apply to the
    magnet and stays the scenario's. None: the candidate is not a valid scenario, or the
    magnet's face does not reach beyond the frame along the approach
    (:func:`~tetherland.models.hook.magnet_reach_margin`; the mission's plan refuses it)."""
    approach = magnet_approach_A(math.radians(base.surface.slope_deg))
    point = DesignPoint(float(base.surface.slope_deg), cand.length, cand.attachment, cand.h_A,
                        approach, float(base.tether.hook_drop))  # fmt: skip
    try:
        sc = point.apply(base)
    except ConfigError:
        return None
    if magnet_reach_margin(sc) <= 0.0:
        return None
    geo = LandingGeometry.from_scenario(sc)
    return _Hooking(approach, float(base.tether.hook_drop),
                    pass_clearance(sc, geo, hooking_pass(sc, geo)))  # fmt: skip


def _hook_score(h: _Hooking, space: DesignSpace) -> tuple[float, float]:
    return (min(h.clearance, space.target_clearance), -h.hook_drop)


def is_robust(design: Design, scenario: Scenario) -> bool:
    """Does ``design`` keep the control margin and ``mission.hooking.min_clearance`` when the
    belief is off by the error bounds, and does the robot plan on every such belief?"""
    return (
        design.robust_rotor_margin >= scenario.vehicle.control_margin - _TOL
        and design.robust_clearance >= scenario.mission.hooking.min_clearance - _TOL
        and design.believed_hover_margin >= -_TOL
    )


def rank_key(design: Design, scenario: Scenario, space: DesignSpace) -> tuple[float, ...]:
    """Sort key of a design, best first: robust ones (:func:`is_robust`) first, then the larger
    least rotor margin under the belief's errors (the smaller of the commanded thrusts'
    margin beyond the control margin and the believed hovers' margin), then the larger
    robust clearance counted up to ``space.target_clearance``."""
    rotor = min(
        design.robust_rotor_margin - scenario.vehicle.control_margin,
        design.believed_hover_margin,
    )
    return (
        0.0 if is_robust(design, scenario) else 1.0,
        -rotor,
        -min(design.robust_clearance, space.target_clearance),
    )


def _plan_stage(
    sc: Scenario, planner: Planner, cand: _Candidate, hook: _Hooking, point: DesignPoint
) -> Design | tuple[DesignLimit, str]:
    plans = []
    for maneuver in (Maneuver.LANDING, Maneuver.TAKEOFF):
        plan = planner.plan(sc, maneuver)
        if not plan.success:
            return (
                DesignLimit.PLAN,
                f"{cand.describe()}: {maneuver.value} plan {plan.status.value}: {plan.message}",
            )
        plans.append(plan)
    v, bounds = sc.vehicle, BeliefBounds.from_scenario(sc)
    f_low, f_high = plan_thrust_range(sc, plans)
    margin = rotor_margin([f_low, f_high], v.f_min, v.f_max)
    floor = sc.vehicle.control_margin
    if margin < floor - _TOL:
        return (
            DesignLimit.PLAN_ROTOR_MARGIN,
            f"{cand.describe()}: with the cable-offset torque the planned maneuvers keep a rotor "
            f"margin of {margin:.3f} N < control_margin = {floor:g} N",
        )
    try:  # the mission's own checks, from the plant's start pad
        plan_mission(sc, SceneLayout.from_scenario(sc).start_state(sc.vehicle.h_R), planner)
    except MissionError as err:
        why = str(err).replace(f"; {design_hint(sc)}", "")
        return DesignLimit.MISSION_PLAN, f"{cand.describe()}: the mission's plan: {why}"
    return Design(
        point=point,
        landed_rotor_margin=cand.landed_margin,
        min_rotor_margin=margin,
        min_clearance=hook.clearance,
        landing=plans[0],
        takeoff=plans[1],
        robust_rotor_margin=robust_rotor_margin(f_low, f_high, v.f_min, v.f_max, bounds),
        robust_clearance=robust_pass_clearance(sc, bounds),
        believed_hover_margin=believed_hover_margin(sc, bounds),
    )


def landed_slope_limit(scenario: Scenario, length: float, space: DesignSpace) -> SlopeLimit:
    """Steepest slope whose landed hover is feasible for cable ``length`` [m], over the
    attachment offsets and anchor heights of ``space`` (the analysis' bound, without
    hooking or planning), and what binds beyond it. An elastic cable's c = h/(l + s) is
    re-solved at every slope searched (docs/theory.md section 13.2)."""
    base = design_base(scenario)
    surface = LandingGeometry.from_scenario(base).surface
    limits0 = VehicleLimits.from_scenario(base)
    h_R = effective_h_R(base)
    rx, ry, _ = base.vehicle.cable_attachment
    best = SlopeLimit(None, None)
    for z in space.attachment_z:
        for h_A in anchor_heights(base, space):
            h = h_R + z - h_A
            if not abs(h) < length:
                continue
            limits = replace(limits0, r_att_B=np.array([rx, ry, z], dtype=float))
            limit = tethered_slope_limit(
                surface, lambda b, h=h: h / _link_length(base, h, length, b), limits
            )
            if limit.max_slope_rad is not None and (
                best.max_slope_rad is None or limit.max_slope_rad > best.max_slope_rad
            ):
                best = limit
    return best
