"""The physical scenario: vehicle, tether, surface and anchor (docs/theory.md sections 3, 4, 12)."""

from __future__ import annotations

from typing import Literal

from pydantic import Field, field_validator, model_validator

from tetherland.config.base import PositiveVec3, Section, Vec3


class VehicleConfig(Section):
    """A quadrotor with four landers and a cable attachment point.

    Rotors are numbered counter-clockwise seen from above, starting at the front-left
    rotor (``layout = "x"``: azimuths 45, 135, 225, 315 deg in F_B) or at the front rotor
    (``layout = "+"``: 0, 90, 180, 270 deg).
    """

    mass: float = Field(1.0, gt=0, le=100)
    """Total mass m [kg]."""
    inertia: PositiveVec3 = (0.015, 0.015, 0.025)
    """Principal moments of inertia (J_xx, J_yy, J_zz) about the centre of mass, F_B [kg m^2]."""
    layout: Literal["x", "+"] = "x"
    """Rotor layout: ``x`` (rotors at 45 deg to the body axes) or ``+``."""
    arm_length: float = Field(0.23, gt=0, le=2)
    """Distance from the centre of mass to each rotor axis [m]."""
    rotor_spins: tuple[Literal[-1, 1], Literal[-1, 1], Literal[-1, 1], Literal[-1, 1]] = (
        1,
        -1,
        1,
        -1,
    )
    """Sign sigma_i of the yaw torque about z_B per newton of thrust of rotor i [-]."""
    f_min: float = Field(0.2, ge=0, le=100)
    """Minimum thrust per rotor f_min > 0: propellers cannot reverse [N]."""
    f_max: float = Field(6.0, gt=0, le=200)
    """Maximum thrust per rotor [N]."""
    thrust_coefficient: float = Field(1.0e-5, gt=0, le=1)
    """c_f in f_i = c_f w_i^2 [N/(rad/s)^2]."""
    drag_coefficient: float = Field(0.016, ge=0, le=1)
    """c_tau: yaw torque per newton of thrust [m]."""
    motor_time_constant: float = Field(0.03, ge=0, le=1)
    """Time constant tau_m of the first-order lag on rotor speed [s]."""
    h_R: float = Field(0.10, gt=0, le=2)
    """Distance from the centre of mass to the landers plane P_RL along -z_B [m]."""
    lander_half_width: float = Field(0.15, gt=0, le=2)
    """Lander tips at (+-w, +-w, -h_R) in F_B [m]."""
    lander_radius: float = Field(0.01, gt=0, le=0.2)
    """Radius of the spherical lander tips (collision geometry) [m]."""
    cable_attachment: Vec3 = (0.0, 0.0, -0.03)
    """Cable attachment point r_att in F_B, offset from the centre of mass (6.6.5) [m]."""
    control_margin: float = Field(0.25, ge=0, le=100)
    """Thrust per rotor reserved for attitude control when judging feasibility [N]."""

    @field_validator("inertia")
    @classmethod
    def _triangle_inequality(cls, value: PositiveVec3) -> PositiveVec3:
        jx, jy, jz = value
        if jx + jy < jz or jy + jz < jx or jx + jz < jy:
            raise ValueError(
                "principal inertias must satisfy the triangle inequality "
                f"(J_a + J_b >= J_c), got {value}"
            )
        return value

    @model_validator(mode="after")
    def _thrust_limits(self) -> VehicleConfig:
        if self.f_min >= self.f_max:
            raise ValueError(
                f"f_min = {self.f_min} N must be < f_max = {self.f_max} N "
                "(allowed range 0 <= f_min < f_max)"
            )
        if self.control_margin * 2 >= self.f_max - self.f_min:
            raise ValueError(
                f"control_margin = {self.control_margin} N must be < (f_max - f_min)/2 = "
                f"{(self.f_max - self.f_min) / 2:g} N"
            )
        if self.lander_radius >= self.h_R:
            raise ValueError(f"lander_radius = {self.lander_radius} m must be < h_R = {self.h_R} m")
        return self


