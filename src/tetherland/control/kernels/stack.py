"""A mission's free-flight controller stack in one compiled call (issue 25).

A mission composes its controller in layers (:func:`~tetherland.control.rotor_drag.
with_aero_belief`, :mod:`tetherland.control.stack`): the believed rotor drag on the reference rows
(:class:`~tetherland.control.rotor_drag.RotorDragCompensation`), around the believed ground
effect on the speeds (:class:`~tetherland.control.ground_effect.GroundEffectCompensation`),
around the switching controller (:class:`~tetherland.control.switching.
SwitchingController`) whose free-flight law is :class:`~tetherland.control.free_flight.
FreeFlightController`. Each layer is one compiled call; on a free-flight tick (most of a
mission's ticks) :func:`free_flight_stack_into` makes the three one, calling the same
compiled functions in the same order on the same numbers: the plain form is the layered
composition itself, and the two agree bit for bit (tests/test_control_stack.py). The
controller is :class:`tetherland.control.stack.CompiledStack`.
"""

from __future__ import annotations

from numba import njit

from tetherland.control.kernels.aero import drag_rows_into, ground_effect_speeds_into
from tetherland.control.kernels.free_flight import OUT_SINGULAR, free_flight_into
from tetherland.control.kernels.mixer import OUT_SPEEDS
from tetherland.geometry import FloatArray

STACK_SINGULAR = 0
"""The desired heading is undefined (the free-flight law's ``OUT_SINGULAR``)."""
STACK_AS_MIXED = 1
"""The mixer's speeds are the command (motors off, or every believed factor 1)."""
STACK_DIVIDED = 2
"""The command's speeds are the ground-effect compensated ones of ``speeds``."""


@njit(cache=True)
def free_flight_stack_into(
    p_W: FloatArray,
    v_W: FloatArray,
    q_WB: FloatArray,
    omega_B: FloatArray,
    rows: FloatArray,
    yaw: float,
    dt: float,
    integral: FloatArray,
    drag: FloatArray,
    par: FloatArray,
    mix: FloatArray,
    lead: float,
    believed: FloatArray,
    ground_effect: bool,
    rows_out: FloatArray,
    out: FloatArray,
    speeds: FloatArray,
) -> int:
    """One free-flight tick of the stack: the drag rows of ``rows`` into ``rows_out``
    (:func:`~tetherland.control.kernels.aero.drag_rows_into`, ``drag`` packed by
    :func:`~tetherland.control.kernels.aero.pack_drag`), the free-flight law on them into
    ``out`` (:func:`~tetherland.control.kernels.free_flight.free_flight_into`,
    ``integral`` in place), and, with ``ground_effect``, the compensated speeds into
    ``speeds`` (:func:`~tetherland.control.kernels.aero.ground_effect_speeds_into`, the
    factor ``lead`` [s] ahead on the packed belief ``believed``).

    Returns
    -------
    int
        :data:`STACK_SINGULAR`, :data:`STACK_AS_MIXED` or :data:`STACK_DIVIDED`.
    """
    drag_rows_into(q_WB, rows, drag, rows_out)
    free_flight_into(p_W, v_W, q_WB, omega_B, rows_out, yaw, dt, integral, par, mix, out)
    if out[OUT_SINGULAR] != 0.0:
        return STACK_SINGULAR
    if ground_effect and ground_effect_speeds_into(
        p_W, v_W, q_WB, omega_B, out[OUT_SPEEDS], lead, believed, speeds
    ):  # fmt: skip
        return STACK_DIVIDED
    return STACK_AS_MIXED
