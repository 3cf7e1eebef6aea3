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
"""

from __future__ import annotations

import math

import numpy as np

from tetherland.config import Scenario
from tetherland.control.position import PositionController, PositionReference
from tetherland.errors import TetherlandError
from tetherland.geometry import FloatArray
from tetherland.interfaces import Command, ControlMode, Reference, StateEstimate
from tetherland.models.quadrotor import RotorLayout, RotorModel
from tetherland.rotations import cross3

_DIAGNOSTICS = ("position_error", "saturated")


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
        self._t_int: float | None = None
        self._last: tuple[float, FloatArray] | None = None

    def reset(self) -> None:
        """Forget the previous tick (lag compensation restarts)."""
        self._last = None

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
        """Rotor speed commands for ``reference`` from ``estimate``."""
        if reference.mode is ControlMode.MOTORS_OFF:
            self._last = None
            self._t_int = None
            return Command.motors_off()
        if reference.mode is not ControlMode.FREE_FLIGHT:
            raise TetherlandError(
                f"FreeFlightTracker cannot track a {reference.mode.name} reference"
            )
        if reference.p_W is None:
            raise TetherlandError("FreeFlightTracker needs a position reference (p_W rows)")
        ref = PositionReference.from_rows(reference.p_W, reference.yaw)
        body = estimate.body
        # integral action, learnt while hovering (reference at rest) and frozen during the
        # maneuver: the bias of the thrust and mass model errors keeps being cancelled
        dt = None if self._t_int is None else t - self._t_int
        self._t_int = t
        if float(np.linalg.norm(ref.v_W)) > 0.05:
            dt = None
        rates = None if ref.j_W is None else self.position.feedforward_rates(ref)
        wrench = self.position.update(body, ref, dt, rates)
        alloc = self.layout.allocate(np.concatenate(([wrench.thrust], wrench.torque_B)))
        f_dot = None
        if self.lag_compensation:
            f_n = self.nominal_thrusts(ref, rates)
            last = self._last
            if last is not None and 0.0 < t - last[0] <= 2.5 * self._period:
                f_dot = (f_n - last[1]) / (t - last[0])
            self._last = (t, f_n)
        speeds = self.rotors.speed_command(alloc.thrusts, f_dot)
        err = float(np.linalg.norm(body.p_W - ref.p_W))
        return Command(
            rotor_speeds=speeds,
            thrust=float(alloc.wrench[0]),
            torque_B=alloc.wrench[1:].copy(),
            diagnostics={"position_error": err, "saturated": float(alloc.saturated)},
        )

    @property
    def hover_speeds(self) -> FloatArray:
        """Rotor speeds holding m g level [rad/s]."""
        f = self._Gi[:, 0] * self.mass * self.position.g
        return np.array([math.sqrt(x / self.rotors.thrust_coefficient) for x in f])
