"""Free-flight controller behind the :class:`~tetherland.interfaces.Controller` interface.

Approach, hooking, cable stretching, unhooking and return (chapter 6.6.2) use it:
``Reference.p_W`` rows (p, v, a, ...) -> geometric position/attitude control -> mixer.
"""

from __future__ import annotations

import numpy as np

from tetherland.config import Scenario
from tetherland.control.common import Mixer
from tetherland.control.position import PositionController, PositionReference
from tetherland.interfaces import Command, Reference, StateEstimate

_ZERO3 = np.zeros(3)


class FreeFlightController:
    """Geometric position + SO(3) attitude control (Lee et al. 2010) to rotor speeds.

    Parameters
    ----------
    scenario : Scenario
        Believed vehicle and ``controller.free_flight`` gains.
    """

    def __init__(self, scenario: Scenario):
        v = scenario.vehicle
        self.position = PositionController(
            v.mass,
            np.asarray(v.inertia, dtype=float),
            scenario.controller.free_flight,
            min_thrust=4.0 * v.f_min,
        )
        self.mixer = Mixer(v)
        self._t_last: float | None = None

    def reset(self) -> None:
        """Clear the position integral (the controller is taking over)."""
        self.position.reset()
        self._t_last = None

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        """Rotor commands tracking ``reference.p_W`` (rows p, v, a) with ``reference.yaw``."""
        P = reference.p_W
        if P is None:
            raise ValueError("the free-flight controller needs reference.p_W")
        ref = PositionReference(
            p_W=P[0],
            v_W=P[1] if P.shape[0] > 1 else _ZERO3,
            a_W=P[2] if P.shape[0] > 2 else _ZERO3,
            yaw=reference.yaw,
        )
        dt = None if self._t_last is None else t - self._t_last
        self._t_last = t
        w = self.position.update(estimate.body, ref, dt)
        e = estimate.body.p_W - ref.p_W
        diag = {
            "e_x": float(e[0]),
            "e_y": float(e[1]),
            "e_z": float(e[2]),
            "tilt_limited": float(w.limited),
        }
        return self.mixer.command(w.thrust, w.torque_B, diag)
