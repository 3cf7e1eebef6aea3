"""The supervisor's helpers for switching control laws: the bumpless blend onto a
planned tethered track and the cable pull handed over to free flight at the release."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland.interfaces import ControlMode, Reference, StateEstimate
from tetherland.mission.blend import BlendedTrack
from tetherland.mission.phases import Phase
from tetherland.mission.release import ReleasePull
from tetherland.state import RigidBodyState

MASS = 1.2
P_A = np.array([0.5, -0.2, 0.0])


def _estimate(p_W, tension: float) -> StateEstimate:
    body = RigidBodyState(
        np.asarray(p_W, dtype=float), np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(3)
    )
    return StateEstimate(t=0.0, body=body, tension=tension)


def _pull(**kw) -> ReleasePull:
    d0 = np.array([0.0, 0.6, 0.8])
    args = dict(t0=2.0, fade=1.0, tension=3.0, d0=d0, mass=MASS, p_A=P_A)
    return ReleasePull(**(args | kw))


def test_the_pull_starts_at_the_estimated_tension_and_fades_to_zero_along_the_cable():
    pull = _pull()
    far = _estimate(P_A + np.array([0.0, 0.6, 0.8]), tension=2.5)
    p_d = far.body.p_W
    start = pull.feedforward(2.0, far, p_d)
    np.testing.assert_allclose(start, 3.0 / MASS * pull.d0, atol=1e-12)
    # the 9th-order smoothstep is point-symmetric about its middle: half the pull there
    np.testing.assert_allclose(pull.feedforward(2.5, far, p_d), 0.5 * start, atol=1e-12)
    # after the fade, with the vehicle outside the slack point, nothing is read
    np.testing.assert_allclose(pull.feedforward(3.0, far, p_d - 0.1 * pull.d0), 0.0)
    assert pull.bias == 0.0


@pytest.mark.parametrize(("estimate", "bias"), [(0.4, 0.4), (-0.3, 0.0), (5.0, 3.0)])
def test_inside_the_slack_point_the_tension_estimate_is_the_model_error_along_the_cable(
    estimate, bias
):
    pull = _pull()
    p_W = P_A + np.array([0.3, 0.0, 0.4])  # d = (0.6, 0, 0.8)
    est = _estimate(p_W, tension=estimate)
    d = np.array([0.6, 0.0, 0.8])
    ff = pull.feedforward(3.5, est, p_W + 0.05 * d)  # the reference lies beyond the vehicle
    assert pull.bias == pytest.approx(bias)  # clipped to [0, tension at the release]
    np.testing.assert_allclose(ff, bias / MASS * d, atol=1e-12)


def test_the_frozen_pull_holds_whatever_the_estimate_does():
    pull = _pull()
    p_W = P_A + np.array([0.3, 0.0, 0.4])
    pull.freeze(3.5, _estimate(p_W, tension=0.6), p_W + 0.05)
    held = pull.frozen.copy()
    later = pull.feedforward(9.0, _estimate(p_W + 1.0, tension=0.0), p_W)
    np.testing.assert_array_equal(later, held)
    np.testing.assert_allclose(np.linalg.norm(held), 0.6 / MASS)


class _PolynomialTrack:
    """A planned track whose output rows are y(t) = a + b t + c t^2 and its derivatives."""

    def __init__(self) -> None:
        self.a = np.array([0.4, 0.1, -0.2, 3.0])
        self.b = np.array([-0.1, 0.05, 0.02, 0.0])
        self.c = np.array([0.01, 0.0, -0.03, 0.0])

    def reference(self, t: float) -> Reference:
        out = np.zeros((5, 4))
        out[0] = self.a + self.b * t + self.c * t * t
        out[1] = self.b + 2.0 * self.c * t
        out[2] = 2.0 * self.c
        return Reference(t=t, mode=ControlMode.TETHERED, phase=7, output=out, thrust_ff=9.0)


def test_the_blend_starts_at_the_current_output_with_the_plans_rates_and_ends_on_the_plan():
    track = _PolynomialTrack()
    t_b, T = 1.0, 0.8
    plan_b = track.reference(t_b).output
    y_now = plan_b[0] + np.array([0.05, -0.02, 0.03, -2.0 * math.pi + 0.1])
    blend = BlendedTrack(track, y_now, t_b, T)  # type: ignore[arg-type]
    np.testing.assert_allclose(blend.delta, [0.05, -0.02, 0.03, 0.1], atol=1e-12)  # psi wrapped

    first = blend.reference(t_b, Phase.TETHERED_LANDING)
    np.testing.assert_allclose(first.output[0], plan_b[0] + blend.delta, atol=1e-12)
    np.testing.assert_allclose(first.output[1:], plan_b[1:], atol=1e-12)  # offset at rest
    assert first.phase == int(Phase.TETHERED_LANDING) and first.thrust_ff == 9.0

    mid = blend.reference(t_b + 0.5 * T, Phase.TETHERED_LANDING)
    plan_mid = track.reference(t_b + 0.5 * T).output
    np.testing.assert_allclose(mid.output[0], plan_mid[0] + 0.5 * blend.delta, atol=1e-12)

    after = blend.reference(t_b + T, Phase.SPIN_UP)
    np.testing.assert_allclose(after.output, track.reference(t_b + T).output, atol=1e-12)
    assert after.phase == int(Phase.SPIN_UP)
