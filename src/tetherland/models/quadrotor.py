"""Quadrotor rotor layout and the allocation matrix Gamma (6.19), DESIGN.md section 4.

u = [f_R, tau_x, tau_y, tau_z] = Gamma @ [f_1, f_2, f_3, f_4]; column i of Gamma is
[1, (r_i x e3), sigma_i c_tau] with r_i the rotor position in F_B and sigma_i its spin
sign. Rotor thrust f_i = c_f w_i^2 (w_i the spinning speed commanded to the ESC).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland.config import VehicleConfig
from tetherland.geometry import FloatArray


@dataclass(frozen=True)
class RotorLayout:
    """Rotor positions, spins and coefficients of a quadrotor.

    Attributes
    ----------
    positions_B : (4, 3) array
        Rotor centres r_i in F_B [m] (in the plane z_B = 0 through the centre of mass).
    spins : (4,) array
        sigma_i = +-1: sign of the yaw torque per newton of thrust.
    drag_coefficient : float
        c_tau [m].
    thrust_coefficient : float
        c_f [N/(rad/s)^2].
    f_min, f_max : float
        Per-rotor thrust limits [N].
    """

    positions_B: FloatArray
    spins: FloatArray
    drag_coefficient: float
    thrust_coefficient: float
    f_min: float
    f_max: float

    @classmethod
    def from_config(cls, vehicle: VehicleConfig) -> RotorLayout:
        offset = math.pi / 4 if vehicle.layout == "x" else 0.0
        angles = offset + np.arange(4) * math.pi / 2
        L = vehicle.arm_length
        positions = np.column_stack((L * np.cos(angles), L * np.sin(angles), np.zeros(4)))
        return cls(
            positions_B=positions,
            spins=np.asarray(vehicle.rotor_spins, dtype=float),
            drag_coefficient=vehicle.drag_coefficient,
            thrust_coefficient=vehicle.thrust_coefficient,
            f_min=vehicle.f_min,
            f_max=vehicle.f_max,
        )

    @property
    def allocation(self) -> FloatArray:
        """Gamma (4x4): rotor thrusts -> [f_R, tau_B] [N, N m]."""
        e3 = np.array([0.0, 0.0, 1.0])
        torque_rows = np.cross(self.positions_B, e3).T  # (3, 4): r_i x e3
        return np.vstack((np.ones(4), torque_rows[:2], self.spins * self.drag_coefficient))

    def speed_from_thrust(self, f: ArrayLike) -> FloatArray:
        """Rotor speeds w_i = sqrt(f_i / c_f) [rad/s] (thrusts clipped at 0)."""
        return np.sqrt(np.maximum(np.asarray(f, dtype=float), 0.0) / self.thrust_coefficient)

    def thrust_from_speed(self, w: ArrayLike) -> FloatArray:
        """Rotor thrusts f_i = c_f w_i^2 [N]."""
        w = np.asarray(w, dtype=float)
        return self.thrust_coefficient * w * w

    @property
    def speed_limits(self) -> tuple[float, float]:
        """(w_min, w_max) matching (f_min, f_max) [rad/s]."""
        w = self.speed_from_thrust([self.f_min, self.f_max])
        return float(w[0]), float(w[1])
