"""What the outer loop hands to a rate-commanding inner loop: body rates and thrust.

tetherland's controllers end in the SO(3) attitude law (Lee et al. 2010),

    tau = w x J w - J (k_R e_R + k_w (w - w_d)) + J alpha_ff,

an angular acceleration alpha = J^-1 (tau - w x J w) = -k_R e_R - k_w (w - w_d) + alpha_ff.
A rate loop that follows its setpoint as a first-order lag of bandwidth k_w,
w' = k_w (w_cmd - w), produces exactly that alpha for

    w_cmd = w + alpha / k_w = w_d - (k_R / k_w) e_R + alpha_ff / k_w,

in which the measured rate cancels: a proportional attitude loop of gain k_R/k_w with the
planned rate and acceleration as feed-forward. This is the rate sent to the firmware,
computed from the command's torque, so the hand-over needs nothing of a controller's
inside. The collective thrust goes over as it is (the throttle map inverts the firmware's
throttle path). With a rate loop faster than k_w the attitude closes at k_R/k_w
(7.8 rad/s for the default gains).

The torque must hold the attitude law alone: a torque that cancels a known disturbance
(the cable at the attachment offset) would become a standing rate. With a rate-commanding
inner loop the firmware's I term carries such torques, and the outer controllers run
without offset compensation (:func:`outer_belief`).
"""

from __future__ import annotations

import numpy as np

from tetherland.config import Scenario
from tetherland.control.attitude import AttitudeGains
from tetherland.geometry import FloatArray
from tetherland.interfaces import Command, ControlMode, Reference, StateEstimate
from tetherland.rotations import cross3


class RateHandover:
    """Body-rate setpoints from a controller's command (see the module docstring).

    Parameters
    ----------
    belief : Scenario
        Believed inertia and the attitude gains of both controllers.
    """

    def __init__(self, belief: Scenario):
        self.J = np.asarray(belief.vehicle.inertia, dtype=float)
        c = belief.controller
        self.k_w = {
            ControlMode.FREE_FLIGHT: AttitudeGains.from_config(c.free_flight).k_w,
            ControlMode.TETHERED: AttitudeGains.from_config(c.tethered).k_w,
        }

    def rates(self, estimate: StateEstimate, reference: Reference, command: Command) -> FloatArray:
        """w_cmd in F_B [rad/s]; zero when the command carries no torque (motors off)."""
        tau = command.torque_B
        k_w = self.k_w.get(reference.mode)
        if tau is None or k_w is None:
            return np.zeros(3)
        w = np.asarray(estimate.body.omega_B, dtype=float)
        alpha = (np.asarray(tau, dtype=float) - cross3(w, self.J * w)) / self.J
        return w + alpha / k_w


def outer_belief(belief: Scenario) -> Scenario:
    """The belief the outer controllers use above a rate loop: no cable-offset torque."""
    tethered = belief.controller.tethered.model_copy(update={"offset_compensation": False})
    controller = belief.controller.model_copy(update={"tethered": tethered})
    return belief.model_copy(update={"controller": controller})


__all__ = ["RateHandover", "outer_belief"]
