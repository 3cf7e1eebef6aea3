"""Settings of the landing/takeoff trajectory planner (DESIGN.md section 6)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from tetherland.config.base import Section


class PlannerConfig(Section):
    """The optimal planner (OCP 6.21) or the spline alternative, and the maneuver's ends."""

    method: Literal["ocp", "spline"] = "ocp"
    """Trajectory generator: the optimal control problem (6.21) or a smooth spline."""
    solver: Literal["fatrop", "ipopt"] = "fatrop"
    """NLP solver for the OCP."""
    nodes: int = Field(100, ge=10, le=2000)
    """Number of shooting intervals N [-]."""
    landing_duration: float = Field(4.0, gt=0.5, le=60)
    """Duration t_L - t_0 of the tethered landing [s]."""
    takeoff_duration: float = Field(4.0, gt=0.5, le=60)
    """Duration of the tethered takeoff [s]."""
    start_elevation_offset_deg: float = Field(35.0, gt=0, le=120)
    """Link elevation of the taut start (landing) / end (takeoff) hover above phi* [deg]."""
    start_tension: float = Field(2.0, gt=0, le=1000)
    """Cable tension held in the taut start/end hover [N]."""
    min_tension: float = Field(0.3, gt=0, le=1000)
    """Lower bound f_L_min on the tension along the planned trajectory (6.21d) [N]."""
    max_iter: int = Field(500, ge=1, le=100000)
    """Iteration limit of the NLP solver [-]."""
