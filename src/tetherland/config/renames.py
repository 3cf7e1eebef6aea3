"""Scenario fields that were renamed, and the check that names the new field.

A scenario file (or a ``--set`` override) that still uses an old name fails with one line
naming the new one, e.g. ``mission.touchdown_hold_rate was renamed: use
mission.touchdown.hold_rate``, instead of the generic "unknown key". :data:`RENAMES` is
the one table of renames; docs/reference/scenario.md lists it.
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType
from typing import Any

from tetherland.errors import ConfigError

RENAMES: Mapping[str, str] = MappingProxyType({
    # [mission] in sub-sections by reader (issue 26)
    "mission.takeoff_height": "mission.flight.takeoff_height",
    "mission.cruise_speed": "mission.flight.cruise_speed",
    "mission.cruise_accel": "mission.flight.cruise_accel",
    "mission.safe_height_margin": "mission.flight.safe_height_margin",
    "mission.waypoint_tolerance": "mission.flight.waypoint_tolerance",
    "mission.pad_press_depth": "mission.flight.pad_press_depth",
    "mission.hook_speed": "mission.hooking.speed",
    "mission.approach_distance": "mission.hooking.approach_distance",
    "mission.hook_overshoot": "mission.hooking.overshoot",
    "mission.unhook_depth": "mission.hooking.unhook_depth",
    "mission.hooking_clearance": "mission.hooking.min_clearance",
    "mission.hook_start_tolerance": "mission.hooking.start_tolerance",
    "mission.max_hook_attempts": "mission.hooking.max_attempts",
    "mission.release_slack": "mission.hooking.release_slack",
    "mission.slack_out_distance": "mission.stretch.slack_out_distance",
    "mission.take_up_speed_factor": "mission.stretch.take_up_speed_factor",
    "mission.stretch_speed": "mission.stretch.speed",
    "mission.stretch_margin": "mission.stretch.pull_margin",
    "mission.stretch_timeout": "mission.stretch.timeout",
    "mission.tension_threshold": "mission.stretch.tension_threshold",
    "mission.tension_dwell": "mission.stretch.tension_dwell",
    "mission.touchdown_approach_speed": "mission.touchdown.approach_speed",
    "mission.touchdown_approach_gain": "mission.touchdown.approach_gain",
    "mission.touchdown_hold_rate": "mission.touchdown.hold_rate",
    "mission.touchdown_hold_clearance": "mission.touchdown.hold_clearance",
    "mission.touchdown_hold_max": "mission.touchdown.hold_max_time",
    "mission.touchdown_hold_retreat": "mission.touchdown.hold_retreat",
    "mission.touchdown_lateral_clearance": "mission.touchdown.lateral_clearance",
    "mission.touchdown_rate_deg": "mission.touchdown.descent_rate_deg_s",
    "mission.touchdown_search_deg": "mission.touchdown.search_depth_deg",
    "mission.contact_window": "mission.contact.window",
    "mission.contact_gate_deg": "mission.contact.gate_deg",
    "mission.contact_clearance": "mission.contact.clearance",
    "mission.contact_error_deg": "mission.contact.link_lag_deg",
    "mission.contact_stall_rate_deg": "mission.contact.stall_rate_deg_s",
    "mission.contact_creep_rate_deg": "mission.contact.creep_rate_deg_s",
    "mission.contact_force": "mission.contact.surface_force",
    "mission.contact_force_time_constant": "mission.contact.surface_force_time_constant",
    "mission.contact_impact_force": "mission.contact.impact_force",
    "mission.contact_dwell": "mission.contact.dwell",
    "mission.contact_press_deg": "mission.contact.press_deg",
    "mission.fault_min_tension": "mission.detection.slack_tension",
    "mission.fault_slack_time": "mission.detection.slack_dwell",
    "mission.fault_tracking_deg": "mission.detection.tracking_error_deg",
    "mission.takeoff_fault_delay": "mission.detection.tethered_takeoff_delay",
    "mission.phase_timeout": "mission.detection.leg_timeout",
    "mission.touchdown_search_grace": "mission.detection.no_contact_grace",
    "mission.max_duration": "mission.time_limit",
    "mission.detection.rotor_filter_time": "mission.detection.rotor_torque_time_constant",
    "mission.detection.rotor_suspect_max": "mission.detection.rotor_suspect_max_time",
    # one spelling for time constants and damping ratios
    "sim.contact_timeconst": "sim.contact_time_constant",
    "sim.contact_dampratio": "sim.contact_damping_ratio",
    "sim.cable_timeconst": "sim.cable_time_constant",
    "sim.cable_dampratio": "sim.cable_damping_ratio",
    # SI fields carry no unit suffix; one name, one meaning
    "verdict.position_m": "verdict.position_error",
    "verdict.attitude_deg": "verdict.attitude_error_deg",
    "verdict.speed_mps": "verdict.touchdown_speed",
    "verdict.angular_rate_rps": "verdict.touchdown_angular_rate",
    "verdict.accel_mps2": "verdict.touchdown_accel",
    "verdict.angular_accel_rps2": "verdict.touchdown_angular_accel",
    "verdict.slip_m": "verdict.rest_slip",
    "verdict.rest_speed_mps": "verdict.rest_speed",
    "verdict.rest_settle": "verdict.rest_settle_time",
    "verdict.contact_force": "verdict.touchdown_force",
    "verdict.safe_stop_speed_mps": "verdict.safe_stop_speed",
    "verdict.return_position_m": "verdict.return_position_error",
    "perturbation.slope_deg": "perturbation.slope_error_deg",
    "perturbation.azimuth_deg": "perturbation.azimuth_error_deg",
    "perturbation.anchor_position": "perturbation.anchor_error",
    "perching.start_distance": "perching.hover_distance",
    "perching.start_position": "perching.hover_position",
})  # fmt: skip
"""Old dotted TOML key -> new dotted TOML key."""


def _lookup(data: Mapping[str, Any], dotted: str) -> bool:
    node: Any = data
    for key in dotted.split("."):
        if not isinstance(node, Mapping) or key not in node:
            return False
        node = node[key]
    return True


def renamed_keys(data: Mapping[str, Any]) -> list[tuple[str, str]]:
    """The (old, new) names of every renamed key present in ``data`` (TOML layout)."""
    return [(old, new) for old, new in RENAMES.items() if _lookup(data, old)]


def check_renames(data: Mapping[str, Any]) -> None:
    """Raise :class:`ConfigError` naming the new field of every old name in ``data``.

    Raises
    ------
    ConfigError
        One line: ``OLD was renamed: use NEW`` (joined by ``;`` when several are found).
    """
    found = renamed_keys(data)
    if found:
        raise ConfigError("; ".join(f"{old} was renamed: use {new}" for old, new in found))
