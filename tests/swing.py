"""Test helper: the swing a leg of the reference leaves a hanging hook (an undamped
pendulum at rest under the pivot), against the zero-vibration shaper's prediction."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland.mission.paths import smoothstep_residual


def assert_legs_leave_the_shaped_swing(
    t: np.ndarray, a_h: np.ndarray, legs: list[tuple[float, float, float, float]],
    period: float, dt: float,
) -> None:  # fmt: skip
    """Each leg (start, duration, unshaped duration T, horizontal length D_h) [s, s, s,
    m] of the traced horizontal reference acceleration ``a_h`` (ticks ``t``, ``dt``
    apart) leaves a pendulum of true period P' the swing the shaper at ``period`` P
    predicts: |cos(pi P / (2 P'))| D_h r(T / P'), r the smoothstep's velocity spectrum
    (:func:`smoothstep_residual`), to 2e-5 m; at P' = P, 0.99 P and 1.01 P."""
    for P_true in (period, 1.01 * period, 0.99 * period):
        w = 2.0 * math.pi / P_true
        ratio = abs(math.cos(0.5 * math.pi * period / P_true))
        for t0, duration, T, D_h in legs:
            k = (t >= t0 - 0.5 * dt) & (t <= t0 + duration + 0.5 * dt)
            # x'' + w^2 x = -a_h from rest: the swing left is |int a_h e^{-iwt} dt| / w
            z = np.trapezoid(a_h[k] * np.exp(-1j * w * t[k])[:, None], dx=dt, axis=0) / w
            residual = float(np.linalg.norm(np.abs(z)))
            expected = ratio * D_h * smoothstep_residual(T / P_true)
            assert residual == pytest.approx(expected, abs=2e-5), (P_true / period, t0, D_h)
