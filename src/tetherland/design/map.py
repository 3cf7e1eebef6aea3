"""Feasibility map of a vehicle: slope against cable length, and the steepest slope.

Each cell (slope, cable length) holds the best design of :func:`search_designs` with
that length (attachment offset, anchor height and hooking approach searched): its rotor
margin over the planned landing and takeoff, or why there is none.
"""

from __future__ import annotations

import csv
import io
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from tetherland.config import Scenario
from tetherland.design.search import (
    DesignResult,
    design_base,
    landed_slope_limit,
    search_designs,
)
from tetherland.design.space import DesignSpace
from tetherland.geometry import FloatArray
from tetherland.planning import Planner

MAP_SLOPES_DEG: tuple[float, ...] = tuple(float(b) for b in range(0, 181, 5))
"""Default slopes of the map [deg]."""
MAP_LENGTHS: tuple[float, ...] = (0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5, 0.55, 0.6, 0.8, 1.0)
"""Default cable lengths of the map [m]."""
CELL_SHORTLIST = 3
"""Candidates planned at most per map cell, best landed-hover margin first, until one is
verified."""


@dataclass(frozen=True)
class MapCell:
    """One (slope, cable length) of the map.

    Attributes
    ----------
    slope_deg, length : float
        [deg], [m].
    plan_margin : float
        Rotor margin over the planned maneuvers of the cell's best design [N]; NaN if none.
    landed_margin : float
        Best landed-hover rotor margin of the analysis for this length [N]; NaN if none.
    binding : str or None
        Why no design exists (see :attr:`DesignResult.binding`); None when one does.
    overrides : tuple of str
        The cell's best design (empty when none).
    """

    slope_deg: float
    length: float
    plan_margin: float
    landed_margin: float
    binding: str | None
    overrides: tuple[str, ...]

    @classmethod
    def from_result(cls, length: float, result: DesignResult) -> MapCell:
        best = result.chosen
        return cls(
            slope_deg=result.slope_deg,
            length=length,
            plan_margin=math.nan if best is None else best.min_rotor_margin,
            landed_margin=math.nan if result.landed_margin is None else result.landed_margin,
            binding=result.binding,
            overrides=() if best is None else best.overrides,
        )


@dataclass(frozen=True)
class SteepestSlope:
    """The steepest slope for one cable length.

    Attributes
    ----------
    length : float
        [m].
    landed_slope_deg : float or None
        Bound of the analysis: steepest slope whose landed hover is feasible [deg].
    landed_binding : str or None
        What binds beyond it (an :class:`~tetherland.analysis.Infeasibility` value).
    slope_deg : float or None
        Steepest slope with a design verified by hooking clearance and planning, within
        ``tol_deg`` [deg] (None: none at any slope tried).
    binding : str or None
        What binds just beyond ``slope_deg``.
    """

    length: float
    landed_slope_deg: float | None
    landed_binding: str | None
    slope_deg: float | None
    binding: str | None


@dataclass(frozen=True)
class FeasibilityMap:
    """The map and the steepest slopes of one vehicle (see :func:`feasibility_map`)."""

    scenario: str
    slopes_deg: tuple[float, ...]
    lengths: tuple[float, ...]
    cells: tuple[MapCell, ...]
    steepest: tuple[SteepestSlope, ...]
    wall_time_s: float

    def grid(self, name: str) -> FloatArray:
        """A cell field (``plan_margin`` or ``landed_margin``) as (lengths, slopes) [N]."""
        out = np.full((len(self.lengths), len(self.slopes_deg)), math.nan)
        for cell in self.cells:
            i = self.lengths.index(cell.length)
            j = self.slopes_deg.index(cell.slope_deg)
            out[i, j] = getattr(cell, name)
        return out

    def to_dict(self) -> dict[str, Any]:
        return {
            "scenario": self.scenario,
            "slopes_deg": list(self.slopes_deg),
            "lengths_m": list(self.lengths),
            "cells": [
                {
                    "slope_deg": c.slope_deg,
                    "length_m": c.length,
                    "plan_rotor_margin_N": c.plan_margin,
                    "landed_rotor_margin_N": c.landed_margin,
                    "binding": c.binding,
                    "overrides": list(c.overrides),
                }
                for c in self.cells
            ],
            "steepest": [
                {
                    "length_m": s.length,
                    "landed_slope_deg": s.landed_slope_deg,
                    "landed_binding": s.landed_binding,
                    "slope_deg": s.slope_deg,
                    "binding": s.binding,
                }
                for s in self.steepest
            ],
            "wall_time_s": self.wall_time_s,
        }

    def to_csv(self) -> str:
        """One row per cell; NaN margins are empty fields."""
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow(
            ["slope_deg", "length_m", "plan_rotor_margin_N", "landed_rotor_margin_N", "binding"]
        )
        for c in self.cells:
            writer.writerow(
                [
                    f"{c.slope_deg:g}",
                    f"{c.length:g}",
                    "" if math.isnan(c.plan_margin) else f"{c.plan_margin:.6f}",
                    "" if math.isnan(c.landed_margin) else f"{c.landed_margin:.6f}",
                    c.binding or "",
                ]
            )
        return buf.getvalue()


