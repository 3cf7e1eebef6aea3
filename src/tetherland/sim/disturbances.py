"""External disturbances applied to the plant: wind gusts (issue 7 perturbations)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import mujoco
import numpy as np

from tetherland.sim.plant import Plant


class GustLike(Protocol):
    def force(self, t: float) -> tuple[float, float]: ...


class WindGusts:
    """Applies horizontal gust forces to the vehicle; use it as a runner observer.

    After each control tick it sets the force for the next control period (zero-order
    hold at the control rate) in ``xfrc_applied``, so the IMU senses it like real wind.

    Parameters
    ----------
    plant : Plant
    gusts : sequence of objects with ``force(t) -> (f_x, f_y)`` [N]
    period : float
        Control period: the force is held over [t, t + period) and evaluated mid-way [s].
    """

    def __init__(self, plant: Plant, gusts: Sequence[GustLike], period: float):
        self.gusts = tuple(gusts)
        self.period = period
        self._body = mujoco.mj_name2id(plant.model, mujoco.mjtObj.mjOBJ_BODY, "vehicle")
        self._xfrc = plant.data.xfrc_applied
        self.peak = 0.0

    def force_at(self, t: float) -> np.ndarray:
        """Total gust force at time ``t`` in F_W [N]."""
        fx = fy = 0.0
        for g in self.gusts:
            gx, gy = g.force(t)
            fx += gx
            fy += gy
        return np.array([fx, fy, 0.0])

    def __call__(self, t: float, plant: Plant) -> None:
        f = self.force_at(t + 0.5 * self.period)
        self._xfrc[self._body, 0:3] = f
        self.peak = max(self.peak, float(np.hypot(f[0], f[1])))
