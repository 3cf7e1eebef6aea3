"""The physical scenario: vehicle, tether, surface and anchor (docs/theory.md sections 3, 4, 12)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from enum import StrEnum
from types import MappingProxyType
from typing import Literal, NamedTuple

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


class TetherMaterial(NamedTuple):
    """Axial stiffness and mass of a 1 mm line of one material (docs/tether.md).

    Attributes
    ----------
    name : str
    axial_stiffness : float or None
        Effective EA of the line, None for an inextensible cable [N].
    linear_density : float
        Mass per length [kg/m].
    source : str
        Where the numbers come from.
    """

    name: str
    axial_stiffness: float | None
    linear_density: float
    source: str


TETHER_MATERIALS: Mapping[str, TetherMaterial] = MappingProxyType(
    {
        "ideal": TetherMaterial(
            "ideal", None, 0.0, "inextensible and massless (the chapter's cable)"
        ),
        "dyneema": TetherMaterial(
            "dyneema",
            1.5e4,
            6.0e-4,
            "12-strand HMPE braid of Dyneema SK78: fibre modulus 109-132 GPa, elongation at "
            "break 3-4 % (DSM Dyneema fact sheet CIS YA100, 2010); 0.6 g/m of fibre is "
            "0.62 mm2 at 975 kg/m3, fibre EA 7.4e4 N, of which a braid keeps about 20 % at "
            "low load (construction stretch)",
        ),
        "nylon": TetherMaterial(
            "nylon",
            1.2e3,
            9.0e-4,
            "polyamide 6.6 monofilament: tensile modulus about 1.5 GPa conditioned "
            "(2.8 GPa dry, DuPont Zytel 101 data sheet), 1140 kg/m3, on 0.785 mm2",
        ),
        "steel": TetherMaterial(
            "steel",
            4.4e4,
            3.5e-3,
            "7x7 stainless wire rope: metallic area 0.44 mm2 (fill factor 0.56 from the "
            "API 9A / ISO 2408 mass table, 6x7 class), rope modulus about 100 GPa on the "
            "metallic area, 7900 kg/m3",
        ),
    }
)
"""Presets of ``tether.material`` for a 1 mm line; the derivations are in docs/tether.md."""

TetherMaterialName = Literal["ideal", "dyneema", "nylon", "steel"]


class CableModel(StrEnum):
    """How the plant simulates the cable (docs/tether.md)."""

    IDEAL = "ideal"
    """Inextensible, massless: a limited tendon (a unilateral constraint at l)."""
    ELASTIC = "elastic"
    """Massless and elastic: a unilateral spring-damper on the anchor-attachment distance."""
    CHAIN = "chain"
    """Massive: ``segments`` rigid links with ball joints, the stretch added quasi-statically."""


class TetherConfig(Section):
    """The cable between the anchor and the vehicle, its material, and its hook.

    Cable (docs/tether.md): ``material`` presets the effective axial stiffness EA and the
    linear density of a 1 mm line (:data:`TETHER_MATERIALS`); ``axial_stiffness`` and
    ``linear_density`` override the preset. Taut, the cable pulls with
    f_L = k x + c x' (x = distance - l > 0, k = EA/l, c = 2 zeta sqrt(k m), m the
    vehicle mass) and never pushes; slack, it exerts no force. ``segments = 0`` models it
    massless (the preset's density is then not used: a 1 m line of 1 mm weighs under
    4 g); ``segments >= 1`` simulates that many massive links that drape when slack.
    Giving a ``linear_density > 0`` with ``segments = 0``, or ``segments >= 1`` with a
    zero density, is an error.

    Hook model (simulation, chapter 6.6.1): the hook point is the attachment point moved
    by ``hook_drop`` along the approach direction n (for the default n = -z_W the hook
    hanging under the vehicle; for another direction a hook held out along n, e.g.
    horizontally toward a wall). The cable engages when
    the hook point crosses the capture disk (centre p_A, normal ``approach_direction``,
    radius ``capture_radius``) moving along the approach direction, and releases when it
    crosses the disk again the opposite way.
    """

    length: float = Field(1.0, gt=0, le=100)
    """Unstretched cable length l from the anchor to the attachment point [m]."""
    material: TetherMaterialName = "dyneema"
    """Preset of EA and linear density for a 1 mm line: ``ideal`` (inextensible,
    massless), ``dyneema`` (EA 1.5e4 N, 0.6 g/m), ``nylon`` (1.2e3 N, 0.9 g/m), ``steel``
    (7x7 wire rope, 4.4e4 N, 3.5 g/m) [-]."""
    axial_stiffness: float | None = Field(None, gt=0, le=1e7)
    """Effective axial stiffness EA, overriding the material's; k = EA/l [N]."""
    damping_ratio: float = Field(0.05, ge=0, le=2)
    """Damping ratio zeta of the taut cable with the vehicle mass, c = 2 zeta sqrt(k m) [-]."""
    linear_density: float | None = Field(None, ge=0, le=10)
    """Mass per length, overriding the material's (needs ``segments >= 1``) [kg/m]."""
    segments: int = Field(0, ge=0, le=50)
    """Number of massive links simulated; 0 models the cable massless [-]."""
    capture_radius: float = Field(0.1, gt=0, le=10)
    """Radius of the capture disk around the anchor within which the hook catches [m]."""
    approach_direction: Vec3 = (0.0, 0.0, -1.0)
    """Direction in F_A in which the hook point must cross the capture disk to engage
    (default: lowered vertically onto the anchor); reversing through it releases [-]."""
    hook_drop: float = Field(0.5, ge=0, le=100)
    """Distance of the hook point from the attachment point, along the approach direction
    (below it for the default approach); 0 puts the hook at the attachment point [m]."""

    @field_validator("approach_direction")
    @classmethod
    def _nonzero_direction(cls, value: Vec3) -> Vec3:
        if sum(v * v for v in value) < 1e-18:
            raise ValueError("approach_direction must be a non-zero vector")
        return value

    @model_validator(mode="after")
    def _mass_needs_segments(self) -> TetherConfig:
        rho = self.linear_density
        if rho is not None and rho > 0 and self.segments == 0:
            raise ValueError(
                f"linear_density = {rho:g} kg/m needs segments >= 1 (segments = 0 is the "
                "massless cable; remove linear_density or simulate segments in [1, 50])"
            )
        if self.segments > 0 and self.mass_per_length <= 0.0:
            raise ValueError(
                f"segments = {self.segments} needs a linear_density > 0 kg/m (material "
                f"'{self.material}' gives {TETHER_MATERIALS[self.material].linear_density:g}); "
                "set linear_density in (0, 10] or segments = 0"
            )
        return self

    # -- resolved cable parameters -----------------------------------------------------

    @property
    def effective_axial_stiffness(self) -> float | None:
        """Effective axial stiffness: ``axial_stiffness`` or the material's; None if
        inextensible [N]."""
        if self.axial_stiffness is not None:
            return self.axial_stiffness
        return TETHER_MATERIALS[self.material].axial_stiffness

    @property
    def stiffness(self) -> float | None:
        """Spring constant k = EA/l of the taut cable; None if inextensible [N/m]."""
        EA = self.effective_axial_stiffness
        return None if EA is None else EA / self.length

    @property
    def mass_per_length(self) -> float:
        """Simulated linear density: ``linear_density``, else the material's when
        ``segments >= 1``, else 0 (massless) [kg/m]."""
        if self.linear_density is not None:
            return self.linear_density
        return TETHER_MATERIALS[self.material].linear_density if self.segments > 0 else 0.0

    @property
    def cable_model(self) -> CableModel:
        """How the plant simulates this cable."""
        if self.segments > 0:
            return CableModel.CHAIN
        return CableModel.IDEAL if self.stiffness is None else CableModel.ELASTIC

    def damping(self, mass: float) -> float:
        """Damping coefficient c = 2 zeta sqrt(k m) of the taut cable holding ``mass`` [N s/m]
        (0 if inextensible)."""
        k = self.stiffness
        return 0.0 if k is None else 2.0 * self.damping_ratio * math.sqrt(k * mass)

    def stretch(self, tension: float) -> float:
        """Static elongation f_L l / EA of the cable under ``tension`` [N] (0 if
        inextensible or slack) [m]."""
        k = self.stiffness
        return 0.0 if k is None or tension <= 0.0 else tension / k