def _cell_space(space: DesignSpace, length: float) -> DesignSpace:
    """``space`` with only this cable length, planning few candidates, keeping the best."""
    return replace(
        space, lengths=(length,), shortlist=min(space.shortlist, CELL_SHORTLIST), max_designs=1
    )


def steepest_slope(
    scenario: Scenario,
    length: float,
    space: DesignSpace | None = None,
    planner: Planner | None = None,
    tol_deg: float = 0.25,
) -> SteepestSlope:
    """Steepest slope with a verified design for cable ``length`` [m].

    Starts at the analysis bound (:func:`landed_slope_limit`), steps down 5 deg at a
    time until a design exists, then bisects to ``tol_deg``.
    """
    space = _cell_space(space or DesignSpace(), length)
    planner = planner or Planner()
    limit = landed_slope_limit(scenario, length, space)
    if limit.max_slope_rad is None:
        return SteepestSlope(length, None, None, None, None)
    bound = math.degrees(limit.max_slope_rad)
    landed_binding = None if limit.binding is None else limit.binding.value

    def search(slope: float) -> DesignResult:
        return search_designs(scenario, slope, space, planner)

    hi = math.floor(bound * 100.0) / 100.0  # the analysis says feasible up to here
    top = search(hi)
    if top.feasible:
        beyond = search(min(hi + tol_deg, 180.0)) if hi < 180.0 else None
        return SteepestSlope(
            length, bound, landed_binding, hi, None if beyond is None else beyond.binding
        )
    lo, failed = None, top
    for step in range(1, 37):
        trial = hi - 5.0 * step
        if trial < 0.0:
            break
        if search(trial).feasible:
            lo = trial
            break
    if lo is None:
        return SteepestSlope(length, bound, landed_binding, None, top.binding)
    while hi - lo > tol_deg:
        mid = 0.5 * (lo + hi)
        result = search(mid)
        if result.feasible:
            lo = mid
        else:
            hi, failed = mid, result
    return SteepestSlope(length, bound, landed_binding, lo, failed.binding)


def feasibility_map(
    scenario: Scenario,
    space: DesignSpace | None = None,
    planner: Planner | None = None,
    slopes_deg: Sequence[float] = MAP_SLOPES_DEG,
    lengths: Sequence[float] = MAP_LENGTHS,
) -> FeasibilityMap:
    """Best design per (slope, cable length) and the steepest slope per length.

    Parameters
    ----------
    scenario : Scenario
        The vehicle and the surface kind (its slope is replaced by each of ``slopes_deg``).
    space : DesignSpace, optional
        Attachment offsets, anchor heights and hooking approaches searched per cell.
    slopes_deg, lengths : sequences of float
        Map axes [deg], [m].
    """
    t0 = time.perf_counter()
    space = space or DesignSpace()
    planner = planner or Planner()
    base = design_base(scenario)
    cells = []
    for length in lengths:
        cell_space = _cell_space(space, length)
        for slope in slopes_deg:
            result = search_designs(base, slope, cell_space, planner)
            cells.append(MapCell.from_result(float(length), result))
    steepest = tuple(steepest_slope(base, float(length), space, planner) for length in lengths)
    return FeasibilityMap(
        scenario=base.name,
        slopes_deg=tuple(float(b) for b in slopes_deg),
        lengths=tuple(float(length) for length in lengths),
        cells=tuple(cells),
        steepest=steepest,
        wall_time_s=time.perf_counter() - t0,
    )
