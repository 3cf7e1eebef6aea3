"""Physics simulation settings (DESIGN.md section 9)."""

from __future__ import annotations

from pydantic import Field

from tetherland.config.base import Section


class SimConfig(Section):
    """MuJoCo plant settings."""

    timestep: float = Field(0.001, gt=0, le=0.005)
    """Physics time step [s]."""
