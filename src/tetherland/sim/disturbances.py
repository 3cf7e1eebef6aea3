"""External disturbances applied to the plant: wind gusts (issue 7 perturbations)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Protocol

import mujoco
import numpy as np

from tetherland.sim.plant import Plant

_CALM = [0.0, 0.0, 0.0]


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
        self._xfrc_row = plant.data.xfrc_applied[self._body, 0:3]  # the vehicle's, F_W [N]
        self.peak = 0.0
        # raised-cosine gusts (campaign.perturb.Gust) as plain tuples sorted by start,
        # so that a tick skips the gusts that are over or still to come with two
        # comparisons; any other GustLike is asked through its force(t)
        windows = [
            (float(g.t_start), float(g.duration), float(g.force_W[0]), float(g.force_W[1]))
            for g in self.gusts
            if all(hasattr(g, a) for a in ("t_start", "duration", "force_W"))
        ]
        self._windows = sorted(windows) if len(windows) == len(self.gusts) else None

    def force_at(self, t: float) -> np.ndarray:
        """Total gust force at time ``t`` in F_W [N]."""
        fx, fy = self._force_xy(t)
        return np.array([fx, fy, 0.0])

    def _force_xy(self, t: float) -> tuple[float, float]:
        """The horizontal components of :meth:`force_at` [N]."""
        fx = fy = 0.0
        if self._windows is None:
            for g in self.gusts:
                gx, gy = g.force(t)
                fx += gx
                fy += gy
            return fx, fy
        for t_start, duration, peak_x, peak_y in self._windows:
            if t < t_start:
                break  # sorted by start: the rest are still to come
            s = (t - t_start) / duration
            if s <= 1.0:  # the raised cosine of Gust.force
                k = 0.5 * (1.0 - math.cos(2.0 * math.pi * s))
                fx += k * peak_x
                fy += k * peak_y
        return fx, fy

    def __call__(self, t: float, plant: Plant) -> None:
        fx, fy = self._force_xy(t + 0.5 * self.period)
        row = self._xfrc_row
        # (calm and calm before, the usual tick: nothing to write; the sums start at +0.0,
        # so a zero force is never -0.0 and equality keeps the bits)
        if fx != 0.0 or fy != 0.0 or row.tolist() != _CALM:
            row[:] = (fx, fy, 0.0)
            if fx != 0.0 or fy != 0.0:
                self.peak = max(self.peak, float(np.hypot(fx, fy)))
