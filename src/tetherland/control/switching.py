"""Switching between free-flight, tethered and motors-off control (chapter 6.6.3).

The supervisor makes the transfer bumpless by starting the next controller's reference at
the current output (by flatness, the same output means the same nominal input); this
controller dispatches on ``Reference.mode`` (and scales the command by
``Reference.thrust_scale``, the spin-down before the motors go off, after taking
``Reference.thrust_shed`` off the collective thrust, the preload before it), resets the controller
it switches to (the DFL thrust extension starts at the last commanded thrust; from
tethered flight the free-flight position integral starts at the force the tethered law was
commanding, and with ``controller.tethered.integral_hand_over`` from free flight the
hierarchical law's link integral at the force the free-flight law was commanding) and
records the command jump of every switch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tetherland.config import Scenario
from tetherland.control.dfl import DflController
from tetherland.control.free_flight import FreeFlightController
from tetherland.control.hierarchical import HierarchicalController
from tetherland.geometry import FloatArray
from tetherland.interfaces import Command, Controller, ControlMode, Reference, StateEstimate
from tetherland.models.quadrotor import RotorLayout


@dataclass(frozen=True)
class SwitchRecord:
    """One controller switch: when, from what to what, and the command jump.

    Attributes
    ----------
    t : float
        Time of the first command of the new controller [s].
    from_mode, to_mode : ControlMode
    thrust_jump : float
        |f_R(new) - f_R(old)| [N].
    rotor_speed_jump : float
        max_i |w_i(new) - w_i(old)| [rad/s].
    """

    t: float
    from_mode: ControlMode
    to_mode: ControlMode
    thrust_jump: float
    rotor_speed_jump: float


def make_tethered_controller(scenario: Scenario, kind: str | Controller | None = None):
    """The tethered controller named by ``kind`` (default ``scenario.controller.kind``), or
    ``kind`` itself when it is already a :class:`~tetherland.interfaces.Controller`."""
    if isinstance(kind, Controller):
        return kind
    kind = kind or scenario.controller.kind
    if kind == "hierarchical":
        return HierarchicalController(scenario)
    if kind == "dfl":
        return DflController(scenario)
    raise ValueError(f"unknown tethered controller {kind!r} (allowed: hierarchical, dfl)")


def scaled(command: Command, scale: float) -> Command:
    """``command`` with every rotor thrust multiplied by ``scale`` (clipped to 0-1): the
    rotor speeds by its square root (thrust c_f w^2), the wanted thrust and torque by it."""
    s = min(max(float(scale), 0.0), 1.0)
    return Command(
        rotor_speeds=math.sqrt(s) * np.asarray(command.rotor_speeds),
        thrust=None if command.thrust is None else s * command.thrust,
        torque_B=None if command.torque_B is None else s * np.asarray(command.torque_B),
        diagnostics=command.diagnostics,
    )


def shed(command: Command, fraction: float, thrust_coefficient: float) -> Command:
    """``command`` with ``fraction`` (clipped to 0-1) of its total thrust taken off every
    rotor equally, each rotor thrust c_f w^2 staying >= 0: the roll, pitch and yaw torques
    are kept (equal changes cancel in each), so the attitude keeps its full authority while
    the collective thrust presses the vehicle onto its landers."""
    p = min(max(float(fraction), 0.0), 1.0)
    w = np.asarray(command.rotor_speeds, dtype=float)
    f = thrust_coefficient * w * w
    f_new = np.maximum(f - p * float(f.sum()) / 4.0, 0.0)
    return Command(
        rotor_speeds=np.sqrt(f_new / thrust_coefficient),
        thrust=None if command.thrust is None else (1.0 - p) * command.thrust,
        torque_B=command.torque_B,
        diagnostics=command.diagnostics,
    )


def with_torque(command: Command, torque_B: FloatArray, layout: RotorLayout) -> Command:
    """``command`` with the body torque ``torque_B`` (F_B) [N m] added: each rotor's thrust
    c_f w^2 changed by the allocation's Gamma^-1 [0, torque_B] (the total thrust kept),
    then held within [f_min, f_max]; the wanted torque grows by ``torque_B``. Per rotor,
    so the motor-lag lead already in the command's speeds stays
    (``Reference.torque_ff_B``)."""
    c_f = layout.thrust_coefficient
    w = np.asarray(command.rotor_speeds, dtype=float)
    tau = np.asarray(torque_B, dtype=float)
    df = layout.allocation_inverse[:, 1:] @ tau
    f = np.clip(c_f * w * w + df, layout.f_min, layout.f_max)
    return Command(
        rotor_speeds=np.sqrt(f / c_f),
        thrust=command.thrust,
        torque_B=tau if command.torque_B is None else np.asarray(command.torque_B) + tau,
        diagnostics=command.diagnostics,
    )


class SwitchingController:
    """Dispatches to the free-flight or tethered controller by ``Reference.mode``.

    Parameters
    ----------
    scenario : Scenario
        Believed scenario.
    tethered : str or Controller, optional
        ``"hierarchical"`` or ``"dfl"`` (default: ``scenario.controller.kind``), or your own
        tethered controller (any :class:`~tetherland.interfaces.Controller`; a ``reset()``
        method, if it has one, is called when tethered control starts).
    """

    def __init__(self, scenario: Scenario, tethered: str | Controller | None = None):
        self.free_flight = FreeFlightController(scenario)
        self.tethered = make_tethered_controller(scenario, tethered)
        self._c_f = scenario.vehicle.thrust_coefficient
        self._hand_over = scenario.controller.tethered.integral_hand_over
        self._layout = RotorLayout.from_config(scenario.vehicle)
        self.mode: ControlMode | None = None
        self.last: Command | None = None
        self.switches: list[SwitchRecord] = []

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        mode = reference.mode
        if mode != self.mode and self.mode is not None:
            if mode == ControlMode.FREE_FLIGHT:
                if self.mode == ControlMode.TETHERED and self.last is not None:
                    # from tethered flight (release, abort): continue the commanded force
                    self.free_flight.hand_over(estimate, reference, self.last.thrust or 0.0)
                else:
                    self.free_flight.reset()
            if mode == ControlMode.TETHERED:
                if isinstance(self.tethered, DflController):
                    # from flight: continue the commanded thrust (bumpless); from motors off
                    # the thrust is zero, where A is singular: start from the plan's nominal
                    flying = self.mode != ControlMode.MOTORS_OFF and self.last is not None
                    self.tethered.reset(self.last.thrust if flying else None)
                elif (
                    self._hand_over and self.mode == ControlMode.FREE_FLIGHT
                    and self.last is not None and hasattr(self.tethered, "hand_over")
                ):  # fmt: skip
                    # from flight: continue the commanded force (the model error the
                    # free-flight integral held is kept, as at the release)
                    self.tethered.hand_over(estimate, reference, self.last.thrust or 0.0)
                elif hasattr(self.tethered, "reset"):
                    self.tethered.reset()
        if mode == ControlMode.MOTORS_OFF:
            cmd = Command.motors_off()
        elif mode == ControlMode.TETHERED:
            cmd = self.tethered.update(t, estimate, reference)
        else:
            cmd = self.free_flight.update(t, estimate, reference)
        if reference.torque_ff_B is not None and mode != ControlMode.MOTORS_OFF:
            cmd = with_torque(cmd, reference.torque_ff_B, self._layout)
        if reference.thrust_shed > 0.0 and mode != ControlMode.MOTORS_OFF:
            cmd = shed(cmd, reference.thrust_shed, self._c_f)
        if reference.thrust_scale < 1.0 and mode != ControlMode.MOTORS_OFF:
            cmd = scaled(cmd, reference.thrust_scale)
        if mode != self.mode and self.mode is not None and self.last is not None:
            self.switches.append(
                SwitchRecord(
                    t=t,
                    from_mode=self.mode,
                    to_mode=mode,
                    thrust_jump=abs((cmd.thrust or 0.0) - (self.last.thrust or 0.0)),
                    rotor_speed_jump=float(
                        np.max(np.abs(cmd.rotor_speeds - self.last.rotor_speeds))
                    ),
                )
            )
        self.mode = mode
        self.last = cmd
        return cmd
