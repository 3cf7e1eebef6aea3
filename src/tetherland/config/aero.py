"""Rotors near surfaces and rotor drag (``[aero]``, the plant's truth), issue 23.

The models and their sources are in :mod:`tetherland.models.aero`. The robot never reads
this section: what the controllers believe about these effects is their own business.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import Field, model_validator

from tetherland.config.base import Section

DragCoefficient = Annotated[float, Field(ge=0, le=10)]
"""One rotor-drag coefficient, in [0, 10] N s/m."""

ROTOR_DRAG_DEFAULT = 0.45
"""Rotor drag of the default 1 kg vehicle at the hover speed [N s/m]: rotorpy's AscTec
Hummingbird parameters (k_d = 1.19e-4 kg/rad per rotor, k_eta = 5.57e-6 N/(rad/s)^2,
0.5 kg) give 4 k_d w_h / m = 4 * 1.19e-4 * 469 / 0.5 = 0.45 /s of mass-normalised drag
(the form of Faessler, Franchi and Scaramuzza 2018), carried to 1 kg."""


class AeroConfig(Section):
    """Ground, ceiling and wall effects on each rotor, and rotor drag (the plant's truth).

    With ``ground_effect = false``, ``wall_effect = false`` and ``rotor_drag = [0, 0]``
    the plant is the plain c_f w^2 plant, bit for bit.
    """

    ground_effect: bool = True
    """Each rotor's thrust (and drag torque) is multiplied by its surface factor: the
    Cheeseman-Bennett ground effect over the covered part of its disk, and the ceiling
    effect on its inflow side."""
    wall_effect: bool = False
    """A wall across a rotor's disk plane draws the rotor toward it (a documented simple
    model, see ``wall_coefficient``)."""
    rotor_drag: tuple[DragCoefficient, DragCoefficient] = (ROTOR_DRAG_DEFAULT, ROTOR_DRAG_DEFAULT)
    """(d_x, d_y) of the rotor drag F = -R_WB diag(d_x, d_y, 0) R_WB^T v at the hover
    rotor speed, scaled with the mean rotor speed; [0, 0] switches it off. On by default
    at the published fit, ``ROTOR_DRAG_DEFAULT`` (docs/aero.md measures it on and off)
    [N s/m]."""
    rotor_radius: float | None = Field(None, gt=0, le=1)
    """Rotor radius R; by default the rotor-guard radius, 0.4 arm_length [m]."""
    disk_rings: int = Field(3, ge=1, le=8)
    """Rings of equal-area sample points over each rotor disk [-]."""
    disk_sectors: int = Field(8, ge=2, le=32)
    """Sample points per ring [-]."""
    min_distance_ratio: float = Field(0.5, ge=0.3, le=2)
    """Lower bound z_min / R of the distance used in the ground and ceiling factors (the
    image formula has its pole at z = R/4; at the default 0.5 the bound is 4/3) [-]."""
    ceiling_coefficient: float = Field(0.0625, ge=0, le=0.25)
    """k_c of the ceiling factor 1 / (1 - k_c (R/z)^2); 1/16 mirrors the ground effect [-]."""
    wall_coefficient: float = Field(0.05, ge=0, le=1)
    """k_w of the wall pull k_w f (R / max(d, R))^2 (an assumption: a few percent of the
    rotor's thrust when its disk edge touches the wall) [-]."""

    @model_validator(mode="after")
    def _bound_below_pole(self) -> AeroConfig:
        k = max(self.ceiling_coefficient, 0.0625)
        if self.min_distance_ratio**2 <= 1.2 * k:
            raise ValueError(
                f"aero.min_distance_ratio = {self.min_distance_ratio} must be > "
                f"sqrt(1.2 max(ceiling_coefficient, 1/16)) = {(1.2 * k) ** 0.5:.3g} "
                "(the factor's pole is at sqrt(k))"
            )
        return self

    @property
    def active(self) -> bool:
        """Any effect switched on."""
        return self.ground_effect or self.wall_effect or any(d > 0 for d in self.rotor_drag)
