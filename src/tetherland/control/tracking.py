"""Free-flight trajectory tracking as a :class:`~tetherland.interfaces.Controller`.

``Reference.p_W`` rows (position, velocity, acceleration, jerk, snap; the first k given)
-> :class:`PositionController` with the flatness feed-forward of the body rate and
angular acceleration -> wrench [f_R, tau_B] -> :meth:`RotorLayout.allocate` (rotor
limits, priority saturation) -> rotor speed commands through :class:`RotorModel`.

Motor-lag compensation (optional): the speed command leads the first-order lag along the
*nominal* rotor thrusts of the reference, f_n = Gamma^-1 [m ||p'' + g z_W||,
J omega_d' + omega_d x J omega_d], whose rate is the difference of two successive control
ticks. The nominal thrusts depend on the reference only, so estimation noise is not
differentiated.

The update is one compiled call, :func:`tetherland.control.kernels.tracker.tracker_into`
(plain reference beside it: ``tracker_reference``).
"""

from __future__ import annotations

import math

import numpy as np

from tetherland.config import Scenario
from tetherland.control.kernels import free_flight
from tetherland.control.kernels import tracker as kernel
from tetherland.control.kernels.mixer import OUT_SATURATION
from tetherland.control.mixer import Mixer, command_from
from tetherland.control.position import PositionController, PositionReference
from tetherland.errors import SingularityError, TetherlandError
from tetherland.geometry import FloatArray
from tetherland.interfaces import Command, ControlMode, Reference, StateEstimate
from tetherland.models.quadrotor import RotorLayout, RotorModel
from tetherland.rotations import cross3

_DIAGNOSTICS = ("position_error", "saturated")
HOLD_SPEED = 0.05
"""Largest reference speed at which the position-error integral runs (hover) [m/s]."""


class FreeFlightTracker:
    """Tracks free-flight references (hover, approach, perching) with rotor speed commands.

    Parameters
    ----------
    scenario : Scenario
        Vehicle (mass, inertia, rotors), ``controller.free_flight`` gains and rate.
    lag_compensation : bool
        Lead the speed commands by the motor lag along the nominal thrusts.
    max_tilt_deg : float, optional
        Overrides ``controller.free_flight.max_tilt_deg`` (a perch on a steep slope needs
        the thrust axis tilted as far as the slope) [deg].

    ``ControlMode.MOTORS_OFF`` stops the rotors; ``TETHERED`` references are refused
    (:class:`TetherlandError`): this controller has no cable model.
    """

    diagnostic_keys = _DIAGNOSTICS

    def __init__(
        self,
        scenario: Scenario,
        lag_compensation: bool = True,
        max_tilt_deg: float | None = None,
    ) -> None:
        v = scenario.vehicle
        self.mass = v.mass
        self.inertia = np.asarray(v.inertia, dtype=float)
        self.layout = RotorLayout.from_config(v)
        self.rotors = RotorModel.from_config(v)
        gains = scenario.controller.free_flight
        if max_tilt_deg is not None:
            gains = gains.model_copy(update={"max_tilt_deg": float(max_tilt_deg)})
        self.position = PositionController(v.mass, self.inertia, gains, min_thrust=4.0 * v.f_min)
        self.lag_compensation = lag_compensation and v.motor_time_constant > 0
        self._period = 1.0 / scenario.controller.rate_hz

        self._Gi = self.layout.allocation_inverse
        self.mixer = Mixer(v)
        pos, att = self.position, self.position.attitude
        law = free_flight.pack_free_flight(
            pos.mass, pos.g, pos.k_x, pos.k_v, pos.k_i, pos.integral_max, pos.tan_max_tilt,
            pos.min_vertical, att.J, att.gains.k_R, att.gains.k_w,
        )  # fmt: skip
        self._par = kernel.pack_tracker(law, self._period, self.lag_compensation, HOLD_SPEED)
        self._state = kernel.tracker_state()

    def reset(self) -> None:
        """Forget the previous tick (lag compensation restarts)."""
        fresh = kernel.tracker_state()
        self._state[kernel.STATE_T_NOMINAL] = fresh[kernel.STATE_T_NOMINAL]

    def nominal_thrusts(
        self, ref: PositionReference, rates: tuple[FloatArray, FloatArray] | None = None
    ) -> FloatArray:
        """Rotor thrusts of the reference's nominal wrench (flatness) [N] (``rates``: the
        reference's feed-forward body rates when the caller has them already)."""
        F = self.mass * np.asarray(ref.a_W, dtype=float)
        F[2] += self.mass * self.position.g
        tau = np.zeros(3)
        if ref.j_W is not None:
            w, w_dot = rates if rates is not None else self.position.feedforward_rates(ref)
            J = self.inertia
            tau = J * w_dot + cross3(w, J * w)
        return self._Gi @ np.concatenate(([float(np.linalg.norm(F))], tau))

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        """Rotor speed commands for ``reference`` from ``estimate`` (one compiled call,
        :func:`tetherland.control.kernels.tracker.tracker_into`)."""
        if reference.mode is ControlMode.MOTORS_OFF:
            self._state[:] = kernel.tracker_state()
            return Command.motors_off()
        if reference.mode is not ControlMode.FREE_FLIGHT:
            raise TetherlandError(
                f"FreeFlightTracker cannot track a {reference.mode.name} reference"
            )
        if reference.p_W is None:
            raise TetherlandError("FreeFlightTracker needs a position reference (p_W rows)")
        body = estimate.body
        rows = np.array(reference.p_W, dtype=float).reshape(-1, 3)  # one compiled signature
        out = np.empty(kernel.OUT_WIDTH)
        kernel.tracker_into(
            float(t), body.p_W, body.v_W, body.q_WB, body.omega_B, rows, float(reference.yaw),
            self.position.integral, self._state, self._par, self.mixer.packed, out,
        )  # fmt: skip
        singular = int(out[kernel.OUT_SINGULAR])
        if singular:
            raise SingularityError(kernel.SINGULAR_MESSAGES[singular])
        diag = {
            "position_error": float(out[kernel.OUT_POSITION_ERROR]),
            "saturated": float(out[OUT_SATURATION] > 0.0),
        }
        return command_from(out, diag)

    @property
    def hover_speeds(self) -> FloatArray:
        """Rotor speeds holding m g level [rad/s]."""
        f = self._Gi[:, 0] * self.mass * self.position.g
        return np.array([math.sqrt(x / self.rotors.thrust_coefficient) for x in f])
