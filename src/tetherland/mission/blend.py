"""Bumpless transfer onto a planned tethered track (chapter 6.6.3).

When tethered control takes over (after stretching, and at the spin-up before the
tethered takeoff) the vehicle is not exactly where the plan starts; :class:`BlendedTrack`
moves the plan's start onto the current output and blends it back onto the plan.
"""

from __future__ import annotations

import math

import numpy as np

from tetherland.interfaces import ControlMode, Reference
from tetherland.mission.phases import Phase
from tetherland.planning.spline import smoothstep9_scalar
from tetherland.planning.tracking import TrajectoryTrack


class BlendedTrack:
    """A planned tethered track whose start is moved onto the current output (bumpless).

    y_d(t) = y_plan(t) + (1 - s((t - t_b)/T)) (y_now - y_plan(t_b)), s the 9th-order
    smoothstep: at t_b the reference equals the current output with zero derivatives of
    the offset, and after t_b + T it is the plan.

    Parameters
    ----------
    track : TrajectoryTrack
        The planned track.
    y_now : (4,) array
        The current output y^b = [phi, delta, theta_A, psi] [rad].
    t_b : float
        Mission time of the switch [s].
    duration : float
        Blend time T [s].
    """

    def __init__(self, track: TrajectoryTrack, y_now: np.ndarray, t_b: float, duration: float):
        self.track = track
        self.t_b = t_b
        self.duration = duration
        y0 = track.reference(t_b).output[0]
        delta = np.asarray(y_now, dtype=float) - y0
        delta[3] = math.remainder(delta[3], 2.0 * math.pi)
        self.delta = delta

    def reference(self, t: float, phase: Phase) -> Reference:
        """The blended reference at mission time ``t`` [s], tagged with ``phase``."""
        ref = self.track.reference(t)
        tau = (t - self.t_b) / self.duration
        if tau >= 1.0:
            if ref.phase == int(phase):
                return ref
            return Reference(
                t=t, mode=ref.mode, phase=int(phase), output=ref.output,
                thrust_ff=ref.thrust_ff, feedforward=ref.feedforward,
            )  # fmt: skip
        s = smoothstep9_scalar(tau, 4)
        scale = np.array([1.0 - s[0]] + [-s[k] / self.duration**k for k in range(1, 5)])
        out = ref.output + np.outer(scale, self.delta)
        return Reference(
            t=t, mode=ControlMode.TETHERED, phase=int(phase), output=out,
            thrust_ff=ref.thrust_ff, feedforward=ref.feedforward,
        )  # fmt: skip
