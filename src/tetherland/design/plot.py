"""Figure of a feasibility map: slope against cable length, coloured by the rotor margin.

Uses matplotlib's object API with the Agg canvas (no display, no global pyplot state).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from tetherland.design.map import FeasibilityMap
from tetherland.design.search import Design
from tetherland.geometry import FloatArray
from tetherland.io import atomic_write_with


def _edges(centres: tuple[float, ...]) -> FloatArray:
    c = np.asarray(centres, dtype=float)
    if c.size == 1:
        return np.array([c[0] - 0.5, c[0] + 0.5])
    mid = 0.5 * (c[1:] + c[:-1])
    return np.concatenate(([2 * c[0] - mid[0]], mid, [2 * c[-1] - mid[-1]]))


def map_figure(fmap: FeasibilityMap, chosen: Design | None = None, title: str = "") -> Figure:
    """Cells coloured by the rotor margin over the planned maneuvers (grey: no design),
    the analysis bound and the verified steepest slope per length, the chosen design."""
    fig = Figure(figsize=(7.0, 4.2), layout="constrained")
    FigureCanvasAgg(fig)
    ax = fig.subplots()
    ax.set_facecolor("0.85")
    margin = np.ma.masked_invalid(fmap.grid("plan_margin"))
    mesh = ax.pcolormesh(
        _edges(fmap.slopes_deg), _edges(fmap.lengths), margin, cmap="viridis", vmin=0.0,
        shading="flat",
    )  # fmt: skip
    fig.colorbar(mesh, ax=ax, label="min rotor margin, landing + takeoff [N]")
    lengths = [s.length for s in fmap.steepest]
    bound = [np.nan if s.landed_slope_deg is None else s.landed_slope_deg for s in fmap.steepest]
    verified = [np.nan if s.slope_deg is None else s.slope_deg for s in fmap.steepest]
    ax.plot(bound, lengths, "w--", lw=1.2, label="landed hover limit (analysis)")
    ax.plot(verified, lengths, "o-", color="tab:red", ms=4, lw=1.2,
            label="steepest verified (hooking + plan)")  # fmt: skip
    if chosen is not None:
        ax.plot(chosen.point.slope_deg, chosen.point.length, "*", color="gold", ms=16,
                mec="k", label="chosen design")  # fmt: skip
    ax.axvline(90.0, color="k", lw=0.6, ls=":")
    ax.set_xlabel("slope [deg] (90: wall, > 90: overhang)")
    ax.set_ylabel("cable length [m]")
    ax.set_xlim(fmap.slopes_deg[0], fmap.slopes_deg[-1])
    ax.legend(loc="upper right", fontsize="small", framealpha=0.9)
    ax.set_title(title or f"{fmap.scenario}: tethered landing feasibility", fontsize="medium")
    return fig


def save_map_figure(
    path: str | Path, fmap: FeasibilityMap, chosen: Design | None = None, title: str = ""
) -> Path:
    """Write :func:`map_figure` as a PNG to ``path`` atomically."""
    fig = map_figure(fmap, chosen, title)
    return atomic_write_with(path, lambda tmp: fig.savefig(tmp, dpi=100))
