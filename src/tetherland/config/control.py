"""Controller settings (DESIGN.md section 7)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from tetherland.config.base import Section


class ControllerConfig(Section):
    """Which tethered controller runs, and its rate."""

    kind: Literal["hierarchical", "dfl"] = "hierarchical"
    """Tethered controller: hierarchical Gamma_HC^b or dynamic feedback linearisation."""
    rate_hz: float = Field(500.0, gt=0, le=5000)
    """Control rate (rotor-speed commands to the ESCs, section 6.6.4) [Hz]."""
