"""What the design search varies, and one candidate design as ``--set`` overrides.

A design fixes the cable length ``tether.length``, the attachment offset along z_B
(``vehicle.cable_attachment`` z; x and y stay the scenario's), the anchor height
``anchor.h_A`` and the hooking approach (``tether.approach_direction`` in F_A and
``tether.hook_drop``). Everything else is the scenario's. With ``mechanism.kind = "bar"``
the anchor height is the bar's ``mechanism.standoff`` as built and the approach is
straight down (:func:`tetherland.design.search.anchor_heights`); with ``"magnet"`` it is
``plate_thickness + magnet_thickness``, the approach is along the surface's normal
(:func:`tetherland.design.search.magnet_approach_A`) and only cables longer than the boom
are tried (:func:`tetherland.design.search.cable_lengths`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from tetherland.config import Scenario, with_overrides
from tetherland.errors import ConfigError
from tetherland.geometry import approach_at_elevation_A


def _check(name: str, values: Sequence[float], lo: float, hi: float, unit: str) -> None:
    if not values:
        raise ConfigError(f"design space {name}: give at least one value")
    for v in values:
        if not (math.isfinite(v) and lo <= v <= hi):
            raise ConfigError(
                f"design space {name}: {v!r} {unit} is outside the allowed range [{lo:g}, {hi:g}]"
            )


@dataclass(frozen=True)
class DesignSpace:
    """The grid of the design search and its acceptance thresholds.

    Attributes
    ----------
    lengths : tuple of float
        Cable lengths l to try, each in (0, 100] [m] (default every 2 cm from 0.2 to 0.6 m,
        where walls and overhangs are decided, then 0.7 to 1 m).
    attachment_z : tuple of float
        Attachment offsets along z_B from the centre of mass, each in [-0.5, 0.5] [m]
        (the default spans 3 cm below the CoM to the top of the hub).
    anchor_heights : tuple of float
        Anchor heights h_A above the surface, each in [0, 10] [m] (not for the bar, whose
        anchor height is its standoff, nor the magnet, whose is its plate and magnet).
    approach_elevations_deg : tuple of float
        Approach directions in the x_A-z_A plane, n_A = [-cos(e), 0, -sin(e)], each e in
        [-90, 90] [deg]: 90 lowers the hook vertically (the default approach), 0 moves
        horizontally toward the surface.
    include_normal_approach : bool
        Also try the approach along -z_S (toward the surface along its normal, e = 90 - beta).
    hook_drops : tuple of float
        Hook drops to try, ascending, each in [0, 100] [m]; only those with hook_drop +
        capture_radius < l are valid (default every 2 cm up to 1 m).
    target_clearance : float
        Clearance beyond which more does not count when ranking, in [0, 10] [m]: among
        hooking approaches that reach it the shorter hook drop is preferred. (The least
        clearance a design must keep is the scenario's ``mission.hooking.min_clearance``.)
    shortlist : int
        At most how many (length, attachment, anchor height) candidates, best landed-hover
        rotor margin first, get their landing and takeoff planned, in [1, 1000].
    max_designs : int
        How many verified designs the result lists, in [1, 1000]; planning stops once
        this many are verified.
    """

    lengths: tuple[float, ...] = (
        *(round(0.2 + 0.02 * i, 2) for i in range(21)),
        0.7,
        0.8,
        0.9,
        1.0,
    )
    attachment_z: tuple[float, ...] = (-0.03, 0.0, 0.025)
    anchor_heights: tuple[float, ...] = (0.0, 0.05, 0.1)
    approach_elevations_deg: tuple[float, ...] = (90.0, 45.0, 0.0)
    include_normal_approach: bool = True
    hook_drops: tuple[float, ...] = tuple(round(0.02 * i, 2) for i in range(51))
    target_clearance: float = 0.10
    shortlist: int = 12
    max_designs: int = 10

    def __post_init__(self) -> None:
        _check("lengths", self.lengths, 1e-6, 100.0, "m")
        _check("attachment_z", self.attachment_z, -0.5, 0.5, "m")
        _check("anchor_heights", self.anchor_heights, 0.0, 10.0, "m")
        _check("approach_elevations_deg", self.approach_elevations_deg, -90.0, 90.0, "deg")
        _check("hook_drops", self.hook_drops, 0.0, 100.0, "m")
        if list(self.hook_drops) != sorted(self.hook_drops):
            raise ConfigError("design space hook_drops: give them in ascending order")
        _check("target_clearance", (self.target_clearance,), 0.0, 10.0, "m")
        for name in ("shortlist", "max_designs"):
            value = getattr(self, name)
            if not 1 <= value <= 1000:
                raise ConfigError(f"design space {name}: {value} is outside [1, 1000]")

    def approach_directions(self, slope: float) -> tuple[tuple[float, float, float], ...]:
        """Approach directions n_A to try on a surface of slope ``slope`` [rad] (unit, F_A,
        rounded as they are written in the overrides; duplicates removed)."""
        elevations = [math.radians(e) for e in self.approach_elevations_deg]
        if self.include_normal_approach:
            elevations.append(math.pi / 2 - slope)
        out: list[tuple[float, float, float]] = []
        for e in elevations:
            n = approach_at_elevation_A(e)
            if not any(np.allclose(n, m, atol=1e-6) for m in out):
                out.append(n)
        return tuple(out)


def _fmt(v: float) -> str:
    return f"{v:.6g}"


@dataclass(frozen=True)
class DesignPoint:
    """One candidate design (SI units; the approach direction in F_A).

    Attributes
    ----------
    slope_deg : float
        Surface slope the design is for [deg].
    length : float
        Cable length l [m].
    attachment : (3,) tuple of float
        Cable attachment r_att in F_B [m] (the search varies its z).
    h_A : float
        Anchor height [m].
    approach_A : (3,) tuple of float
        Hooking approach direction in F_A [-].
    hook_drop : float
        Hook drop [m].
    """

    slope_deg: float
    length: float
    attachment: tuple[float, float, float]
    h_A: float
    approach_A: tuple[float, float, float]
    hook_drop: float

    def overrides(self) -> tuple[str, ...]:
        """``--set`` values that reproduce this design with any other command."""

        def vec(v: Sequence[float]) -> str:
            return "[" + ",".join(_fmt(x) for x in v) + "]"  # no spaces: one shell word

        return (
            f"surface.slope_deg={_fmt(self.slope_deg)}",
            f"tether.length={_fmt(self.length)}",
            f"vehicle.cable_attachment={vec(self.attachment)}",
            f"anchor.h_A={_fmt(self.h_A)}",
            f"tether.approach_direction={vec(self.approach_A)}",
            f"tether.hook_drop={_fmt(self.hook_drop)}",
        )

    def apply(self, scenario: Scenario) -> Scenario:
        """``scenario`` with this design's overrides (validated; ConfigError if invalid)."""
        return with_overrides(scenario, self.overrides())
