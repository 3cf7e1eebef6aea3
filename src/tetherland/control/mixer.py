"""The mixer: wrench -> rotor thrusts (allocation (6.19) with saturation) -> speed commands.

One compiled call per command, :func:`tetherland.control.kernels.mixer.mix_into` (plain
reference: ``mix_reference``, built on :meth:`RotorLayout.allocate` and
:meth:`RotorModel.speed_command`).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

import numpy as np

from tetherland.config import VehicleConfig
from tetherland.control.kernels import mixer as kernel
from tetherland.geometry import FloatArray
from tetherland.interfaces import Command
from tetherland.models.quadrotor import RotorLayout, RotorModel

_EMPTY: Mapping[str, float] = MappingProxyType({})
_ZERO4 = np.zeros(4)  # writable: numba compiles read-only arrays as another type


class Mixer:
    """Wrench -> rotor thrusts (allocation with saturation) -> rotor speed commands.

    Saturation keeps total thrust and roll/pitch torque before yaw
    (:meth:`RotorLayout.allocate`). Optional per-rotor thrust rates feed the motor-lag
    compensation of :meth:`RotorModel.speed_command`. Compiled:
    :func:`tetherland.control.kernels.mixer.mix_into` (reference: ``mix_reference``).
    """

    def __init__(self, vehicle: VehicleConfig):
        self.layout = RotorLayout.from_config(vehicle)
        self.rotors = RotorModel.from_config(vehicle)
        layout, rotors = self.layout, self.rotors
        self.packed = kernel.pack_mixer(
            layout.allocation, layout.allocation_inverse, layout.f_min, layout.f_max,
            rotors.thrust_coefficient, rotors.time_constant, rotors.w_min, rotors.w_max,
        )  # fmt: skip
        """The mixer as the compiled laws take it
        (:func:`tetherland.control.kernels.mixer.pack_mixer`)."""

    def command(
        self,
        thrust: float,
        torque_B: FloatArray,
        diagnostics: Mapping[str, float] = _EMPTY,
        thrust_rates: FloatArray | None = None,
    ) -> Command:
        tx, ty, tz = np.asarray(torque_B, dtype=float).tolist()
        out = np.empty(kernel.OUT_WIDTH)
        rates = _ZERO4 if thrust_rates is None else np.asarray(thrust_rates, dtype=float)
        kernel.mix_into(
            float(thrust), tx, ty, tz, rates, thrust_rates is not None, self.packed, out
        )
        diag = dict(diagnostics)
        diag["saturation"] = float(out[kernel.OUT_SATURATION])
        return command_from(out, diag)


def command_from(out: FloatArray, diagnostics: Mapping[str, float]) -> Command:
    """The :class:`Command` of a compiled law's ``out`` (speeds, achieved wrench; views)."""
    wrench = out[kernel.OUT_WRENCH]
    # (rotor_speeds, thrust, torque_B, diagnostics: positional, the control-rate path)
    return Command(out[kernel.OUT_SPEEDS], float(wrench[0]), wrench[1:4], diagnostics)
