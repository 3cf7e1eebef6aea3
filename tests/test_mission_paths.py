"""Free-flight reference paths: rest-to-rest segments, continuity, limits, fast sampling."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherland.mission.paths import PEAK_ACCEL_FACTOR, PEAK_SPEED_FACTOR, Path
from tetherland.planning.spline import smoothstep9

point = st.lists(st.floats(-5, 5), min_size=3, max_size=3).map(np.array)


def reference_sample(path: Path, t: float) -> np.ndarray:
    """The rows by definition: find the segment, evaluate the smoothstep (vectorised)."""
    if not path.segments or t <= path.t0:
        return np.vstack((path.start, np.zeros((2, 3))))
    seg = next((s for s in path.segments if t < s.t_end), path.segments[-1])
    s = smoothstep9(np.array([(t - seg.t0) / seg.duration]), 2)[:, 0]
    d = seg.p1 - seg.p0
    return np.vstack((seg.p0 + s[0] * d, s[1] / seg.duration * d, s[2] / seg.duration**2 * d))


@settings(max_examples=40, deadline=None)
@given(a=point, b=point, c=point, pause=st.floats(0.0, 2.0), seed=st.integers(0, 10**6))
def test_sampling_matches_the_definition_in_any_order(a, b, c, pause, seed):
    path = Path(1.0, a, speed=1.5, accel=1.5).to(b, pause=pause).to(c, speed=0.5)
    rng = np.random.default_rng(seed)
    end = path.t_end + 1.0
    times = np.concatenate([np.linspace(0.0, end, 200), rng.uniform(0.0, end, 50)])
    for t in times:  # increasing, then random (the segment cursor must restart)
        np.testing.assert_allclose(path.sample(float(t)), reference_sample(path, float(t)),
                                   atol=1e-12)  # fmt: skip


@given(a=point, b=point)
def test_segments_start_and_end_at_rest_within_the_limits(a, b):
    speed, accel = 1.2, 0.8
    path = Path(0.0, a, speed, accel).to(b)
    T = path.segments[0].duration
    ts = np.linspace(0.0, T, 401)
    rows = np.array([path.sample(float(t)) for t in ts])
    np.testing.assert_allclose(rows[0], [a, np.zeros(3), np.zeros(3)], atol=1e-12)
    np.testing.assert_allclose(rows[-1], [b, np.zeros(3), np.zeros(3)], atol=1e-9)
    d = float(np.linalg.norm(b - a))
    assert np.linalg.norm(rows[:, 1], axis=1).max() <= speed * (1 + 1e-9) + 1e-12
    assert np.linalg.norm(rows[:, 2], axis=1).max() <= accel * (1 + 1e-6) + 1e-12
    if d > 1e-6 and T > 0.5:  # not the minimum duration: one of the two limits is reached
        peak_v = PEAK_SPEED_FACTOR * d / T
        peak_a = PEAK_ACCEL_FACTOR * d / T**2
        assert max(peak_v / speed, peak_a / accel) > 1 - 1e-9


def test_pauses_and_the_end_hold_read_only_rows():
    path = Path(0.0, np.zeros(3), 1.0, 1.0).to(np.ones(3), pause=1.0)
    t_pause = path.segments[1].t0 + 0.5
    rows = path.sample(t_pause)
    np.testing.assert_array_equal(rows, [np.ones(3), np.zeros(3), np.zeros(3)])
    assert not rows.flags.writeable
    np.testing.assert_array_equal(path.sample(path.t_end + 10.0)[0], np.ones(3))


@given(tau=st.floats(-0.5, 1.5), order=st.integers(0, 6))
def test_scalar_smoothstep_closed_forms_match_the_polynomial(tau, order):
    """Inside (0, 1) every derivative; at and beyond the ends the held values (the first
    four derivatives vanish at both ends, the fifth and higher are taken as zero there)."""
    from tetherland.planning.spline import smoothstep9_scalar

    if not 0.0 < tau < 1.0:
        order = min(order, 4)
    expected = smoothstep9(np.array([tau]), order)[:, 0]
    np.testing.assert_allclose(smoothstep9_scalar(tau, order), expected, rtol=1e-12, atol=1e-9)


def test_a_delayed_path_is_the_same_path_later():
    """delay(dt): every sample at t + dt equals the undelayed sample at t (and t_end moves
    by dt), so a held pass resumes exactly where it stopped."""
    def make():
        return Path(1.0, [0.0, 0.0, 1.0], 0.5, 1.0).to([0.3, 0.0, 1.0], pause=0.5).to([0, 0, 0])

    ref, held = make(), make()
    held.sample(1.2)  # the search cursor has moved on before the delay
    held.delay(0.7)
    assert abs(held.t_end - (ref.t_end + 0.7)) < 1e-12
    for t in np.linspace(0.5, ref.t_end + 1.0, 57):
        np.testing.assert_allclose(held.sample(t + 0.7), ref.sample(t), rtol=0, atol=1e-9)
