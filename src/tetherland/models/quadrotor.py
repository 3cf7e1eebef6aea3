"""Quadrotor rotor layout, allocation (6.19) and rotor dynamics, docs/theory.md section 4.

u = [f_R, tau_x, tau_y, tau_z] = Gamma @ [f_1, f_2, f_3, f_4]; column i of Gamma is
[1, (r_i x e3), sigma_i c_tau] with r_i the rotor position in F_B and sigma_i its spin
sign. Rotor thrust f_i = c_f w_i^2 (w_i the spinning speed commanded to the ESC), with a
first-order lag of time constant tau_m on w_i and limits f_min <= f_i <= f_max.

The inverse allocation :meth:`RotorLayout.allocate` saturates with a fixed priority: the
total thrust and the roll/pitch torques are kept, the yaw torque is given up first.
"""

from __future__ import annotations

import enum
import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland.config import VehicleConfig
from tetherland.geometry import FloatArray

_BOUND_TOL = 1e-12


class Saturation(enum.Enum):
    """How much of a requested wrench :meth:`RotorLayout.allocate` had to give up."""

    NONE = "none"
    """The wrench is produced exactly."""
    YAW = "yaw"
    """The yaw torque was reduced; thrust, roll and pitch torques are exact."""
    ROLL_PITCH = "roll_pitch"
    """Yaw dropped and roll/pitch torques scaled down (direction kept); thrust exact."""
    THRUST = "thrust"
    """Even the total thrust alone is out of [n f_min, n f_max]: it was clipped."""


@dataclass(frozen=True)
class Allocation:
    """Rotor thrusts for a requested wrench and what was actually achieved.

    Attributes
    ----------
    thrusts : (4,) array
        Rotor thrusts f_i within [f_min, f_max] [N].
    wrench : (4,) array
        Achieved [f_R, tau_x, tau_y, tau_z] = Gamma @ thrusts, F_B [N, N m].
    saturation : Saturation
        Which priority level had to give way.
    """

    thrusts: FloatArray
    wrench: FloatArray
    saturation: Saturation

    @property
    def saturated(self) -> bool:
        return self.saturation is not Saturation.NONE


