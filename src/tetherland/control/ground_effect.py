"""Thrust compensation for the believed ground effect (issue 23, variant b for the controllers).

A controller wrapper: each rotor's commanded speed is divided by the square root of its
believed ground-effect factor (:class:`~tetherland.estimation.ground_effect.
BelievedGroundEffect`: the believed surface patch at the estimated pose), so that the
thrust it believes acting, c_f w^2 k, is the thrust the controller wanted. Switched on by
``controller.ground_effect_compensation``; the plant's ``[aero]`` is never read.

Motor lag. A speed command acts through the first-order lag tau_m of the believed
vehicle, and the factor grows quickly in the last centimetres (about 0.12 1/s on a
perching approach): dividing by sqrt(k(t)) leaves c_f w^2 (k(t) - k(t - tau_m)) of
surplus thrust, enough to hold a contact-free vehicle 2 mm off the surface at its planned
touchdown. The command therefore uses the factor at the pose predicted tau_m ahead,
(p + v tau_m, q exp(omega tau_m / 2)): to first order w_c = w_a + tau_m w_a' for the
wanted acting speed w_a = w / sqrt(k), the same lead the controllers give their own
thrust (:mod:`tetherland.control.tracking`).

Each tick is one compiled call after the wrapped controller's
(:func:`~tetherland.control.kernels.aero.ground_effect_speeds_into`; its plain form
:func:`~tetherland.control.kernels.aero.ground_effect_speeds_reference`).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tetherland.config import Scenario
from tetherland.control.kernels.aero import (
    ground_effect_speeds_into,
    predicted_attitude,
    predicted_attitude_reference,
)
from tetherland.estimation.ground_effect import BelievedGroundEffect
from tetherland.interfaces import Command, Controller, Reference, StateEstimate

__all__ = ["GroundEffectCompensation", "predicted_attitude", "predicted_attitude_reference"]


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
        self.lead = float(belief.vehicle.motor_time_constant)
        """Prediction horizon of the factor: the believed motor time constant [s]."""

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        cmd = self.inner.update(t, estimate, reference)
        b = estimate.body
        w = np.empty(4)
        if not ground_effect_speeds_into(
            b.p_W, b.v_W, b.q_WB, b.omega_B, np.asarray(cmd.rotor_speeds, dtype=float),
            self.lead, self.ground_effect.packed, w,
        ):  # fmt: skip
            return cmd  # motors off, or every believed factor 1: the command as it is
        # (the fields as dataclasses.replace would copy them, without its generic walk)
        return Command(w, cmd.thrust, cmd.torque_B, cmd.diagnostics)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.inner, name)
