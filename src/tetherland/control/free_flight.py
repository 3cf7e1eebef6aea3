"""Free-flight controller behind the :class:`~tetherland.interfaces.Controller` interface.

Approach, hooking, cable stretching, unhooking and return (chapter 6.6.2) use it:
``Reference.p_W`` rows (p, v, a, ...) -> geometric position/attitude control -> mixer.
"""

from __future__ import annotations

import math

import numpy as np

from tetherland.config import Scenario
from tetherland.control.kernels import free_flight as kernel
from tetherland.control.kernels.mixer import OUT_SATURATION
from tetherland.control.mixer import Mixer, command_from
from tetherland.control.position import PositionController, PositionReference
from tetherland.errors import SingularityError
from tetherland.geometry import FloatArray
from tetherland.interfaces import Command, Reference, StateEstimate
from tetherland.rotations import quat_to_rotmat


class FreeFlightController:
    """Geometric position + SO(3) attitude control (Lee et al. 2010) to rotor speeds.

    The update is one compiled call,
    :func:`tetherland.control.kernels.free_flight.free_flight_into` (plain reference beside
    it: ``free_flight_reference``, the equations of
    :class:`PositionController`, :class:`AttitudeController` and :class:`Mixer`).

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
        pos, att = self.position, self.position.attitude
        self._par = kernel.pack_free_flight(
            pos.mass, pos.g, pos.k_x, pos.k_v, pos.k_i, pos.integral_max, pos.tan_max_tilt,
            pos.min_vertical, att.J, att.gains.k_R, att.gains.k_w,
        )  # fmt: skip
        self._t_last: float | None = None
        # load the compiled law now (numba's cache, once per process): scratch arrays
        z3 = np.zeros(3)
        kernel.free_flight_into(
            z3, z3, np.array([1.0, 0.0, 0.0, 0.0]), z3, np.zeros((3, 3)), 0.0, math.nan,
            np.zeros(3), self._par, self.mixer.packed, np.empty(kernel.OUT_WIDTH),
        )  # fmt: skip

    def reset(self) -> None:
        """Clear the position integral (the controller is taking over)."""
        self.position.reset()
        self._t_last = None

    def hand_over(self, estimate: StateEstimate, reference: Reference, thrust: float) -> None:
        """Take over from a controller that commanded ``thrust`` [N] along the estimated z_B:
        the position integral starts at the difference between that force and this law's
        with an empty integral, so the first command continues the last one (the model
        error the other controller held, e.g. a believed mass 4 % light, is not dropped
        and integrated again while the vehicle sags near a wall)."""
        self.reset()
        P = reference.p_W
        if P is None or not math.isfinite(thrust):
            return
        body = estimate.body
        F_last = thrust * quat_to_rotmat(body.q_WB)[:, 2]
        F_0, _ = self.position.desired_force(body, PositionReference.from_rows(P, reference.yaw))
        self.position.seed_integral(F_last - F_0)

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        """Rotor commands tracking ``reference.p_W`` (rows p, v, a) with ``reference.yaw``."""
        P = reference.p_W
        if P is None:
            raise ValueError("the free-flight controller needs reference.p_W")
        dt = math.nan if self._t_last is None else t - self._t_last
        self._t_last = t
        body = estimate.body
        out = np.empty(kernel.OUT_WIDTH)
        kernel.free_flight_into(
            body.p_W, body.v_W, body.q_WB, body.omega_B, P, float(reference.yaw), dt,
            self.position.integral, self._par, self.mixer.packed, out,
        )  # fmt: skip
        if out[kernel.OUT_SINGULAR]:
            raise SingularityError(SINGULAR_MESSAGE)
        return command_of(out)


SINGULAR_MESSAGE = "thrust axis is aligned with the desired heading: yaw undefined"
"""The :class:`~tetherland.errors.SingularityError` of a heading the law cannot define."""


def command_of(out: FloatArray) -> Command:
    """The :class:`Command` of the compiled law's ``out``
    (:func:`tetherland.control.kernels.free_flight.free_flight_into`), its diagnostics the
    position error ``e_x``, ``e_y``, ``e_z`` [m], ``tilt_limited`` (1 when a limit acted)
    and the mixer's ``saturation`` level."""
    e_x, e_y, e_z = out[kernel.OUT_E_X].tolist()
    diag = {
        "e_x": e_x,
        "e_y": e_y,
        "e_z": e_z,
        "tilt_limited": float(out[kernel.OUT_LIMITED]),
        "saturation": float(out[OUT_SATURATION]),
    }
    return command_from(out, diag)
