"""Thrust compensation for the believed ground effect (issue 23, variant b for the controllers).

A controller wrapper: each rotor's commanded speed is divided by the square root of its
believed ground-effect factor (:class:`~tetherland.estimation.ground_effect.
BelievedGroundEffect`: the believed surface patch at the estimated pose), so that the
thrust it believes acting, c_f w^2 k, is the thrust the controller wanted. Switched on by
``controller.ground_effect_compensation``; the plant's ``[aero]`` is never read.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np

from tetherland.config import Scenario
from tetherland.estimation.ground_effect import BelievedGroundEffect
from tetherland.interfaces import Command, Controller, Reference, StateEstimate


class GroundEffectCompensation:
    """Wraps ``controller``: the same commands, rotor speeds divided by sqrt(k_i).

    Parameters
    ----------
    controller : Controller
        The wrapped controller (its other attributes are reached through the wrapper).
    belief : Scenario
        The *believed* scenario (surface, vehicle).
    """

    def __init__(self, controller: Controller, belief: Scenario) -> None:
        self.inner = controller
        self.ground_effect = BelievedGroundEffect(belief)

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        cmd = self.inner.update(t, estimate, reference)
        w = np.asarray(cmd.rotor_speeds, dtype=float)
        if not w.any():
            return cmd
        b = estimate.body
        k = self.ground_effect.factors_at(b.p_W, b.q_WB)
        return replace(cmd, rotor_speeds=w / np.sqrt(k))

    def __getattr__(self, name: str) -> Any:
        return getattr(self.inner, name)
