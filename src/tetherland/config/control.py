"""Controller settings (DESIGN.md section 7).

Gains are given as natural frequencies and damping ratios of the closed-loop error
dynamics (mass and inertia are taken from the vehicle), so they stay meaningful when the
vehicle changes.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from tetherland.config.base import Section


class FreeFlightGains(Section):
    """Geometric position and SO(3) attitude control (Lee, Leok, McClamroch 2010)."""

    position_frequency: float = Field(2.5, gt=0, le=50)
    """Natural frequency of the position error dynamics [rad/s]."""
    position_damping: float = Field(1.0, gt=0, le=5)
    """Damping ratio of the position error dynamics [-]."""
    attitude_frequency: float = Field(14.0, gt=0, le=200)
    """Natural frequency of the roll/pitch attitude error dynamics [rad/s]."""
    attitude_damping: float = Field(0.9, gt=0, le=5)
    """Damping ratio of the roll/pitch attitude error dynamics [-]."""
    yaw_frequency: float = Field(5.0, gt=0, le=200)
    """Natural frequency of the yaw error dynamics [rad/s]."""
    yaw_damping: float = Field(1.0, gt=0, le=5)
    """Damping ratio of the yaw error dynamics [-]."""
    max_tilt_deg: float = Field(60.0, gt=0, lt=90)
    """Largest commanded tilt of the thrust axis from vertical in free flight [deg]."""


class ControllerConfig(Section):
    """Which tethered controller runs, its rate and the gains."""

    kind: Literal["hierarchical", "dfl"] = "hierarchical"
    """Tethered controller: hierarchical Gamma_HC^b or dynamic feedback linearisation."""
    rate_hz: float = Field(500.0, gt=0, le=5000)
    """Control rate (rotor-speed commands to the ESCs, section 6.6.4) [Hz]."""
    free_flight: FreeFlightGains = FreeFlightGains()
    """Free-flight gains."""
