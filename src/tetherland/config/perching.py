"""Settings of the contact-free perching baseline (chapter section 6.4.1, issue 7).

The baseline lands without a tether: a state-to-state kinodynamic plan from a hover near
the surface to touchdown at the landing point with the landers plane on the surface,
tracked by the free-flight controller, motors off right after touchdown. The NLP solver
settings (solver, tolerance, iteration limit, mu_init, fallback) are shared with the
tethered planner's ``[planner]`` section.
"""

from __future__ import annotations

from pydantic import Field, model_validator

from tetherland.config.base import Section, Vec3


class PerchingWeights(Section):
    """Gains of the perching cost integral(k_jerk |p'''|^2 + k_omega theta'^2
    + k_thrust_accel sum f_i''^2) dt + k_time T."""

    k_jerk: float = Field(1e-2, ge=0, le=1e6)
    """|p'''|^2, jerk of the centre of mass [(m/s^3)^-2]."""
    k_omega: float = Field(0.1, ge=0, le=1e6)
    """theta'^2, pitch rate [(rad/s)^-2]."""
    k_thrust_accel: float = Field(1e-3, ge=0, le=1e6)
    """sum f_i''^2, smooth rotor commands [(N/s^2)^-2]."""
    k_time: float = Field(5.0, ge=0, le=1e6)
    """Weight of the duration T in the free-final-time search [1/s]."""


class PerchingConfig(Section):
    """The contact-free perching maneuver: start, touchdown, timing and tracking run."""

    hover_distance: float = Field(0.8, gt=0, le=20)
    """Start hover point: the centre of mass this far from the landed centre of mass
    p*_L + h_R z_S, along the surface normal z_S through the landing point [m]."""
    hover_position: Vec3 | None = None
    """Explicit start hover point of the centre of mass in F_W (overrides
    ``hover_distance``); it must lie in the vertical plane of the fall line through the
    landing point [m]."""
    approach_speed: float = Field(0.05, ge=0, le=1)
    """v_n, the planned touchdown velocity p'(t_L) = -v_n z_S. Zero is the chapter's
    condition (3) exactly, but then nothing fixes *when* contact happens: near t_L the
    vehicle closes on the surface only cubically in time, so a millimetre of tracking
    error shifts contact by tens of milliseconds, at a tangential speed of g sin(beta)
    per second of shift. A small normal speed makes contact happen on time (timing error
    = normal error / v_n) at a touchdown speed still within condition (3)'s tolerance
    [m/s]."""
    approach_height: float = Field(0.03, ge=0, le=1)
    """d_f: the lander tips stay above min(d_f, 0.5 v_n (t_L - t)), so the last d_f are
    flown towards the surface, not along it [m]."""
    duration: float | None = Field(None, gt=0.3, le=30)
    """Maneuver duration t_L - t_0 (None: free final time, chosen between
    ``min_duration`` and ``max_duration`` by minimising cost + k_time T) [s]."""
    min_duration: float = Field(0.8, gt=0.3, le=30)
    """Shortest duration of the free-final-time search [s]."""
    max_duration: float = Field(4.0, gt=0.3, le=30)
    """Longest duration of the free-final-time search [s]."""
    nodes: int = Field(50, ge=10, le=2000)
    """Shooting intervals N [-]."""
    integrator_step: float = Field(0.04, gt=0, le=1)
    """Largest RK4 step of the shooting integrator [s]."""
    max_pitch_deg: float = Field(80.0, gt=0, lt=90)
    """Largest |pitch| of the thrust axis from vertical along the plan [deg]."""
    clearance_margin: float = Field(0.0, ge=0, le=1)
    """Least clearance of the landers and rotor guards above the surface before t_L [m]."""
    hover_time: float = Field(4.0, ge=0, le=60)
    """Hover at the start point before the maneuver starts (closed-loop run) [s]."""
    rest_time: float = Field(1.5, gt=0, le=60)
    """Simulated time with the motors off after touchdown (closed-loop run), at least
    ``verdict.min_rest_time`` plus the rotors' spin-down [s]."""
    contact_grace: float = Field(0.1, ge=0, le=5)
    """Longest flight past the planned touchdown time, holding the touchdown thrust and
    attitude, while waiting for (estimated) contact; then the motors go off anyway [s]."""
    lag_compensation: bool = True
    """Lead the rotor-speed commands by the motor lag along the planned thrust profile."""
    model_rotor_drag: bool = True
    """Put the believed rotor drag (``controller.rotor_drag``, d_x: the plan's motion is in
    the x_B-z_B plane) into the plan's dynamics, so that the planned attitude and thrust
    fly the path through the drag; no effect while the believed drag is zero (the plan is
    then the drag-free plan, bit for bit) [-]."""
    weights: PerchingWeights = PerchingWeights()

    @model_validator(mode="after")
    def _durations(self) -> PerchingConfig:
        if self.min_duration >= self.max_duration:
            raise ValueError(
                f"min_duration = {self.min_duration} s must be < max_duration = "
                f"{self.max_duration} s"
            )
        return self
