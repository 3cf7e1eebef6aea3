"""The control-rate scalar forms give the same bits as the numpy forms they replace (issue 25).

Each per-tick path rewritten with Python floats (no small numpy temporaries) is compared
with the plain numpy expression it stands for, with exact equality: the default missions'
logs must not change by a bit. Where numpy's BLAS sums dot products in another order
(OpenBLAS's AVX-512 kernels: ``tests/rounding.py``) the forms that go through
``np.linalg.norm`` or ``@`` are held to their rounding instead.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rounding import assert_same
from tetherland.config import load_scenario
from tetherland.control.ground_effect import predicted_attitude, predicted_attitude_reference
from tetherland.estimation.ground_effect import BelievedGroundEffect
from tetherland.geometry import LandingGeometry
from tetherland.mission.paths import Path
from tetherland.planning.spline import smoothstep9_scalar
from tetherland.rotations import SMALL_ANGLE


def _unit_quats(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1)[:, None]


def test_scalar_norms_and_sums_have_numpys_bits():
    """The identities the scalar forms rely on: np.linalg.norm of 3 and 4 floats is
    sqrt of the squares summed left to right, np.sum of 4 floats sums left to right.

    (Elsewhere, the norm of n floats to its rounding: the squares summed in any order are
    within n/2 epsilon of the exact sum relative to it, the root halves that and adds half
    an epsilon, so two orders differ by at most (n + 2) / 2 epsilon of the norm.)"""
    rng = np.random.default_rng(25)
    for v in rng.normal(size=(20000, 4)) * rng.choice([1e-4, 1.0, 1e3], size=(20000, 1)):
        a, b, c, d = v.tolist()
        assert_same(np.linalg.norm(v[:3]), math.sqrt(a * a + b * b + c * c), ulps=2.5, scale=0)
        assert_same(np.linalg.norm(v), math.sqrt(a * a + b * b + c * c + d * d), ulps=3, scale=0)
        assert float(np.sum(v)) == ((a + b) + c) + d  # (numpy's own loop, not the BLAS)


def test_predicted_attitude_has_the_bits_of_the_rotation_helpers():
    rng = np.random.default_rng(7)
    quats = _unit_quats(rng, 4000)
    # rates from hover (tiny: the small-angle branch) to fast rotation
    scales = np.concatenate((np.full(1000, 1e-9), np.full(1000, 1e-3), np.full(2000, 5.0)))
    rates = rng.normal(size=(4000, 3)) * scales[:, None]
    small = 0
    for q, w in zip(quats, rates, strict=True):
        tau = 0.03
        small += float(np.linalg.norm(tau * w)) < SMALL_ANGLE
        got = np.array(predicted_attitude(q, w, tau))
        # (elsewhere: about 12 rounded operations from q and w to each unit-quaternion
        # component in either form, half an epsilon each)
        assert_same(got, predicted_attitude_reference(q, w, tau), ulps=12)
    assert 0 < small < 4000  # both branches were exercised


@pytest.mark.parametrize("name", ["slope50", "pipe60"])
def test_believed_total_thrust_of_a_state_is_total_thrust(name):
    """The estimator's form (state vector, thrusts as floats) gives the sum and the factors
    of :meth:`BelievedGroundEffect.total_thrust` exactly, near the surface and far off."""
    sc = load_scenario(name)
    geo = LandingGeometry.from_scenario(sc)
    belief = BelievedGroundEffect(sc)
    rng = np.random.default_rng(3)
    near = far = 0
    for h in np.linspace(sc.vehicle.h_R, 4.0, 60):
        x = np.zeros(16)
        x[0:3] = geo.p_L + h * geo.surface.z_S + rng.normal(0.0, 0.05, 3)
        x[6:10] = _unit_quats(rng, 1)[0] * np.array([1.0, 0.2, 0.2, 0.2])
        x[6:10] /= np.linalg.norm(x[6:10])
        thrusts = rng.uniform(0.0, 6.0, 4)
        expected = belief.total_thrust(x[0:3], x[6:10], thrusts)
        factors = belief.factors
        got = belief.total_thrust_of(x, thrusts.tolist())
        assert got == expected
        assert np.array_equal(belief.factors, factors)
        if belief.beyond_reach(x[0:3]):
            far += 1
        else:
            near += 1
            assert np.array_equal(
                belief.factors_at_pose(x[[0, 1, 2, 6, 7, 8, 9]].tolist()),
                belief.factors_at(x[0:3], x[6:10]),
            )
    assert near > 0 and far > 0


def test_path_rows_have_the_bits_of_the_numpy_form():
    """Path.sample's rows are p0 + s0 (p1 - p0), (s1 / T) (p1 - p0), (s2 / T^2) (p1 - p0)
    with s the smoothstep at (t - t0) / T, as numpy computes them."""
    rng = np.random.default_rng(11)
    path = Path(0.3, rng.normal(size=3), speed=1.5, accel=1.5)
    for _ in range(5):
        path.to(rng.normal(size=3) * 2.0, pause=0.2)
    moves = 0
    for t in np.linspace(0.0, path.t_end + 0.5, 3001):
        rows = path.sample(float(t))
        seg = next((s for s in path.segments if s.t0 <= t < s.t_end), None)
        if seg is None or not (seg.p1 - seg.p0).any():
            continue
        T = seg.base if seg.base > 0.0 else seg.duration
        s0, s1, s2 = smoothstep9_scalar((float(t) - seg.t0) / T, 2)
        delta = seg.p1 - seg.p0
        expected = np.array([seg.p0 + s0 * delta, (s1 / T) * delta, (s2 / (T * T)) * delta])
        assert np.array_equal(rows, expected)
        moves += 1
    assert moves > 1000
