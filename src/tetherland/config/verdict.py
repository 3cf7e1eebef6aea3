"""How a run is judged: landing tolerances (conditions (1)-(5)) and touchdown detection.

One section for every landing method: the tethered mission and the contact-free baseline
are judged by the same function with the same numbers (docs/theory.md section 5).
"""

from __future__ import annotations

from pydantic import Field

from tetherland.config.base import Section


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
    """Condition (5): largest speed while resting, from ``rest_settle_time`` after the
    motors go off [m/s]."""
    rest_settle_time: float = Field(0.3, ge=0, le=10)
    """Condition (5): the rest speed is judged from this long after the motors go off
    (rotor spin-down, contact transient); the slip is measured over the whole rest [s]."""
    touchdown_force: float = Field(0.05, gt=0, le=100)
    """Touchdown (t_L): the first true normal force above this on a lander (or on the
    frame); the robot's own estimate is ``mission.contact.surface_force`` [N]."""
    safe_stop_speed: float = Field(0.3, gt=0, le=10)
    """Safe stop: largest vehicle speed at the end of the run for the supervisor's safe
    state (hover, landed, motors off) to count as reached [m/s]."""
    return_position_error: float = Field(0.1, gt=0, le=10)
    """Return: largest ||p_RL - pad|| at the end of the run; the cable must also be
    unhooked by then [m]."""
    crash_force: float = Field(1e-6, gt=0, le=100)
    """Crash: a normal force above this on the hub or a rotor guard, at any time [N]."""
