"""The cable's pull handed over to free flight at the release (chapter 6.6.3).

After the tethered takeoff the supervisor switches to free flight with the cable still
taut. The pull is handed over as a force feed-forward (the reference acceleration
f_L d/m) that fades out while the reference moves inside the cable length, then supplies
the force-model error the hand-over left out (:meth:`ReleasePull.feedforward`). As a
position offset, as in stretching, the free-flight position integral would wind up on it
and keep the cable taut when the release leg is short (short cables near walls).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tetherland.interfaces import StateEstimate
from tetherland.planning.spline import smoothstep9_scalar


@dataclass(slots=True)
class ReleasePull:
    """The cable's pull handed over to free flight at the release (mutable run state)."""

    t0: float
    """Release time [s]."""
    fade: float
    """Duration of the timed fade of the pull: the leg to the slack point [s]."""
    tension: float
    """The tension estimate at the release [N]."""
    d0: np.ndarray
    """Cable direction at the release (anchor to vehicle) [-]."""
    mass: float
    """Believed vehicle mass [kg]."""
    p_A: np.ndarray
    """Believed anchor in F_W [m]."""
    bias: float = 0.0
    """The tension estimate read inside the slack point: B.d, the force-model error
    along the cable [N]."""
    frozen: np.ndarray | None = None
    """The feed-forward frozen when the unhooking pass starts [m/s^2] (None: not yet)."""

    def feedforward(self, t: float, est: StateEstimate, p_d: np.ndarray) -> np.ndarray:
        """The released cable's pull as an acceleration feed-forward [m/s^2] at mission
        time ``t`` [s], for the reference position ``p_d`` [m].

        The estimated pull at the release, along the cable, fades out while the reference
        moves to the slack point. At the hand-over, though, the position integral starts
        with the thrust that held the cable less the estimated pull, and so lacks the part
        of the force-model error B (mass, thrust coefficient) along the cable: taut, the
        pull and B.d look alike, and the tension estimate reads T + B.d. Once the fade is
        over and the vehicle is inside the slack point (the cable slack for sure), the
        estimate reads B.d alone; taken as the feed-forward along the cable it supplies
        the missing part, and it is frozen when the unhooking pass starts (:meth:`freeze`:
        the pass turns d). Without it the missing part became a steady error
        -(B.d) d/(m k_x), up to 5 cm towards a wall during the unhooking pass. B.d < 0 (an
        error away from the anchor, which the cable stops) is left to the integral.
        """
        if self.frozen is not None:
            return self.frozen
        s = (t - self.t0) / self.fade if self.fade > 0.0 else 1.0
        if s < 1.0:
            return ((1.0 - smoothstep9_scalar(s, 0)[0]) * self.tension / self.mass) * self.d0
        d = est.body.p_W - self.p_A
        d /= max(float(np.linalg.norm(d)), 1e-9)
        if float((est.body.p_W - p_d) @ d) <= 0.0:  # inside the slack point: B.d
            self.bias = min(max(est.tension or 0.0, 0.0), self.tension)
        return (self.bias / self.mass) * d

    def freeze(self, t: float, est: StateEstimate, p_d: np.ndarray) -> None:
        """Hold the feed-forward of this tick from now on (the unhooking pass starts)."""
        self.frozen = self.feedforward(t, est, p_d)