def _feasible_interval(
    a: FloatArray, b: FloatArray, lo: float, hi: float
) -> tuple[float, float] | None:
    """The set of s with lo <= a + s b <= hi componentwise, as (s_min, s_max), or None."""
    s_min, s_max = -math.inf, math.inf
    for ai, bi in zip(a, b, strict=True):
        if abs(bi) < 1e-15:
            if ai < lo - _BOUND_TOL or ai > hi + _BOUND_TOL:
                return None
            continue
        s1, s2 = (lo - ai) / bi, (hi - ai) / bi
        s_min, s_max = max(s_min, min(s1, s2)), min(s_max, max(s1, s2))
    if s_min > s_max + _BOUND_TOL:
        return None
    return s_min, s_max


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

    @functools.cached_property
    def allocation(self) -> FloatArray:
        """Gamma (4x4): rotor thrusts -> [f_R, tau_B] [N, N m] (computed once; read-only)."""
        e3 = np.array([0.0, 0.0, 1.0])
        torque_rows = np.cross(self.positions_B, e3).T  # (3, 4): r_i x e3
        G = np.vstack((np.ones(4), torque_rows[:2], self.spins * self.drag_coefficient))
        G.setflags(write=False)
        return G

    @functools.cached_property
    def allocation_inverse(self) -> FloatArray:
        """Gamma^-1 (4x4): [f_R, tau_B] -> rotor thrusts, without limits [N] (read-only)."""
        Gi = np.linalg.inv(self.allocation)
        Gi.setflags(write=False)
        return Gi

    def wrench(self, thrusts: ArrayLike) -> FloatArray:
        """[f_R, tau_x, tau_y, tau_z] = Gamma f for rotor thrusts ``f`` (last axis 4) [N, N m]."""
        return np.asarray(thrusts, dtype=float) @ self.allocation.T

    def thrusts(self, wrench: ArrayLike) -> FloatArray:
        """Gamma^-1 [f_R, tau_B] exactly, ignoring the limits (last axis 4) [N]."""
        return np.asarray(wrench, dtype=float) @ self.allocation_inverse.T

    def within_limits(self, thrusts: ArrayLike, tol: float = 1e-9) -> bool:
        """True when every rotor thrust lies in [f_min - tol, f_max + tol]."""
        f = np.asarray(thrusts, dtype=float)
        return bool(np.all(f >= self.f_min - tol) and np.all(f <= self.f_max + tol))

    def allocate(self, wrench: ArrayLike) -> Allocation:
        """Rotor thrusts for ``wrench`` = [f_R, tau_x, tau_y, tau_z] within [f_min, f_max].

        Priority: the exact solution Gamma^-1 w when it is within limits; otherwise the
        yaw torque is scaled by the s in [0, 1] closest to 1 that fits; if no such s
        exists, the yaw torque is dropped and the roll/pitch torques are scaled down
        together (their direction is kept) at exact total thrust; if the total thrust
        alone does not fit: above 4 f_max it is clipped to it with zero torque, below
        4 f_min the roll/pitch torque is kept (scaled down together only to fit under
        f_max) on rotors raised above f_min by the differential it needs, so the total
        thrust is above the one asked for (a vehicle tilted 90 deg, whose wanted thrust
        along z_B is near zero, must still turn: with zero torque at the floor the safe
        hover after a fault on a wall never levelled and fell, docs/walls.md).
        """
        w = np.asarray(wrench, dtype=float).reshape(4)
        Gi = self.allocation_inverse
        lo, hi = self.f_min, self.f_max
        f = Gi @ w
        if f.min() >= lo - _BOUND_TOL and f.max() <= hi + _BOUND_TOL:  # the common case
            return Allocation(thrusts=np.minimum(np.maximum(f, lo), hi), wrench=w.copy(),
                              saturation=Saturation.NONE)  # fmt: skip
        # 1. keep f_R, tau_x, tau_y; scale tau_z by s in [0, 1].
        base = Gi @ np.array([w[0], w[1], w[2], 0.0])
        s = _feasible_interval(base, Gi[:, 3] * w[3], lo, hi)
        if s is not None and s[0] <= 1.0 and s[1] >= 0.0:
            return self._result(base + min(1.0, s[1]) * Gi[:, 3] * w[3], Saturation.YAW)
        # 2. keep f_R; scale (tau_x, tau_y) by s in [0, 1], no yaw.
        base = Gi[:, 0] * w[0]
        s = _feasible_interval(base, Gi[:, 1:3] @ w[1:3], lo, hi)
        if s is not None and s[0] <= 1.0 and s[1] >= 0.0:
            return self._result(
                base + min(1.0, s[1]) * (Gi[:, 1:3] @ w[1:3]), Saturation.ROLL_PITCH
            )
        # 3. the total thrust does not fit: above the ceiling, clip it, no torque; below
        # the floor, keep the roll/pitch torque (scaled to fit under f_max) on rotors raised
        # above f_min by the differential it needs (torque before thrust at the bottom: the
        # roll and pitch columns of Gamma^-1 sum to zero, so the raise adds thrust only)
        n = len(self.spins)
        if w[0] < n * lo:
            d = Gi[:, 1:3] @ w[1:3]
            spread = float(d.max() - d.min())
            s = 1.0 if spread <= hi - lo else (hi - lo) / spread
            return self._result(lo + s * (d - d.min()), Saturation.THRUST)
        f_R = min(max(w[0], n * lo), n * hi)
        return self._result(Gi[:, 0] * f_R, Saturation.THRUST)

    def _result(self, f: FloatArray, saturation: Saturation) -> Allocation:
        f = np.clip(f, self.f_min, self.f_max)
        return Allocation(thrusts=f, wrench=self.allocation @ f, saturation=saturation)

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


