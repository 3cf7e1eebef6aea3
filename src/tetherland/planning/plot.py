"""Figure of a planned maneuver: phi and theta_A, rotor thrusts, cable tension (PNG).

Uses matplotlib's object API with the Agg canvas (no display, no global pyplot state).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from tetherland.io import atomic_write_with
from tetherland.planning.maneuver import ManeuverSpec
from tetherland.planning.trajectory import Trajectory


def plan_figure(trajectory: Trajectory, spec: ManeuverSpec, title: str = "") -> Figure:
    """A 3-panel figure of ``trajectory`` with the maneuver's targets and bounds."""
    t = np.linspace(0.0, trajectory.duration, 801)
    s = trajectory.sample(t)
    fig = Figure(figsize=(8.0, 8.0), layout="constrained")
    FigureCanvasAgg(fig)
    ax_a, ax_f, ax_l = fig.subplots(3, 1, sharex=True)
    ax_a.plot(t, np.degrees(s.phi[:, 0]), label=r"$\varphi$")
    ax_a.plot(t, np.degrees(s.theta_A[:, 0]), label=r"$\vartheta_A$")
    ax_a.axhline(math.degrees(spec.phi_surface), color="C0", ls=":", lw=1, label=r"$\varphi^*$")
    ax_a.axhline(
        math.degrees(spec.theta_surface), color="C1", ls=":", lw=1, label=r"$\vartheta_A^*$"
    )
    ax_a.set_ylabel("angle [deg]")
    ax_a.legend(loc="best", ncols=2, fontsize="small")
    for i in range(4):
        ax_f.plot(t, s.thrusts[:, i], label=f"$f_{i + 1}$")
    for value, style in (
        (spec.f_min, "-"),
        (spec.f_max, "-"),
        (spec.f_lo, "--"),
        (spec.f_hi, "--"),
    ):
        ax_f.axhline(value, color="0.5", ls=style, lw=0.8)
    ax_f.set_ylabel("rotor thrust [N]")
    ax_f.legend(loc="best", ncols=4, fontsize="small")
    ax_l.plot(t, s.tension, color="C3", label="$f_L$")
    ax_l.plot(t, spec.tension_floor(t), color="0.5", ls="--", lw=0.8, label=r"$f_{L,\min}(t)$")
    ax_l.set_ylabel("tension [N]")
    ax_l.set_xlabel("time [s]")
    ax_l.legend(loc="best", fontsize="small")
    fig.suptitle(
        title or f"{trajectory.meta.scenario}: {trajectory.meta.maneuver} ({trajectory.kind})"
    )
    return fig


def save_plan_figure(
    path: str | Path, trajectory: Trajectory, spec: ManeuverSpec, title: str = ""
) -> Path:
    """Write :func:`plan_figure` as a PNG to ``path`` atomically."""
    fig = plan_figure(trajectory, spec, title)
    return atomic_write_with(path, lambda tmp: fig.savefig(tmp, dpi=110))
