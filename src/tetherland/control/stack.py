"""A mission's composed controller, its free-flight ticks compiled as one call (issue 25).

:func:`with_aero_belief` composes a mission's controller in layers: the believed rotor drag
on the reference (:class:`~tetherland.control.rotor_drag.RotorDragCompensation`), the
believed ground effect on the speeds (:class:`~tetherland.control.ground_effect.
GroundEffectCompensation`), the switching controller and its laws. On a free-flight tick
that is four Python calls, two new references and two commands around four compiled calls.
:class:`CompiledStack` keeps the layers (:attr:`CompiledStack.layered`, the plain form)
and flies every tick the free-flight law flies without a switch, a torque, a thrust shed
or a spin-down through one compiled call (:func:`~tetherland.control.kernels.stack.
free_flight_stack_into`), updating the state the layers would update (the free-flight
law's integral and last time, the switching controller's last command); every other tick
goes through the layers. The commands are the layers' bit for bit
(tests/test_control_stack.py).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from tetherland.config import Scenario
from tetherland.control.free_flight import SINGULAR_MESSAGE, FreeFlightController, command_of
from tetherland.control.ground_effect import GroundEffectCompensation
from tetherland.control.kernels import free_flight as ff_kernel
from tetherland.control.kernels.stack import STACK_DIVIDED, STACK_SINGULAR, free_flight_stack_into
from tetherland.control.rotor_drag import RotorDragCompensation
from tetherland.control.switching import SwitchingController
from tetherland.errors import SingularityError
from tetherland.interfaces import Command, Controller, ControlMode, Reference, StateEstimate

__all__ = ["CompiledStack", "compiled_stack", "with_aero_belief"]

_FREE = ControlMode.FREE_FLIGHT
_NO_GROUND_EFFECT = np.zeros(1)  # (the kernel's ``believed`` when the layer is absent)


class CompiledStack:
    """``layered`` (believed rotor drag around [believed ground effect around] a switching
    controller with the free-flight law), its plain free-flight ticks compiled as one call.

    Build it with :func:`compiled_stack`. Every attribute not defined here is the
    layered controller's (``switches``, ``mode``, ``free_flight``, ...).

    Parameters
    ----------
    layered : RotorDragCompensation
        The composed controller (its ``inner`` a :class:`GroundEffectCompensation` around
        a :class:`SwitchingController`, or the switching controller itself).
    """

    def __init__(self, layered: RotorDragCompensation) -> None:
        inner = layered.inner
        ground_effect = inner if isinstance(inner, GroundEffectCompensation) else None
        switching = inner.inner if ground_effect is not None else inner
        if not (
            type(switching) is SwitchingController
            and type(switching.free_flight) is FreeFlightController
        ):  # fmt: skip
            raise TypeError("CompiledStack needs a SwitchingController with the free-flight law")
        self.layered = layered
        """The layers: the plain form, and every tick the compiled call does not fly."""
        self._switching = switching
        self._free_flight = ff = switching.free_flight
        self._drag = layered.packed
        self._par, self._mix = ff._par, ff.mixer.packed
        self._integral = ff.position.integral
        self._ground_effect = ground_effect is not None
        self._lead = ground_effect.lead if ground_effect is not None else 0.0
        self._believed = (
            ground_effect.ground_effect.packed if ground_effect is not None else _NO_GROUND_EFFECT
        )

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        switching = self._switching
        rows = reference.p_W
        if (
            reference.mode is not _FREE or switching.mode is not _FREE
            or reference.drag_in_rows or reference.torque_ff_B is not None
            or reference.thrust_shed > 0.0 or reference.thrust_scale < 1.0
            or rows is None or len(rows) < 2
        ):  # fmt: skip
            return self.layered.update(t, estimate, reference)
        rows = np.asarray(rows, dtype=float)
        ff = self._free_flight
        dt = math.nan if ff._t_last is None else t - ff._t_last
        ff._t_last = t
        body = estimate.body
        out = np.empty(ff_kernel.OUT_WIDTH)
        speeds = np.empty(4)
        status = free_flight_stack_into(
            body.p_W, body.v_W, body.q_WB, body.omega_B, rows, float(reference.yaw), dt,
            self._integral, self._drag, self._par, self._mix, self._lead, self._believed,
            self._ground_effect, np.empty((max(len(rows), 3), 3)), out, speeds,
        )  # fmt: skip
        if status == STACK_SINGULAR:
            raise SingularityError(SINGULAR_MESSAGE)
        mixed = switching.last = command_of(out)
        if status == STACK_DIVIDED:
            return Command(speeds, mixed.thrust, mixed.torque_B, mixed.diagnostics)
        return mixed

    def __getattr__(self, name: str) -> Any:
        return getattr(self.layered, name)


def compiled_stack(controller: Controller) -> Controller:
    """``controller`` as a :class:`CompiledStack` when it is the believed rotor drag around
    [the believed ground effect around] a :class:`SwitchingController` with the
    free-flight law (a mission's default composition); any other controller as it is."""
    if type(controller) is not RotorDragCompensation:
        return controller
    try:
        return CompiledStack(controller)
    except TypeError:
        return controller


def with_aero_belief(
    controller: Controller, belief: Scenario, *, compiled: bool = True
) -> Controller:
    """``controller`` as a mission composes it: wrapped in the believed ground-effect
    compensation (``controller.ground_effect_compensation``) and the believed rotor-drag
    feed-forward (``controller.rotor_drag`` not zero), each only when switched on.

    With ``compiled`` (default) a switching controller so wrapped flies its plain
    free-flight ticks as one compiled call (:class:`CompiledStack`, the same commands bit
    for bit: :func:`compiled_stack`); False keeps the layers alone."""
    out: Controller = controller
    if belief.controller.ground_effect_compensation:
        out = GroundEffectCompensation(out, belief)
    if any(d > 0.0 for d in belief.controller.rotor_drag):
        out = RotorDragCompensation(out, belief)
    return compiled_stack(out) if compiled else out