class SurfaceConfig(Section):
    """The landing and takeoff surface P_S: a tilted plane, or a tilted pipe.

    The orientation is a slope angle and a downhill azimuth, or a normal vector (not both).
    For a pipe, P_S is the plane tangent to the pipe along its top line, the pipe axis runs
    downhill, and ``origin`` lies on the top line.
    """

    kind: Literal["plane", "pipe"] = "plane"
    """Surface type."""
    slope_deg: float = Field(50.0, ge=0, le=180)
    """Slope angle beta between the surface and the horizontal: 90 is a vertical wall,
    above 90 an overhang (the surface faces down, n_S . z_W = cos(beta) < 0) [deg]."""
    azimuth_deg: float = Field(0.0, ge=-360, le=360)
    """Azimuth of the downhill direction x_S in the horizontal plane, from x_W towards y_W [deg]."""
    normal: Vec3 | None = None
    """Alternative to slope/azimuth: the outward surface normal n_S in F_W, pointing to the
    side the vehicle lands on (any length, not zero; a negative z component is an
    overhang) [-]."""
    origin: Vec3 = (0.0, 0.0, 0.0)
    """A point O_S on the surface (the top line for a pipe), in F_W [m]."""
    friction: float = Field(0.6, ge=0, le=10)
    """Friction coefficient mu between the landers and the surface [-]."""
    f_N_min: float = Field(0.0, ge=-1000, le=0)
    """Minimum normal force: 0 for a plain surface, negative with an adhesive pad; the
    shear limit is f_S_max = mu (f_N - f_N_min) [N]."""
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
