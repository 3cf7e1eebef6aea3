"""Fault campaigns (issue 15): one fault per run, its time drawn across the mission.

``tetherland campaign SCENARIO --faults rotor,snap,mocap,anchor,jam --runs 20`` flies
``runs`` tethered missions per fault kind on top of the usual perturbations. Fault times
are stratified over ``--fault-window`` (run i of n draws its time uniformly in the i-th of
n equal slices), so every phase of the nominal mission gets faults:

* rotor: one rotor (drawn) at a thrust factor in [0.5, 0.8] from the fault time;
* snap: the cable breaks at the fault time;
* mocap: an outage from the fault time, 0.5-3 s long;
* anchor: the believed anchor off by 5-15 cm in a uniformly drawn direction (its normal
  component kept above the believed surface); present from the start, so the phase is
  "all";
* jam: the hook does not release (it matters only at unhooking; phase "all").

Each run is classified by the phase the plant was in at the fault time (from the run's
phases) and by the judge's outcome (:func:`fault_table`).
"""

from __future__ import annotations

import math
from collections import Counter
from typing import Any

import numpy as np

from tetherland.config import FaultKind, FaultsConfig, Scenario
from tetherland.errors import ConfigError
from tetherland.geometry import LandingGeometry
from tetherland.runs.explain import phase_at

FAULT_KINDS = tuple(k.value for k in FaultKind)
"""Names accepted by ``--faults``."""
DEFAULT_WINDOW = (1.0, 72.0)
"""Default fault-time window [s]: the nominal slope50 mission, takeoff to landing."""
ROTOR_EFFICIENCY = (0.5, 0.8)
"""Range of the weak rotor's thrust factor [-]."""
OUTAGE_DURATION = (0.5, 3.0)
"""Range of the motion-capture outage length [s]."""
ANCHOR_ERROR = (0.05, 0.15)
"""Range of the anchor belief error's magnitude [m]."""


def parse_faults(text: str) -> tuple[str, ...]:
    """``"rotor,snap"`` -> ``("rotor", "snap")``, checked against :data:`FAULT_KINDS`."""
    kinds = tuple(k.strip() for k in text.split(",") if k.strip())
    bad = [k for k in kinds if k not in FAULT_KINDS]
    if bad or not kinds:
        raise ConfigError(
            f"--faults: unknown fault kind {bad or '[]'} (allowed: {', '.join(FAULT_KINDS)})"
        )
    return kinds


def parse_window(text: str) -> tuple[float, float]:
    """``"1:72"`` -> (1.0, 72.0): the fault-time window [s]."""
    try:
        start, end = (float(x) for x in text.split(":"))
    except ValueError:
        start = end = math.nan
    if not (0.0 <= start < end <= 3600.0):
        raise ConfigError(
            f"--fault-window '{text}': expected START:END in seconds with 0 <= START < END <= 3600"
        )
    return start, end


def time_slice(window: tuple[float, float], index: int, runs: int) -> tuple[float, float]:
    """The ``index``-th of ``runs`` equal slices of ``window`` [s] (stratified times)."""
    start, end = window
    width = (end - start) / runs
    return (start + index * width, start + (index + 1) * width)


def sample_fault(
    kind: str, t_range: tuple[float, float], belief: Scenario, rng: np.random.Generator
) -> FaultsConfig:
    """The ``[faults]`` of one run of fault ``kind``, its time uniform in ``t_range`` [s].

    ``belief`` is the scenario the anchor error is added to: its surface normal bounds the
    error's normal component (the believed anchor stays on or above the believed surface).
    With the magnet the error lies along the surface: the robot believes its plate
    elsewhere on the wall (a plate believed 5-15 cm thick is no plate).
    """
    t = float(rng.uniform(*t_range))
    if kind == FaultKind.ROTOR.value:
        eff = [1.0, 1.0, 1.0, 1.0]
        eff[int(rng.integers(4))] = float(rng.uniform(*ROTOR_EFFICIENCY))
        return FaultsConfig(rotor_efficiency=tuple(eff), rotor_fault_time=t)
    if kind == FaultKind.SNAP.value:
        return FaultsConfig(cable_snap_time=t)
    if kind == FaultKind.MOCAP.value:
        return FaultsConfig(
            mocap_outage_start=t, mocap_outage_duration=float(rng.uniform(*OUTAGE_DURATION))
        )
    if kind == FaultKind.ANCHOR.value:
        z_S = LandingGeometry.from_scenario(belief).surface.z_S
        u = rng.standard_normal(3)
        u /= np.linalg.norm(u)
        if u @ z_S < 0.0:  # keep the believed anchor on or above the surface
            u -= 2.0 * (u @ z_S) * z_S
        if belief.mechanism.kind == "magnet":  # the plate elsewhere on the surface
            u -= (u @ z_S) * z_S
            u /= np.linalg.norm(u)
        e = float(rng.uniform(*ANCHOR_ERROR)) * u
        return FaultsConfig(anchor_belief_error=tuple(float(x) for x in e))
    if kind == FaultKind.JAM.value:
        return FaultsConfig(hook_jam=True)
    raise ConfigError(f"unknown fault kind {kind!r} (allowed: {', '.join(FAULT_KINDS)})")


def fault_time(faults: FaultsConfig) -> float | None:
    """When the fault starts [s] (None: present all along, anchor error and hook jam)."""
    if faults.rotor_fault:
        return faults.rotor_fault_time
    if faults.cable_snap_time is not None:
        return faults.cable_snap_time
    return faults.mocap_outage_start


def fault_table(records: list[dict[str, Any]]) -> dict[str, dict[str, dict[str, int]]]:
    """Counts of fault kind -> phase at the fault time -> outcome (each run_id once)."""
    seen = {r["run_id"]: r for r in records if r.get("fault")}
    table: dict[str, dict[str, Counter[str]]] = {}
    for r in seen.values():
        kind = r["fault"]["kind"]
        phase = r["fault"].get("phase", "unknown")
        outcome = r["verdict"].get("outcome", "error") if r.get("status") == "ok" else "error"
        table.setdefault(kind, {}).setdefault(phase, Counter())[outcome] += 1
    return {k: {p: dict(c) for p, c in v.items()} for k, v in table.items()}


__all__ = [
    "DEFAULT_WINDOW",
    "FAULT_KINDS",
    "fault_table",
    "fault_time",
    "parse_faults",
    "parse_window",
    "phase_at",
    "sample_fault",
    "time_slice",
]
