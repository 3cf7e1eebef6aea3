"""One seeded random source per run, with named streams that do not move each other."""

from __future__ import annotations

import numpy as np
import pytest

from tetherland.campaign.faults import sample_fault
from tetherland.campaign.perturb import apply_perturbation, sample_perturbation
from tetherland.campaign.spec import CampaignSpec
from tetherland.config import load_scenario, with_overrides
from tetherland.randomness import STREAMS, RandomSource, derive_seed


def test_every_stream_has_its_own_fixed_key():
    assert len(set(STREAMS.values())) == len(STREAMS)
    assert {"imu", "mocap", "perturbation", "wind", "faults"} <= set(STREAMS)
    source = RandomSource(7)
    for name, key in STREAMS.items():
        assert source.seed_sequence(name).spawn_key == (key,)
        assert source.seed_sequence(name).entropy == 7


def test_a_stream_is_the_same_every_time_and_differs_from_the_others():
    source = RandomSource(2026)
    draws = {name: source.stream(name).random(8) for name in STREAMS}
    for name in STREAMS:
        np.testing.assert_array_equal(source.stream(name).random(8), draws[name])
        np.testing.assert_array_equal(RandomSource(2026).stream(name).random(8), draws[name])
        assert not np.array_equal(RandomSource(2027).stream(name).random(8), draws[name])
    values = np.concatenate(list(draws.values()))
    assert len(np.unique(values)) == len(values)


def test_the_sensor_streams_are_the_noise_of_a_seed_from_before_the_names():
    """default_rng(seed).spawn(2) gave the IMU and motion capture their generators."""
    for seed in (0, 5, 3556918803):
        imu, mocap = np.random.default_rng(seed).spawn(2)
        source = RandomSource(seed)
        np.testing.assert_array_equal(source.stream("imu").random(16), imu.random(16))
        np.testing.assert_array_equal(source.stream("mocap").random(16), mocap.random(16))


def test_drawing_more_from_one_stream_moves_no_other():
    """More gusts (a higher gust rate) leave the model errors of a seed as they were, and
    the fault stream does not depend on the perturbation's draws."""
    truth = load_scenario("slope50")
    windy = with_overrides(truth, ["perturbation.wind_gust_rate=5.0"])
    calm = with_overrides(truth, ["perturbation.wind_gust_rate=0.0"])
    source = RandomSource(41)
    a, b, c = (sample_perturbation(s, source) for s in (truth, windy, calm))
    assert len(b.gusts) > 5 * len(a.gusts) > 0 and c.gusts == ()
    for p in (b, c):
        assert p.mass_factor == a.mass_factor and p.anchor_error_S == a.anchor_error_S
        assert p.slope_error_deg == a.slope_error_deg and p.noise_scale == a.noise_scale
    _, belief = apply_perturbation(truth, a)
    f1 = sample_fault("rotor", (1.0, 72.0), belief, source.stream("faults"))
    f2 = sample_fault("rotor", (1.0, 72.0), truth, RandomSource(41).stream("faults"))
    assert f1 == f2


def test_bad_seeds_and_stream_names_are_refused():
    for bad in (-1, 1.5, True):
        with pytest.raises(ValueError, match="seed"):
            RandomSource(bad)
    with pytest.raises(ValueError, match=r"unknown random stream 'noise'.*imu, mocap"):
        RandomSource(1).stream("noise")


def test_campaign_run_seeds_are_derived_from_the_base_seed():
    spec = CampaignSpec(scenario=load_scenario("slope50").model_dump(mode="json"), runs=3,
                        methods=("tethered", "free-flight"), seed=2026)  # fmt: skip
    runs = spec.expand()
    for run in runs:
        assert run.seed == derive_seed(2026, 0, run.index)
        expected = np.random.SeedSequence([2026, 0, run.index]).generate_state(1)[0]
        assert run.seed == int(expected)
    by_index = {(r.index, r.method): r.seed for r in runs}
    assert by_index[(1, "tethered")] == by_index[(1, "free-flight")]  # common random numbers
    assert len({r.seed for r in runs}) == 3
