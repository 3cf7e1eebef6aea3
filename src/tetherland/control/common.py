"""Pieces shared by the controllers: attitude parametrisation of y^b, cable torque, mixer.

The tethered output y^b = [phi, delta, theta_A, psi] uses the attitude parametrisation
of :mod:`tetherland.models.flatness`: R_AB = R_y(theta_e) R_x(roll) R_z(psi), where
theta_e and roll are the two angles of z_B and psi the rotation about z_B.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from types import MappingProxyType

import numpy as np

from tetherland.config import VehicleConfig
from tetherland.geometry import FloatArray
from tetherland.interfaces import Command
from tetherland.models.quadrotor import RotorLayout, RotorModel, Saturation
from tetherland.rotations import cross3

_EMPTY: Mapping[str, float] = MappingProxyType({})
_SATURATION_LEVEL = {s: i for i, s in enumerate(Saturation)}  # 0 none ... 3 thrust clipped


def rot_x(a: float) -> FloatArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> FloatArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> FloatArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def attitude_from_thrust_axis(z_B_A: FloatArray, psi: float) -> FloatArray:
    """R_AB = R_y(theta_e) R_x(roll) R_z(psi) whose third column is the unit ``z_B_A``."""
    z = z_B_A / np.linalg.norm(z_B_A)
    theta_e = math.atan2(z[0], z[2])
    roll = math.atan2(-z[1], math.hypot(z[0], z[2]))
    return rot_y(theta_e) @ rot_x(roll) @ rot_z(psi)


def heading_of(R_AB: FloatArray) -> float:
    """psi of R_AB = R_y(theta_e) R_x(roll) R_z(psi) [rad]: (R_y R_x)^T R_AB = R_z(psi)."""
    z = R_AB[:, 2]
    M = rot_y(math.atan2(z[0], z[2])) @ rot_x(math.atan2(-z[1], math.hypot(z[0], z[2])))
    Rz = M.T @ R_AB
    return math.atan2(Rz[1, 0], Rz[0, 0])


def cable_torque(r_att_B: FloatArray, tension: float, d_B: FloatArray) -> FloatArray:
    """tau_L = r_att x (-f_L d_B): torque of the cable about the centre of mass, F_B [N m]
    (section 6.6.5); d_B is the unit link direction (anchor -> robot) in F_B."""
    return cross3(r_att_B, -tension * d_B)


class Mixer:
    """Wrench -> rotor thrusts (allocation with saturation) -> rotor speed commands.

    Saturation keeps total thrust and roll/pitch torque before yaw
    (:meth:`RotorLayout.allocate`). Optional per-rotor thrust rates feed the motor-lag
    compensation of :meth:`RotorModel.speed_command`.
    """

    def __init__(self, vehicle: VehicleConfig):
        self.layout = RotorLayout.from_config(vehicle)
        self.rotors = RotorModel.from_config(vehicle)

    def command(
        self,
        thrust: float,
        torque_B: FloatArray,
        diagnostics: Mapping[str, float] = _EMPTY,
        thrust_rates: FloatArray | None = None,
    ) -> Command:
        alloc = self.layout.allocate(np.array([thrust, torque_B[0], torque_B[1], torque_B[2]]))
        speeds = self.rotors.speed_command(alloc.thrusts, thrust_rates)
        diag = dict(diagnostics)
        diag["saturation"] = float(_SATURATION_LEVEL[alloc.saturation])
        return Command(
            rotor_speeds=speeds,
            thrust=float(alloc.wrench[0]),
            torque_B=np.asarray(alloc.wrench[1:4], dtype=float),
            diagnostics=diag,
        )
