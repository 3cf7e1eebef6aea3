"""Physics simulation settings (docs/theory.md section 9)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, field_validator

from tetherland.config.base import Section, Vec3

RATE_TOL = 1e-9
"""Relative tolerance for a rate or period to count as an integer multiple of the step."""


class SimConfig(Section):
    """MuJoCo plant settings: integration, contact and cable compliance, scene layout.

    Constraint softness follows MuJoCo's ``solref = (timeconst, dampratio)``: a violated
    contact or cable limit is corrected like a mass-spring-damper with that time constant
    and damping ratio. MuJoCo raises any time constant below two time steps to two time
    steps, so keep ``*_time_constant >= 2 timestep``.
    """

    timestep: float = Field(0.001, ge=1e-6, le=0.005)
    """Physics time step; 1/timestep must be an integer number of steps per second [s]."""
    integrator: Literal["implicitfast", "Euler"] = "implicitfast"
    """MuJoCo integrator (both semi-implicit in velocity; RK4 is not supported here) [-]."""
    contact_time_constant: float = Field(0.005, gt=0, le=1)
    """Time constant of the lander-surface contacts [s]."""
    contact_damping_ratio: float = Field(1.0, gt=0, le=10)
    """Damping ratio of the lander-surface contacts [-]."""
    impratio: float = Field(10.0, ge=1, le=1000)
    """Ratio of frictional to normal constraint impedance (elliptic cones); larger values
    reduce the creep of soft static friction [-]."""
    cable_time_constant: float = Field(0.004, gt=0, le=1)
    """Time constant of the cable length limit (cable stiffness) [s]."""
    cable_damping_ratio: float = Field(1.0, gt=0, le=10)
    """Damping ratio of the cable length limit [-]."""
    ground_z: float | None = None
    """Height of the horizontal ground plane (start pad) in F_W; by default the lowest point
    of the simulated surface patch [m]."""
    start_position: Vec3 | None = None
    """Start pad: lander-plane centre of the vehicle at the start, in F_W; by default on the
    ground 1 m beyond the downhill foot of the surface patch along x_A [m]."""

    @field_validator("timestep")
    @classmethod
    def _integer_rate(cls, value: float) -> float:
        rate = 1.0 / value
        if abs(rate - round(rate)) > RATE_TOL * rate:
            raise ValueError(
                f"1/timestep = {rate:g} must be an integer number of steps per second "
                "(e.g. timestep = 0.001 or 0.0005)"
            )
        return value

    @property
    def steps_per_second(self) -> int:
        """Physics rate 1/timestep [Hz]."""
        return round(1.0 / self.timestep)
