"""Mission settings (chapter section 6.6, DESIGN.md section 10)."""

from __future__ import annotations

from pydantic import Field

from tetherland.config.base import Section


class MissionConfig(Section):
    """Supervisor thresholds and timing."""

    tension_threshold: float = Field(1.0, gt=0, le=1000)
    """Estimated tension that ends cable stretching (switch to tethered control) [N]."""
    tension_dwell: float = Field(0.2, ge=0, le=10)
    """Time the estimated tension must stay above the threshold [s]."""
    deploy_time: float = Field(2.0, ge=0, le=600)
    """Time on the surface with motors off, t_T - t_G [s]."""
