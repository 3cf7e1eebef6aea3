"""Settings of the landing/takeoff trajectory planner (docs/theory.md section 6)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from tetherland.config.base import Section


class PlannerWeights(Section):
    """Gains k_* >= 0 of the cost J = integral(J1 + J2 + J3 + J4) + J5 (section 6.5.2).

    Angles in rad, rates in rad/s, rotor thrust accelerations f_i'' in N/s^2; each weight's
    unit makes its integrand (J1-J4) or its terminal term (J5) a plain number.
    """

    k_phi: float = Field(1.0, ge=0, le=1e6)
    """J1: (phi - phi_f)^2, elevation error to the maneuver's final value [rad^-2]."""
    k_theta: float = Field(1.0, ge=0, le=1e6)
    """J1: (theta_A - theta_A,f)^2, tilt error to the final value [rad^-2]."""
    k_phi_dot: float = Field(0.5, ge=0, le=1e6)
    """J1: phi'^2, the link elevation rate [(rad/s)^-2]."""
    k_theta_dot: float = Field(0.5, ge=0, le=1e6)
    """J1: theta_A'^2, the tilt rate [(rad/s)^-2]."""
    k_phi_ddot: float = Field(0.05, ge=0, le=1e6)
    """J1: phi''^2, the link elevation acceleration [(rad/s^2)^-2]."""
    k_theta_ddot: float = Field(0.05, ge=0, le=1e6)
    """J1: theta_A''^2, the tilt acceleration [(rad/s^2)^-2]."""
    k_theta_near: float = Field(20.0, ge=0, le=1e6)
    """J2: h(phi) (theta_A - theta_A*)^2, the landing attitude near the surface [rad^-2]."""
    k_rates_near: float = Field(20.0, ge=0, le=1e6)
    """J3: h(phi) (phi'^2 + theta_A'^2), slow near the surface [(rad/s)^-2]."""
    k_thrust_accel: float = Field(1e-3, ge=0, le=1e6)
    """J4: sum f_i''^2, smooth rotor commands [(N/s^2)^-2]."""
    k_final_theta_dot: float = Field(10.0, ge=0, le=1e6)
    """J5: theta_A'(t_L)^2 (zero at the optimum: the final rates are also constrained)
    [(rad/s)^-2]."""
    k_final_phi_dot: float = Field(10.0, ge=0, le=1e6)
    """J5: phi'(t_L)^2 (zero at the optimum: the final rates are also constrained)
    [(rad/s)^-2]."""
    bump_width_deg: float = Field(10.0, gt=0, le=90)
    """Half-width w of the bumps h(phi) = exp(-((phi - phi*)/w)^4) of J2 and J3 [deg]."""


class PlannerConfig(Section):
    """The optimal planner (OCP 6.21) or the spline alternative, and the maneuver's ends."""

    method: Literal["ocp", "spline"] = "ocp"
    """Trajectory generator: the optimal control problem (6.21) or a smooth spline."""
    solver: Literal["fatrop", "ipopt"] = "fatrop"
    """NLP solver for the OCP."""
    fallback_solver: bool = True
    """Retry with IPOPT when fatrop returns no acceptable solution."""
    nodes: int = Field(50, ge=10, le=2000)
    """Number of shooting intervals N [-]."""
    integrator_step: float = Field(0.08, gt=0, le=1)
    """Largest RK4 step of the shooting integrator: ceil(T / (N step)) steps per interval;
    doubled (twice at most) when a solution fails the fine re-simulation check [s]."""
    landing_duration: float = Field(4.0, gt=0.5, le=60)
    """Duration t_L - t_0 of the tethered landing [s]."""
    takeoff_duration: float = Field(4.0, gt=0.5, le=60)
    """Duration of the tethered takeoff [s]."""
    start_elevation_offset_deg: float = Field(35.0, gt=0, le=120)
    """Link elevation of the taut start (landing) / end (takeoff) hover above phi* [deg]."""
    start_tension: float = Field(2.0, gt=0, le=1000)
    """Cable tension held in the taut start/end hover [N]."""
    min_tension: float = Field(0.3, gt=0, le=1000)
    """Lower bound f_L_min on the tension along the planned trajectory (6.21d). Near a
    boundary hover whose own tension is lower (a flat surface has none when landed) the
    bound ramps down to that tension over ``tension_ramp`` of the duration [N]."""
    tension_ramp: float = Field(0.25, gt=0, le=0.5)
    """Fraction of the duration over which the tension bound relaxes towards a boundary [-]."""
    heading_deg: float = Field(0.0, ge=-180, le=180)
    """psi*, the robot's rotation about z_B during the maneuver (free, section 6.5.1) [deg]."""
    tolerance: float = Field(1e-6, gt=0, le=1e-2)
    """Convergence tolerance of the NLP solver [-]."""
    max_iter: int = Field(500, ge=1, le=100000)
    """Iteration limit of the NLP solver [-]."""
    mu_init: float = Field(1e-2, gt=0, le=10)
    """Initial barrier parameter of the interior-point solvers; the default suits the
    cold start from the spline reference (the solvers' own default is 0.1) [-]."""
    model_ground_effect: bool = False
    """Bound the rotor *commands* f_i / k_i rather than the acting thrusts f_i, with k_i
    the believed ground-effect factor of rotor i along the planned path (believed surface
    and rotor radius, as ``estimator.ground_effect_belief``; a plane or pipe surface;
    :mod:`tetherland.planning.ground_effect`). Off: the plan bounds the acting thrusts,
    which ``controller.ground_effect_compensation`` makes the commands divided by k
    (docs/aero.md) [-]."""
    weights: PlannerWeights = PlannerWeights()
    """Cost gains of J1..J5 and the bump width."""
