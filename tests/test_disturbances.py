"""Wind gusts on the plant: the summed force of the campaign's raised-cosine gusts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland.campaign.perturb import Gust
from tetherland.config import load_scenario
from tetherland.sim.disturbances import WindGusts
from tetherland.sim.plant import Plant


class _Opaque:
    """A GustLike that only offers force(t) (takes the general path)."""

    def __init__(self, gust: Gust):
        self.gust = gust

    def force(self, t: float) -> tuple[float, float]:
        return self.gust.force(t)


@pytest.fixture(scope="module")
def plant():
    return Plant(load_scenario("slope50"))


def test_gust_sum_matches_each_gusts_raised_cosine(plant):
    rng = np.random.default_rng(3)
    gusts = [
        Gust(float(t0), float(d), (float(fx), float(fy)))
        for t0, d, fx, fy in zip(rng.uniform(0, 20, 12), rng.uniform(0.2, 3, 12),
                                 rng.normal(0, 0.3, 12), rng.normal(0, 0.3, 12), strict=True)
    ]  # fmt: skip
    fast = WindGusts(plant, gusts, 0.002)
    general = WindGusts(plant, [_Opaque(g) for g in gusts], 0.002)
    for t in np.concatenate((rng.uniform(-1, 25, 400), [g.t_start for g in gusts])):
        want = np.zeros(3)
        for g in gusts:  # the profile written out: 0.5 (1 - cos(2 pi s)) on s in [0, 1]
            s = (t - g.t_start) / g.duration
            if 0.0 <= s <= 1.0:
                want[:2] += 0.5 * (1.0 - math.cos(2.0 * math.pi * s)) * np.array(g.force_W)
        np.testing.assert_allclose(fast.force_at(t), want, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(general.force_at(t), want, rtol=1e-12, atol=1e-15)


def test_gust_peaks_at_mid_duration_and_vanishes_outside(plant):
    g = Gust(2.0, 1.0, (0.4, -0.2))
    wind = WindGusts(plant, [g], 0.002)
    np.testing.assert_allclose(wind.force_at(2.5), [0.4, -0.2, 0.0], atol=1e-15)
    for t in (1.999, 3.001, 10.0):
        np.testing.assert_array_equal(wind.force_at(t), np.zeros(3))
    wind(2.5 - 0.001, plant)  # held over the next control period, evaluated mid-way
    assert wind.peak == pytest.approx(math.hypot(0.4, 0.2))


def test_the_held_force_is_written_each_tick_and_again_after_a_reset(plant):
    # calm ticks leave the (zero) force alone; a gust is written mid-period, cleared when
    # it is over, and written again after a reset zeroed MuJoCo's applied forces
    g = Gust(2.0, 1.0, (0.4, -0.2))
    wind = WindGusts(plant, [g], 0.002)
    body = plant.model.body("vehicle").id
    xfrc = plant.data.xfrc_applied
    plant.reset()
    wind(0.5, plant)
    np.testing.assert_array_equal(xfrc[body], 0.0)
    assert wind.peak == 0.0
    t = 2.3
    wind(t, plant)
    np.testing.assert_array_equal(xfrc[body, 0:3], wind.force_at(t + 0.001))
    assert np.all(xfrc[body, 0:2] != 0.0)
    plant.reset()  # mj_resetData: the applied force is gone
    np.testing.assert_array_equal(xfrc[body], 0.0)
    wind(t, plant)  # the same gust force as before the reset: written again
    np.testing.assert_array_equal(xfrc[body, 0:3], wind.force_at(t + 0.001))
    wind(5.0, plant)  # over: back to calm
    np.testing.assert_array_equal(xfrc[body], 0.0)
    k = 0.5 * (1.0 - math.cos(2.0 * math.pi * (t + 0.001 - 2.0) / 1.0))
    assert wind.peak == pytest.approx(k * math.hypot(0.4, 0.2))
