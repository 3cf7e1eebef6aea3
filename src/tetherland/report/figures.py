"""Figures of a mission: figure 6.5 of the chapter, and the flown path in 3D.

Figure 6.5 shows, over the tethered part of the mission, the link angles phi and delta,
the robot angles (roll varphi, theta_A, psi), the rotor thrusts f_1..f_4 and the cable
tension f_L, each as desired (the supervisor's reference, superscript d), nominal (the
planner's trajectory through the flatness map, superscript n) and actual (the plant's
truth), with the phases shaded and t_L, t_G, t_T marked.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Protocol

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from tetherland.config import Scenario
from tetherland.geometry import FloatArray, LandingGeometry, theta_A_from_z_B_many
from tetherland.io import atomic_write_with
from tetherland.mission.phases import Phase
from tetherland.models.flatness import FlatnessMap
from tetherland.rotations import quat_to_rotmat, quat_to_rotmat_many, quat_to_rotmat_stack
from tetherland.sim.log import SimLog
from tetherland.verdict.record import RunRecord


class MissionResult(Protocol):
    """What the figures read of a run (:class:`tetherland.runs.RunResult` provides it)."""

    log: SimLog
    record: RunRecord
    plan: Any
    plant_scenario: Scenario
    belief_scenario: Scenario

    @property
    def summary(self) -> dict[str, Any]: ...

_TETHERED = (Phase.TETHERED_LANDING, Phase.TOUCHDOWN, Phase.MOTORS_OFF, Phase.SPIN_UP,
             Phase.TETHERED_TAKEOFF)  # fmt: skip
_PHASE_COLORS = {
    Phase.TETHERED_LANDING.name.lower(): "#dbe9f6",
    Phase.TOUCHDOWN.name.lower(): "#e5f5e0",
    Phase.MOTORS_OFF.name.lower(): "#f0f0f0",
    Phase.SPIN_UP.name.lower(): "#fdebd2",
    Phase.TETHERED_TAKEOFF.name.lower(): "#f3e0f7",
}


def robot_angles(q_WB: FloatArray, R_WA: FloatArray, phi: FloatArray, delta: FloatArray):
    """(roll, theta_A, psi) of each attitude, for R_AB = R_y(theta_e) R_x(roll) R_z(psi) [rad].

    Vectorised over the n attitudes where numpy gives the bits of the per-attitude
    computation (products, the stacked 3 x 3 matmuls); the angles from ``math`` per
    attitude (numpy's vectorised trigonometry may differ in the last bit).
    """
    R_AB = np.asarray(R_WA, dtype=float).T @ quat_to_rotmat_stack(q_WB)
    z = R_AB[:, :, 2]
    z0, z2 = z[:, 0].tolist(), z[:, 2].tolist()
    th_e = list(map(math.atan2, z0, z2))
    roll = list(map(math.atan2, (-z[:, 1]).tolist(), map(math.hypot, z0, z2)))
    c_t, s_t = np.array(list(map(math.cos, th_e))), np.array(list(map(math.sin, th_e)))
    c_r, s_r = np.array(list(map(math.cos, roll))), np.array(list(map(math.sin, roll)))
    M = np.empty_like(R_AB)
    M[:, 0, 0], M[:, 0, 1], M[:, 0, 2] = c_t, s_t * s_r, s_t * c_r
    M[:, 1, 0], M[:, 1, 1], M[:, 1, 2] = 0.0, c_r, -s_r
    M[:, 2, 0], M[:, 2, 1], M[:, 2, 2] = -s_t, c_t * s_r, c_t * c_r
    Rz = M.transpose(0, 2, 1) @ R_AB
    psi = list(map(math.atan2, Rz[:, 1, 0].tolist(), Rz[:, 0, 0].tolist()))
    theta = theta_A_from_z_B_many(z, phi, delta)
    return np.array(roll, dtype=float), theta, np.array(psi, dtype=float)


def nominal_series(result: MissionResult, t: FloatArray) -> dict[str, FloatArray]:
    """The planned (nominal) values at mission times ``t``: NaN outside the planned maneuvers.

    Rotor thrusts include the cancellation of the cable-offset torque (6.6.5), as flown.
    """
    times, plan = result.record.times, result.plan
    n = len(t)
    out = {k: np.full(n, math.nan) for k in ("phi", "theta_A", "tension")}
    out["rotors"] = np.full((n, 4), math.nan)
    fmap = FlatnessMap.from_scenario(result.belief_scenario, with_cable_offset=True)
    spans = []
    if "t_tethered" in times:
        spans.append((plan.landing_trajectory, times["t_tethered"], times.get("t_L", t[-1])))
    if "t_T" in times:
        t0 = times["t_T"] + result.belief_scenario.mission.spinup_time
        spans.append((plan.takeoff_trajectory, t0, times.get("t_released", t[-1])))
    for traj, t0, t1 in spans:
        mask = (t >= t0) & (t <= t1)
        if not mask.any():
            continue
        s = traj.sample(t[mask] - t0)
        nominal = fmap.evaluate_many(s.outputs(), check=False)
        out["phi"][mask] = s.phi[:, 0]
        out["theta_A"][mask] = s.theta_A[:, 0]
        out["tension"][mask] = s.tension
        out["rotors"][mask] = nominal["rotor_thrusts"]
    return out


def _mark(ax, result: MissionResult, t0: float, t1: float) -> None:
    for r in result.record.phases:
        color = _PHASE_COLORS.get(r.name)
        if color is not None and r.end > t0 and r.start < t1:
            ax.axvspan(max(r.start, t0), min(r.end, t1), color=color, lw=0)
    for name in ("t_L", "t_G", "t_T"):
        tt = result.record.times.get(name)
        if tt is not None and t0 <= tt <= t1:
            ax.axvline(tt, color="k", lw=0.7, ls=":")
            ax.text(tt, 1.0, f" {name}", transform=ax.get_xaxis_transform(), fontsize=7, va="top")


def figure_6_5(result: MissionResult) -> Figure:
    """The chapter's figure 6.5 for a run (tethered part: landing, deploy, takeoff)."""
    log = result.log
    t = log["t"]
    phase = log["phase"].astype(int)
    sel = np.isin(phase, [int(p) for p in _TETHERED])
    fig, axes = plt.subplots(4, 2, figsize=(11, 10), sharex=True)
    axes = axes.ravel()
    if not sel.any():
        axes[0].text(
            0.5, 0.5, "no tethered flight in this run", ha="center", transform=axes[0].transAxes
        )
        return fig
    idx = np.flatnonzero(sel)
    k0, k1 = max(idx[0] - 100, 0), min(idx[-1] + 100, len(t) - 1)
    tt = t[k0 : k1 + 1]
    geo = LandingGeometry.from_scenario(result.plant_scenario)
    phi, delta = log["link_phi"][k0 : k1 + 1], log["link_delta"][k0 : k1 + 1]
    roll, theta, psi = robot_angles(log["q_WB"][k0 : k1 + 1], geo.R_WA, phi, delta)
    ref = log["ref_output"][k0 : k1 + 1]
    nom = nominal_series(result, tt)
    deg = np.degrees
    series = [
        ("$\\varphi$ [deg]", deg(phi), deg(ref[:, 0]), deg(nom["phi"])),
        ("$\\delta$ [deg]", deg(delta), deg(ref[:, 1]), None),
        ("roll $\\phi$ [deg]", deg(roll), None, None),
        ("$\\psi$ [deg]", deg(psi), deg(ref[:, 3]), None),
        ("$\\vartheta_A$ [deg]", deg(theta), deg(ref[:, 2]), deg(nom["theta_A"])),
        ("tension $f_L$ [N]", log["tension"][k0 : k1 + 1], None, nom["tension"]),
    ]
    for ax, (label, actual, desired, nominal) in zip(axes[:6], series, strict=True):
        _mark(ax, result, tt[0], tt[-1])
        if desired is not None:
            ax.plot(tt, desired, "C1--", lw=1.2, label="desired $^d$")
        if nominal is not None:
            ax.plot(tt, nominal, "C2:", lw=1.5, label="nominal $^n$")
        ax.plot(tt, actual, "C0-", lw=1.0, label="actual")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, loc="best")
    ax = axes[6]
    _mark(ax, result, tt[0], tt[-1])
    thrusts = log["rotor_thrusts"][k0 : k1 + 1]
    for i in range(4):
        ax.plot(tt, thrusts[:, i], f"C{i}-", lw=1.0, label=f"$f_{i + 1}$")
        ax.plot(tt, nom["rotors"][:, i], f"C{i}:", lw=1.3)
    v = result.plant_scenario.vehicle
    ax.axhline(v.f_min, color="gray", lw=0.6)
    ax.set_ylabel("rotor thrust [N] (dotted: nominal)")
    ax.legend(fontsize=7, ncol=4)
    ax.grid(alpha=0.3)
    ax = axes[7]
    _mark(ax, result, tt[0], tt[-1])
    z_B = quat_to_rotmat_many(log["q_WB"][k0 : k1 + 1])[:, :, 2]
    p_RL = log["p_W"][k0 : k1 + 1] - geo.h_R * z_B
    ax.plot(tt, 100 * ((p_RL - geo.surface.origin) @ geo.surface.z_S), "C0-", lw=1.0)
    ax.set_ylabel("landers clearance [cm]")
    ax.grid(alpha=0.3)
    for a in axes[6:]:
        a.set_xlabel("time [s]")
    s = result.summary
    fig.suptitle(
        f"{result.plant_scenario.name}: tethered landing and takeoff "
        f"({result.record.controller}, seed {result.record.seed}, "
        f"{'success' if s.get('success') else 'failure'})"
    )
    fig.tight_layout()
    return fig