class TetherConfig(Section):
    """A passive cable of constant length between the anchor and the vehicle, and its hook.

    Hook model (simulation, chapter 6.6.1): the hook point is the attachment point lowered
    by ``hook_drop`` along -z_W (the hook hanging under the vehicle). The cable engages when
    the hook point crosses the capture disk (centre p_A, normal ``approach_direction``,
    radius ``capture_radius``) moving along the approach direction, and releases when it
    crosses the disk again the opposite way.
    """

    length: float = Field(1.0, gt=0, le=100)
    """Cable length l from the anchor to the attachment point [m]."""
    capture_radius: float = Field(0.1, gt=0, le=10)
    """Radius of the capture disk around the anchor within which the hook catches [m]."""
    approach_direction: Vec3 = (0.0, 0.0, -1.0)
    """Direction in F_A in which the hook point must cross the capture disk to engage
    (default: lowered vertically onto the anchor); reversing through it releases [-]."""
    hook_drop: float = Field(0.5, ge=0, le=100)
    """Distance of the hook point below the attachment point, along -z_W; 0 puts the hook
    at the attachment point [m]."""

    @field_validator("approach_direction")
    @classmethod
    def _nonzero_direction(cls, value: Vec3) -> Vec3:
        if sum(v * v for v in value) < 1e-18:
            raise ValueError("approach_direction must be a non-zero vector")
        return value

    @model_validator(mode="after")
    def _hook_within_reach(self) -> TetherConfig:
        if self.hook_drop + self.capture_radius >= self.length:
            raise ValueError(
                f"hook_drop + capture_radius = {self.hook_drop + self.capture_radius:g} m must "
                f"be < length = {self.length} m (the cable must be slack when the hook catches)"
            )
        return self


class SurfaceConfig(Section):
    """The landing and takeoff surface P_S: a tilted plane, or a tilted pipe.

    The orientation is a slope angle and a downhill azimuth, or a normal vector (not both).
    For a pipe, P_S is the plane tangent to the pipe along its top line, the pipe axis runs
    downhill, and ``origin`` lies on the top line.
    """

    kind: Literal["plane", "pipe"] = "plane"
    """Surface type."""
    slope_deg: float = Field(50.0, ge=0, le=180)
    """Slope angle beta between the surface and the horizontal [deg]: 90 is a vertical wall,
    above 90 an overhang (the surface faces down, n_S . z_W = cos(beta) < 0)."""
    azimuth_deg: float = Field(0.0, ge=-360, le=360)
    """Azimuth of the downhill direction x_S in the horizontal plane, from x_W towards y_W [deg]."""
    normal: Vec3 | None = None
    """Alternative to slope/azimuth: the outward surface normal n_S in F_W, pointing to the
    side the vehicle lands on (any length, not zero; a negative z component is an overhang)."""
    origin: Vec3 = (0.0, 0.0, 0.0)
    """A point O_S on the surface (the top line for a pipe), in F_W [m]."""
    friction: float = Field(0.6, ge=0, le=10)
    """Friction coefficient mu between the landers and the surface [-]."""
    f_N_min: float = Field(0.0, ge=-1000, le=0)
    """Minimum normal force: 0 for a plain surface, negative with an adhesive pad [N].
    The shear limit is f_S_max = mu (f_N - f_N_min)."""
    pipe_radius: float = Field(0.25, gt=0, le=10)
    """Pipe radius (``kind = "pipe"`` only) [m]."""
    extent: float = Field(3.0, gt=0, le=100)
    """Half-length of the simulated surface patch along x_S, y_S (plane) or its axis (pipe) [m]."""

    @field_validator("normal")
    @classmethod
    def _nonzero_normal(cls, value: Vec3 | None) -> Vec3 | None:
        if value is not None and sum(v * v for v in value) < 1e-18:
            raise ValueError("normal must be a non-zero vector")
        return value

    @model_validator(mode="after")
    def _one_orientation(self) -> SurfaceConfig:
        given = {"slope_deg", "azimuth_deg"} & self.model_fields_set
        if self.normal is not None and given:
            raise ValueError(
                f"normal and {sorted(given)[0]} are mutually exclusive: give the normal, "
                "or slope_deg and azimuth_deg"
            )
        return self


class AnchorConfig(Section):
    """Where the cable is anchored: an explicit point, or placed by (6.13) for a landing point.

    Give at most one of ``position`` and ``landing_point``; by default the desired landing
    point p*_L is the surface origin and the anchor is placed by (6.13).
    """

    position: Vec3 | None = None
    """Explicit anchor point p_A in F_W; must lie at height h_A above the surface [m]."""
    landing_point: Vec3 | None = None
    """Desired landing point p*_L on the surface in F_W; the anchor is placed by (6.13) [m]."""
    h_A: float = Field(0.0, ge=0, le=10)
    """Height of the anchor above the surface, h_A = z_S.(p_A - p) for p on P_S [m]."""

    @model_validator(mode="after")
    def _one_placement(self) -> AnchorConfig:
        if self.position is not None and self.landing_point is not None:
            raise ValueError("position and landing_point are mutually exclusive: give at most one")
        return self
