"""Controller settings (docs/theory.md section 7).

Gains are given as natural frequencies and damping ratios of the closed-loop error
dynamics (mass and inertia are taken from the vehicle), so they stay meaningful when the
vehicle changes.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from tetherland.config.aero import ROTOR_DRAG_DEFAULT, DragCoefficient
from tetherland.config.base import Section


class FreeFlightGains(Section):
    """Geometric position and SO(3) attitude control (Lee, Leok, McClamroch 2010)."""

    position_frequency: float = Field(2.5, gt=0, le=50)
    """Natural frequency of the position error dynamics [rad/s]."""
    position_damping: float = Field(1.0, gt=0, le=5)
    """Damping ratio of the position error dynamics [-]."""
    attitude_frequency: float = Field(14.0, gt=0, le=200)
    """Natural frequency of the roll/pitch attitude error dynamics [rad/s]."""
    attitude_damping: float = Field(0.9, gt=0, le=5)
    """Damping ratio of the roll/pitch attitude error dynamics [-]."""
    yaw_frequency: float = Field(5.0, gt=0, le=200)
    """Natural frequency of the yaw error dynamics [rad/s]."""
    yaw_damping: float = Field(1.0, gt=0, le=5)
    """Damping ratio of the yaw error dynamics [-]."""
    position_integral: float = Field(4.0, ge=0, le=1000)
    """Integral gain k_i of the position loop (cancels thrust and mass model errors) [1/s^3]."""
    integral_force_max: float = Field(0.2, ge=0, le=1)
    """Largest integral force per axis as a fraction of m g (anti-windup clamp) [-]."""
    max_tilt_deg: float = Field(60.0, gt=0, lt=90)
    """Largest commanded tilt of the thrust axis from vertical in free flight [deg]."""


class TetheredGains(Section):
    """Tethered controllers: hierarchical Gamma_HC^b and DFL Gamma_DFL^b
    (docs/theory.md section 7)."""

    link_frequency: float = Field(3.0, gt=0, le=50)
    """Hierarchical outer loop: natural frequency of the phi and delta errors [rad/s]."""
    link_damping: float = Field(1.0, gt=0, le=5)
    """Hierarchical outer loop: damping ratio of the phi and delta errors [-]."""
    attitude_frequency: float = Field(14.0, gt=0, le=200)
    """Inner attitude loop: natural frequency (roll/pitch) [rad/s]."""
    attitude_damping: float = Field(0.9, gt=0, le=5)
    """Inner attitude loop: damping ratio (roll/pitch) [-]."""
    yaw_frequency: float = Field(5.0, gt=0, le=200)
    """Inner attitude loop: natural frequency about z_B [rad/s]."""
    yaw_damping: float = Field(1.0, gt=0, le=5)
    """Inner attitude loop: damping ratio about z_B [-]."""
    link_integral: float = Field(6.0, ge=0, le=1000)
    """Hierarchical outer loop: integral gain on the phi and delta errors [1/s^3]."""
    link_integral_max: float = Field(1.0, ge=0, le=100)
    """Largest integral contribution to phi'' and delta'' (anti-windup clamp) [rad/s^2]."""
    dfl_link_pole: float = Field(3.0, gt=0, le=50)
    """DFL: repeated pole of the 4th-order phi and delta error dynamics, (s + p)^4 [rad/s]."""
    dfl_attitude_pole: float = Field(8.0, gt=0, le=100)
    """DFL: repeated pole of the 2nd-order theta_A and psi error dynamics, (s + p)^2 [rad/s]."""
    dfl_integral: bool = True
    """DFL: add integral action, one more pole of the same value in each error polynomial,
    (s + p)^(r+1), so model errors (thrust, offset torque) leave no steady tracking error."""
    dfl_integral_max: float = Field(0.3, ge=0, le=10)
    """DFL: clamp of each error integral (anti-windup) [rad s]."""
    lateral_damping: float = Field(0.5, ge=0, le=1)
    """Hierarchical, with the link azimuth left to gravity (``Reference.lateral_free``, the
    last centimetres of a landing): the fraction of the link damping k_d kept on delta'.
    The sideways force is then only this damping, and it tilts the thrust axis by
    k_d v/(f_R/m) for a sideways speed v: a gust's push met at full damping turns the
    frame at 0.3 rad/s within 0.15 s at 70 deg [-]."""
    offset_compensation: bool = True
    """Cancel the torque of the cable attachment offset with the estimated tension (6.6.5)."""
    integral_hand_over: bool = True
    """Hierarchical law: when tethered control starts from free flight, start the link
    integral where the first command continues the last free-flight force across the link
    (the model error the free-flight integral held is kept; docs/theory.md 7.5); off: the
    integral starts empty."""


class ControllerConfig(Section):
    """Which tethered controller runs, its rate and the gains."""

    kind: Literal["hierarchical", "dfl"] = "hierarchical"
    """Tethered controller: hierarchical Gamma_HC^b or dynamic feedback linearisation."""
    ground_effect_compensation: bool = True
    """Divide each rotor's commanded speed by the square root of its ground-effect factor
    over the believed surface at the estimated pose, so that the thrust believed acting is
    the thrust wanted (false: the integrals absorb the ground effect)."""
    rotor_drag: tuple[DragCoefficient, DragCoefficient] = (ROTOR_DRAG_DEFAULT, ROTOR_DRAG_DEFAULT)
    """Believed rotor drag (d_x, d_y) of the vehicle (the same published fit as the
    plant's default, ``aero.rotor_drag``, which the robot never reads): the position
    references' acceleration gets the drag of the reference velocity as a feed-forward
    (and the tethered references', ``rotor_drag_tethered``), and the perching planner
    models it (``perching.model_rotor_drag``); the default is the plant's; [0, 0] leaves
    the drag to the feedback and the integrals [N s/m]."""
    rotor_drag_tethered: bool = True
    """The believed rotor drag's feed-forward also on tethered references (as link
    accelerations, :func:`tetherland.control.rotor_drag.link_drag_acceleration`); false:
    free-flight references only, the link integral absorbs the drag of the tethered
    swing [-]."""
    rate_hz: float = Field(500.0, gt=0, le=5000)
    """Control rate (rotor-speed commands to the ESCs, section 6.6.4) [Hz]."""
    free_flight: FreeFlightGains = FreeFlightGains()
    """Free-flight gains."""
    tethered: TetheredGains = TetheredGains()
    """Tethered-controller gains."""