def figure_path(result: MissionResult) -> Figure:
    """The flown path (truth) in 3D with the surface patch, anchor, landing point and cable."""
    log = result.log
    sc = result.plant_scenario
    geo = LandingGeometry.from_scenario(sc)
    s = geo.surface
    fig = plt.figure(figsize=(8, 7))
    ax = fig.add_subplot(projection="3d")
    e = min(sc.surface.extent, 2.0 * sc.tether.length + 1.0)
    u, w = np.meshgrid(np.linspace(-e, e, 2), np.linspace(-e, e, 2))
    patch = s.origin[:, None, None] + s.x_S[:, None, None] * u + s.y_S[:, None, None] * w
    ax.plot_surface(*patch, color="tan", alpha=0.35, linewidth=0)
    p = log["p_W"]
    phase = log["phase"].astype(int)
    tethered = np.isin(phase, [int(q) for q in _TETHERED])
    ax.plot(*p.T, color="C0", lw=1.0, label="path (free flight)")
    pt = np.where(tethered[:, None], p, np.nan)
    ax.plot(*pt.T, color="C3", lw=1.6, label="path (tethered)")
    ax.scatter(*geo.p_A, color="k", s=30, label="anchor $p_A$")
    ax.scatter(*geo.p_L, color="C2", s=30, marker="x", label="landing point $p^*_L$")
    ax.scatter(*p[0], color="C1", s=20, label="start pad")
    r_att = np.asarray(sc.vehicle.cable_attachment)
    engaged = np.flatnonzero(log["hook"] == 1)
    for k in engaged[:: max(len(engaged) // 12, 1)]:
        att = p[k] + quat_to_rotmat(log["q_WB"][k]) @ r_att
        ax.plot(*np.column_stack((geo.p_A, att)), color="gray", lw=0.6)
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_zlabel("z [m]")
    lo, hi = np.nanmin(p, axis=0), np.nanmax(p, axis=0)
    c, r = (lo + hi) / 2, max(float(np.max(hi - lo)) / 2, 0.5)
    ax.set_xlim(c[0] - r, c[0] + r)
    ax.set_ylim(c[1] - r, c[1] + r)
    ax.set_zlim(c[2] - r, c[2] + r)
    ax.view_init(elev=18, azim=-70)
    ax.legend(fontsize=8, loc="upper left")
    ax.set_title(f"{sc.name}: mission path ({sc.surface.kind}, {sc.surface.slope_deg:g} deg)")
    return fig


def save_figures(result: MissionResult, directory: str | Path) -> list[Path]:
    """Write ``figure_6_5.png`` and ``path_3d.png`` into ``directory`` (atomically)."""
    directory = Path(directory)
    out = []
    for name, make in (("figure_6_5.png", figure_6_5), ("path_3d.png", figure_path)):
        fig = make(result)
        out.append(atomic_write_with(directory / name, lambda p, f=fig: f.savefig(p, dpi=110)))
        plt.close(fig)
    return out