@dataclass(frozen=True)
class RotorModel:
    """Rotor dynamics: thrust f = c_f w^2 and a first-order lag on the speed w.

    tau_m w' = w_cmd - w, with commands and speeds limited to [w_min, w_max] (the speeds
    matching [f_min, f_max]). Works on any array of rotors (elementwise).

    Attributes
    ----------
    thrust_coefficient : float
        c_f [N/(rad/s)^2].
    time_constant : float
        tau_m [s]; 0 means the speed follows the command instantly.
    f_min, f_max : float
        Thrust limits per rotor [N].
    """

    thrust_coefficient: float
    time_constant: float
    f_min: float
    f_max: float

    def __post_init__(self) -> None:
        if self.thrust_coefficient <= 0 or self.time_constant < 0:
            raise ValueError("thrust_coefficient must be > 0 and time_constant >= 0")
        if not 0 <= self.f_min < self.f_max:
            raise ValueError(f"need 0 <= f_min < f_max, got {self.f_min}, {self.f_max}")

    @classmethod
    def from_config(cls, vehicle: VehicleConfig) -> RotorModel:
        return cls(
            thrust_coefficient=vehicle.thrust_coefficient,
            time_constant=vehicle.motor_time_constant,
            f_min=vehicle.f_min,
            f_max=vehicle.f_max,
        )

    @property
    def w_min(self) -> float:
        """Speed at f_min [rad/s]."""
        return math.sqrt(self.f_min / self.thrust_coefficient)

    @property
    def w_max(self) -> float:
        """Speed at f_max [rad/s]."""
        return math.sqrt(self.f_max / self.thrust_coefficient)

    def thrust(self, w: ArrayLike) -> FloatArray:
        """f = c_f w^2 [N]."""
        w = np.asarray(w, dtype=float)
        return self.thrust_coefficient * w * w

    def speed(self, f: ArrayLike) -> FloatArray:
        """w = sqrt(f / c_f) for f clipped to [f_min, f_max] [rad/s]."""
        f = np.clip(np.asarray(f, dtype=float), self.f_min, self.f_max)
        return np.sqrt(f / self.thrust_coefficient)

    def speed_command(self, f: ArrayLike, f_dot: ArrayLike | None = None) -> FloatArray:
        """Speed command producing the thrust ``f`` [N], optionally with lag compensation.

        With the planned thrust rate ``f_dot`` [N/s] the command leads the lag:
        w_cmd = w + tau_m w', w' = f'/(2 c_f w) (exact inversion of the first-order lag
        along a differentiable thrust profile). The result is limited to [w_min, w_max].
        """
        f = np.asarray(f, dtype=float)
        w = np.sqrt(np.minimum(np.maximum(f, self.f_min), self.f_max) / self.thrust_coefficient)
        if f_dot is None or self.time_constant <= 0:
            return w  # already within [w_min, w_max]
        w = w + self.time_constant * np.asarray(f_dot, dtype=float) / (
            2.0 * self.thrust_coefficient * w
        )
        return np.minimum(np.maximum(w, self.w_min), self.w_max)

    def speed_rate(self, w: ArrayLike, w_cmd: ArrayLike) -> FloatArray:
        """w' = (w_cmd - w)/tau_m for a command limited to [w_min, w_max] [rad/s^2]."""
        if self.time_constant == 0:
            raise ZeroDivisionError("the lag has no rate form for time_constant = 0: use step()")
        w_cmd = np.clip(np.asarray(w_cmd, dtype=float), self.w_min, self.w_max)
        return (w_cmd - np.asarray(w, dtype=float)) / self.time_constant

    def step(self, w: ArrayLike, w_cmd: ArrayLike, dt: float) -> FloatArray:
        """Speeds after ``dt`` seconds of a constant command (exact solution of the lag).

        w(t + dt) = w_c + (w - w_c) exp(-dt/tau_m), w_c the command limited to
        [w_min, w_max]; with tau_m = 0 the speed equals the command.
        """
        w_c = np.clip(np.asarray(w_cmd, dtype=float), self.w_min, self.w_max)
        if self.time_constant == 0:
            return w_c.copy()
        decay = math.exp(-dt / self.time_constant)
        return w_c + (np.asarray(w, dtype=float) - w_c) * decay
