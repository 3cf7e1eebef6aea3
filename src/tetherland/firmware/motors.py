"""Motor outputs <-> rotors: the ESC model, Betaflight's throttle path and the motor order.

**ESC (hardware).** The SITL's normalised output u in [0, 1] drives an ESC that sets the
rotor speed in proportion, w_cmd = u w_max (an open-loop ESC: speed follows the duty),
and the plant's rotor model does the rest (first-order lag tau_m, thrust c_f w^2). So a
motor's steady thrust is f = f_max u^2: quadratic in the output.

**Throttle path (firmware).** For a throttle stick t in [0, 1] (``min_check`` = 1000 us,
a linear throttle curve) and zero attitude mix, Betaflight 4.6 outputs (``mixer.c``)::

    t_c = t / (1 + (k - k^2/2) (1 - t)^2)        thrust_linear compensation of the throttle
    m   = t_c (1 + k (1 - t_c)^2)                thrust linearisation of the motor output
    u   = u_idle + (1 - u_idle) m                u_idle = motor_idle / 10^4 (PWM endpoints)

with k = ``thrust_linear`` / 100. :class:`ThrottleMap` inverts this chain for a wanted
collective thrust (a table, monotone in t). The values chosen for the default vehicle
(``betaflight_default.txt``): u_idle = sqrt(f_min / f_max), so that idle is the rotor
model's f_min (0.2 N), and k = 0.8, which keeps the rate loop's gain df/dm within 13 % from
half to 1.6 times hover thrust per rotor (83 % apart without linearisation).

**Motor order.** Betaflight's QUADX motors 1-4 sit rear-right, front-right, rear-left,
front-left; the SITL writes them into the servo packet's slots 3, 0, 1, 2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tetherland.config import VehicleConfig
from tetherland.errors import ConfigError
from tetherland.geometry import FloatArray
from tetherland.models.quadrotor import RotorLayout

SITL_SLOT_OF_MOTOR = (3, 0, 1, 2)
"""Servo-packet slot of Betaflight motors 1..4 (``pwmCompleteMotorUpdate``)."""
QUADX_POSITIONS = ((-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0))
"""Signs of (x, y) in F_B (FLU) of Betaflight motors 1..4: RR, FR, RL, FL."""
QUADX_PROPS_IN_SPIN = (1.0, -1.0, -1.0, 1.0)
"""Yaw-torque sign sigma (tetherland's ``rotor_spins``) of motors 1..4 with Betaflight's
default props (motor 1 turns clockwise seen from above: its drag turns the body
counter-clockwise, +z_B)."""


@dataclass(frozen=True)
class MotorOrder:
    """Which rotor each servo-packet slot drives, and the yaw direction setting.

    Attributes
    ----------
    rotor_of_slot : tuple of int
        tetherland rotor index driven by slots 0..3.
    yaw_motors_reversed : bool
        Betaflight's ``yaw_motors_reversed`` the vehicle's spins need.
    """

    rotor_of_slot: tuple[int, int, int, int]
    yaw_motors_reversed: bool

    @classmethod
    def from_vehicle(cls, vehicle: VehicleConfig) -> MotorOrder:
        """The order for an ``x`` quadrotor; ConfigError for another layout or spins."""
        if vehicle.layout != "x":
            raise ConfigError("vehicle.layout = '+' is not supported with the firmware (QUADX)")
        layout = RotorLayout.from_config(vehicle)
        rotor_of_motor = []
        for sx, sy in QUADX_POSITIONS:
            match = [i for i, (x, y) in enumerate(layout.positions_B[:, :2])
                     if math.copysign(1.0, x) == sx and math.copysign(1.0, y) == sy]  # fmt: skip
            rotor_of_motor.append(match[0])
        spins = np.array([layout.spins[i] for i in rotor_of_motor])
        if np.array_equal(spins, QUADX_PROPS_IN_SPIN):
            reversed_ = False
        elif np.array_equal(spins, -np.array(QUADX_PROPS_IN_SPIN)):
            reversed_ = True
        else:
            raise ConfigError(
                f"vehicle.rotor_spins = {vehicle.rotor_spins}: diagonal rotors must spin alike"
            )
        slots = [0, 0, 0, 0]
        for motor, slot in enumerate(SITL_SLOT_OF_MOTOR):
            slots[slot] = rotor_of_motor[motor]
        return cls(tuple(slots), reversed_)  # type: ignore[arg-type]


@dataclass(frozen=True)
class Esc:
    """The ESCs: normalised output -> rotor speed command, w_cmd = u w_max.

    Attributes
    ----------
    w_max : float
        Rotor speed at full output, the rotor model's speed at f_max [rad/s].
    order : MotorOrder
    """

    w_max: float
    order: MotorOrder

    @classmethod
    def from_vehicle(cls, vehicle: VehicleConfig) -> Esc:
        return cls(math.sqrt(vehicle.f_max / vehicle.thrust_coefficient),
                   MotorOrder.from_vehicle(vehicle))  # fmt: skip

    def rotor_speeds(self, outputs: FloatArray) -> FloatArray:
        """Speed commands in tetherland's rotor order from servo-packet outputs [rad/s]."""
        w = np.empty(4)
        u = np.clip(outputs, 0.0, 1.0)
        for slot, rotor in enumerate(self.order.rotor_of_slot):
            w[rotor] = self.w_max * u[slot]
        return w


@dataclass(frozen=True)
class ThrottleMap:
    """Collective thrust <-> throttle stick through Betaflight's throttle path (believed).

    Attributes
    ----------
    f_max : float
        Believed thrust per rotor at full output [N].
    idle : float
        u_idle, ``motor_idle`` / 10^4 [-].
    thrust_linear : float
        k, ``thrust_linear`` / 100 [-].
    """

    f_max: float
    idle: float
    thrust_linear: float

    def __post_init__(self) -> None:
        t = np.linspace(0.0, 1.0, 4001)
        object.__setattr__(self, "_t", t)
        object.__setattr__(self, "_f", 4.0 * self.f_max * self.output(t) ** 2)

    def output(self, t: FloatArray | float) -> FloatArray:
        """Motor output u for throttle stick t with no attitude mix [-]."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, 1.0)
        k = self.thrust_linear
        t_c = t / (1.0 + (k - 0.5 * k * k) * (1.0 - t) ** 2)
        m = t_c * (1.0 + k * (1.0 - t_c) ** 2)
        return self.idle + (1.0 - self.idle) * m

    def collective(self, t: FloatArray | float) -> FloatArray:
        """Steady collective thrust 4 f_max u^2 at throttle t [N]."""
        return 4.0 * self.f_max * self.output(t) ** 2

    def throttle(self, thrust: float) -> float:
        """Throttle stick in [0, 1] for a collective thrust [N] (clipped to the range)."""
        return float(np.interp(thrust, self._f, self._t))  # type: ignore[attr-defined]

    def mix_slope(self, thrust: float) -> float:
        """df/dm: one rotor's thrust per unit of attitude mix m at the steady output of a
        collective thrust [N].

        The mix adds to the compensated throttle before the linearisation, so at stick t
        (x = t_c) the output is u = u_idle + (1 - u_idle) L(x + m), L(x) = x (1 + k (1-x)^2),
        and df/dm = 2 f_max u (1 - u_idle) L'(x), L'(x) = 1 + k (1 - x)(1 - 3 x).
        """
        t = self.throttle(thrust)
        k = self.thrust_linear
        x = t / (1.0 + (k - 0.5 * k * k) * (1.0 - t) ** 2)
        u = float(self.output(t))
        return 2.0 * self.f_max * u * (1.0 - self.idle) * (1.0 + k * (1.0 - x) * (1.0 - 3.0 * x))


__all__ = ["QUADX_POSITIONS", "SITL_SLOT_OF_MOTOR", "Esc", "MotorOrder", "ThrottleMap"]
