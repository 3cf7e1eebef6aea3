"""Test helper: the vehicle moved by prescribed positions (open loop)."""

from __future__ import annotations

import itertools
from collections.abc import Callable

import numpy as np

from tetherland.sim.plant import Plant


def drive(plant: Plant, points: list[np.ndarray], speed: float, hold: float,
          each: Callable[[Plant], None] | None = None,
          q_WB: np.ndarray | None = None) -> None:  # fmt: skip
    """Move the vehicle's centre of mass through ``points`` at ``speed`` (position and
    velocity written every physics step, attitude ``q_WB``, default the current one), then
    hold the last point for ``hold`` seconds; ``each(plant)`` after every step [m, m/s, s]."""
    d = plant.data
    q0 = d.qpos[3:7].copy() if q_WB is None else np.asarray(q_WB, dtype=float)
    for a, b in itertools.pairwise(points):
        n = max(1, round(float(np.linalg.norm(b - a)) / speed / plant.dt))
        v = (b - a) / (n * plant.dt)
        for i in range(n):
            d.qpos[0:3], d.qpos[3:7] = a + (i + 1) / n * (b - a), q0
            d.qvel[0:3], d.qvel[3:6] = v, 0.0
            plant.step(1)
            if each is not None:
                each(plant)
    for _ in range(round(hold / plant.dt)):
        d.qpos[0:3], d.qpos[3:7], d.qvel[0:6] = points[-1], q0, 0.0
        plant.step(1)
        if each is not None:
            each(plant)
