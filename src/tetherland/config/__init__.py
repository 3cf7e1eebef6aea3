"""Scenario configuration: typed, frozen, validated sections loaded from TOML.

>>> from tetherland.config import load_scenario
>>> s = load_scenario("slope50", ["surface.slope_deg=60"])
>>> s.surface.slope_deg
60.0
"""

from tetherland.config.aero import AeroConfig
from tetherland.config.base import Section, Vec3
from tetherland.config.control import ControllerConfig, FreeFlightGains, TetheredGains
from tetherland.config.estimation import EstimatorConfig
from tetherland.config.faults import FaultDetectionConfig, FaultKind, FaultsConfig
from tetherland.config.loader import (
    ScenarioInfo,
    apply_overrides,
    builtin_scenarios,
    format_validation_error,
    load_scenario,
    parse_override,
    scenario_from_dict,
    scenario_to_toml,
    with_overrides,
)
from tetherland.config.mechanism import MechanismConfig
from tetherland.config.mission import (
    ContactConfig,
    FlightConfig,
    HookingConfig,
    MissionConfig,
    StretchConfig,
    TouchdownConfig,
)
from tetherland.config.perching import PerchingConfig, PerchingWeights
from tetherland.config.perturbation import PerturbationConfig
from tetherland.config.physical import (
    TETHER_MATERIALS,
    AnchorConfig,
    CableModel,
    SurfaceConfig,
    TetherConfig,
    TetherMaterial,
    VehicleConfig,
)
from tetherland.config.planning import PlannerConfig, PlannerWeights
from tetherland.config.renames import RENAMES, check_renames
from tetherland.config.scenario import Scenario
from tetherland.config.sensors import ImuConfig, MocapConfig, SensorsConfig
from tetherland.config.simulation import SimConfig
from tetherland.config.verdict import VerdictConfig

__all__ = [
    "RENAMES",
    "TETHER_MATERIALS",
    "AeroConfig",
    "AnchorConfig",
    "CableModel",
    "ContactConfig",
    "ControllerConfig",
    "EstimatorConfig",
    "FaultDetectionConfig",
    "FaultKind",
    "FaultsConfig",
    "FlightConfig",
    "FreeFlightGains",
    "HookingConfig",
    "ImuConfig",
    "MechanismConfig",
    "MissionConfig",
    "MocapConfig",
    "PerchingConfig",
    "PerchingWeights",
    "PerturbationConfig",
    "PlannerConfig",
    "PlannerWeights",
    "Scenario",
    "ScenarioInfo",
    "Section",
    "SensorsConfig",
    "SimConfig",
    "StretchConfig",
    "SurfaceConfig",
    "TetherConfig",
    "TetherMaterial",
    "TetheredGains",
    "TouchdownConfig",
    "Vec3",
    "VehicleConfig",
    "VerdictConfig",
    "apply_overrides",
    "builtin_scenarios",
    "check_renames",
    "format_validation_error",
    "load_scenario",
    "parse_override",
    "scenario_from_dict",
    "scenario_to_toml",
    "with_overrides",
]
