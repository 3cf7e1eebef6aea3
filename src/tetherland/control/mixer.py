"""The mixer: wrench -> rotor thrusts (allocation (6.19) with saturation) -> speed commands.

One compiled call per command, :func:`tetherland.control.kernels.mix_into` (plain
reference: ``mix_reference``, built on :meth:`RotorLayout.allocate` and
:meth:`RotorModel.speed_command`).
"""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

import numpy as np

from tetherland.config import VehicleConfig
from tetherland.control import kernels
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
    :func:`tetherland.control.kernels.mix_into` (reference: ``mix_reference``).
    """

    def __init__(self, vehicle: VehicleConfig):
        self.layout = RotorLayout.from_config(vehicle)
        self.rotors = RotorModel.from_config(vehicle)
        self.packed = kernels.pack_mixer(self.layout, self.rotors)
        """The mixer as the kernels take it (:func:`tetherland.control.kernels.pack_mixer`)."""

    def command(
        self,
        thrust: float,
        torque_B: FloatArray,
        diagnostics: Mapping[str, float] = _EMPTY,
        thrust_rates: FloatArray | None = None,
    ) -> Command:
        tx, ty, tz = np.asarray(torque_B, dtype=float).tolist()
        out = np.empty(kernels.OUT_SATURATION + 1)
        rates = _ZERO4 if thrust_rates is None else np.asarray(thrust_rates, dtype=float)
        kernels.mix_into(
            float(thrust), tx, ty, tz, rates, thrust_rates is not None, self.packed, out
        )
        diag = dict(diagnostics)
        diag["saturation"] = float(out[kernels.OUT_SATURATION])
        return command_from(out, diag)


def command_from(out: FloatArray, diagnostics: Mapping[str, float]) -> Command:
    """The :class:`Command` of a kernel's ``out`` (speeds, achieved wrench; views)."""
    return Command(
        rotor_speeds=out[kernels.OUT_SPEEDS],
        thrust=float(out[4]),
        torque_B=out[5:8],
        diagnostics=diagnostics,
    )
