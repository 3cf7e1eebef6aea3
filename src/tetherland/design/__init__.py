"""Design search: cable, attachment, anchor height and hooking approach for a slope.

:func:`search_designs` finds the designs of a scenario's vehicle that can land on and take
off from a given slope (analysis, hooking clearance, then the planner), ranked by their
margins when the belief is off by the campaign's error bounds (:mod:`.robust`);
:func:`verify_designs` flies perturbed missions of the best and ranks by their success;
:func:`feasibility_map` maps the best design over slopes and cable lengths. The figure
lives in :mod:`tetherland.design.plot` (matplotlib).
"""

from tetherland.design.map import (
    FeasibilityMap,
    MapCell,
    SteepestSlope,
    feasibility_map,
    steepest_slope,
)
from tetherland.design.margins import plan_rotor_margin, plan_thrust_range, rotor_margin
from tetherland.design.robust import (
    BeliefBounds,
    gust_deviation,
    robust_pass_clearance,
    robust_rotor_margin,
)
from tetherland.design.search import (
    Design,
    DesignLimit,
    DesignResult,
    design_base,
    is_robust,
    landed_slope_limit,
    rank_key,
    search_designs,
)
from tetherland.design.space import DesignPoint, DesignSpace
from tetherland.design.verification import Verification
from tetherland.design.verify import rank_verified, verify_designs
from tetherland.mission.hooking import HookingPass, hooking_pass, hooking_pass_for, pass_clearance

__all__ = [
    "BeliefBounds",
    "Design",
    "DesignLimit",
    "DesignPoint",
    "DesignResult",
    "DesignSpace",
    "FeasibilityMap",
    "HookingPass",
    "MapCell",
    "SteepestSlope",
    "Verification",
    "design_base",
    "feasibility_map",
    "gust_deviation",
    "hooking_pass",
    "hooking_pass_for",
    "is_robust",
    "landed_slope_limit",
    "pass_clearance",
    "plan_rotor_margin",
    "plan_thrust_range",
    "rank_key",
    "rank_verified",
    "robust_pass_clearance",
    "robust_rotor_margin",
    "rotor_margin",
    "search_designs",
    "steepest_slope",
    "verify_designs",
]
