"""How a run is judged: landing tolerances (conditions (1)-(5)) and touchdown detection.

One section for every landing method: the tethered mission and the contact-free baseline
are judged by the same function with the same numbers (docs/theory.md section 5).
"""

from __future__ import annotations

import math

from pydantic import Field, model_validator

from tetherland import GRAVITY
from tetherland.config.base import Section
from tetherland.config.physical import VehicleConfig

MOTORS_OFF_FRACTION = 0.02
"""The motors-off level of the judge as a fraction of the hover thrust m g [-]
(:func:`motors_off_thrust`)."""


class VerdictConfig(Section):
    """Landing tolerances and the contact rules of the judge, measured on the plant's truth."""

    position_error: float = Field(0.03, gt=0, le=1)
    """Condition (1): largest ||p_RL(t_L) - p*_L|| [m]."""
    attitude_error_deg: float = Field(3.0, gt=0, le=45)
    """Condition (2): largest angle between z_B(t_L) and z_S [deg]."""
    touchdown_speed: float = Field(0.1, gt=0, le=10)
    """Condition (3): largest ||p'_R(t_L-)|| [m/s]."""
    touchdown_angular_rate: float = Field(0.3, gt=0, le=50)
    """Condition (3): largest ||omega_B(t_L-)|| [rad/s]."""
    touchdown_accel: float = Field(1.0, gt=0, le=100)
    """Condition (4): largest ||p''_R(t_L-)|| [m/s^2]."""
    touchdown_angular_accel: float = Field(10.0, gt=0, le=1000)
    """Condition (4): largest ||omega'_B(t_L-)|| [rad/s^2]."""
    rest_slip: float = Field(0.01, gt=0, le=1)
    """Condition (5): largest displacement of p_RL while the motors are off [m]."""
    rest_speed: float = Field(0.02, gt=0, le=10)
    """Condition (5): largest speed while resting, from ``rest_settle_time`` after the rest
    begins [m/s]."""
    rest_settle_time: float = Field(0.3, ge=0, le=10)
    """Condition (5): the rest speed is judged from this long after the rest begins (the
    contact transient); the slip is measured from the first touchdown [s]."""
    min_rest_time: float = Field(1.0, gt=0, le=600)
    """Condition (5): the rest, the interval in which the plant's true rotor thrust stays
    below the motors-off level (:func:`motors_off_thrust`), must last at least this long [s]."""
    touchdown_force: float = Field(0.05, gt=0, le=100)
    """Touchdown (t_L): the first true normal force above this on a lander from the landing
    surface; the robot's own estimate is ``mission.contact.surface_force`` [N]."""
    safe_stop_speed: float = Field(0.3, gt=0, le=10)
    """Safe stop: largest vehicle speed at the end of the run for the supervisor's safe
    state (hover, landed, motors off) to count as reached [m/s]."""
    return_position_error: float = Field(0.1, gt=0, le=10)
    """Return: largest ||p_RL - pad|| at the end of the run; the cable must also be
    unhooked by then [m]."""
    crash_force: float = Field(1e-6, gt=0, le=100)
    """Crash: a normal force above this on any part of the vehicle but the landers (hub,
    cable mount, arms, legs, rotor guards), at any physics step [N]."""

    @model_validator(mode="after")
    def _settle_within_rest(self) -> VerdictConfig:
        if self.rest_settle_time >= self.min_rest_time:
            raise ValueError(
                f"verdict.rest_settle_time = {self.rest_settle_time:g} s must be < "
                f"verdict.min_rest_time = {self.min_rest_time:g} s (the rest speed is judged "
                "after the settle)"
            )
        return self


def motors_off_thrust(vehicle: VehicleConfig) -> float:
    """Total true rotor thrust below which the judge counts the motors off [N].

    2 % of the hover thrust, ``MOTORS_OFF_FRACTION`` m g: a thrust that carries at most
    2 % of the vehicle's weight cannot hold it on the surface (what holds it is the
    surface and the cable), yet a stopped motor's thrust, which decays as exp(-2 t /
    tau_m), falls below it within 2 tau_m of a cut from hover. No controller flies
    that low: the flying rotors never go below f_min each (4 f_min = 8 % of m g for the
    default vehicle).
    """
    return MOTORS_OFF_FRACTION * vehicle.mass * GRAVITY


def spin_down_time(vehicle: VehicleConfig) -> float:
    """Longest time from stopping the motors to the true thrust below
    :func:`motors_off_thrust` [s]: from every rotor at f_max, the total thrust
    4 f_max exp(-2 t / tau_m) of the plant's first-order motors."""
    ratio = 4.0 * vehicle.f_max / motors_off_thrust(vehicle)
    return 0.5 * vehicle.motor_time_constant * math.log(max(ratio, 1.0))
