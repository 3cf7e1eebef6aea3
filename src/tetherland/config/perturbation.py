"""Ranges of what goes wrong in practice, for randomised campaigns (issue 7).

Each run draws one :class:`~tetherland.campaign.perturb.Perturbation` from these ranges
with its own seed. The scenario as given is the truth the plant simulates; the planner,
controllers and estimator use a *belief* with model and pose errors.
"""

from __future__ import annotations

from pydantic import Field, model_validator

from tetherland.config.base import Section


class PerturbationConfig(Section):
    """Half-widths of uniform error distributions (0 disables a perturbation).

    Surface and anchor errors default to what a motion-capture measurement of markers on
    the surface gives (the chapter's setup, section 6.6.2): about 1 deg and 1 cm.
    """

    mass_rel: float = Field(0.05, ge=0, le=0.5)
    """Relative error of the believed mass [-]."""
    inertia_rel: float = Field(0.10, ge=0, le=0.5)
    """Relative error of each believed principal inertia [-]."""
    thrust_coefficient_rel: float = Field(0.05, ge=0, le=0.5)
    """Relative error of the believed rotor thrust coefficient c_f [-]."""
    motor_time_constant_rel: float = Field(0.20, ge=0, le=0.9)
    """Relative error of the believed motor time constant [-]."""
    slope_error_deg: float = Field(1.0, ge=0, le=20)
    """Error of the believed slope angle [deg]."""
    azimuth_error_deg: float = Field(1.0, ge=0, le=45)
    """Error of the believed downhill azimuth [deg]."""
    anchor_error: float = Field(0.01, ge=0, le=0.5)
    """Error of the believed anchor position along each surface axis x_S, y_S and z_S
    (the last one is an error of the believed anchor height h_A) [m]."""
    surface_offset_error: float = Field(0.005, ge=0, le=0.5)
    """Error of the believed surface position along its normal (the believed plane or
    pipe top line is moved by up to this towards or away from the vehicle) [m]."""
    pipe_radius_error: float = Field(0.002, ge=0, le=0.5)
    """Error of the believed pipe radius (``surface.kind = "pipe"`` only) [m]."""
    noise_scale_min: float = Field(0.5, ge=0, le=100)
    """Smallest sensor-noise multiplier of the plant [-]."""
    noise_scale_max: float = Field(2.0, ge=0, le=100)
    """Largest sensor-noise multiplier of the plant [-]."""
    wind_gust_force: float = Field(0.5, ge=0, le=50)
    """Largest peak horizontal gust force on the vehicle [N]."""
    wind_gust_rate: float = Field(0.2, ge=0, le=10)
    """Mean number of gusts per second (Poisson) [1/s]."""
    wind_gust_duration: float = Field(0.5, gt=0, le=10)
    """Duration of one gust (raised-cosine profile) [s]."""
    mocap_dropout_rate: float = Field(0.1, ge=0, le=10)
    """Mean motion-capture dropouts per second in the plant [1/s]."""
    mocap_dropout_duration: float = Field(0.2, ge=0, le=5)
    """Length of each dropout [s]."""

    @model_validator(mode="after")
    def _ordered(self) -> PerturbationConfig:
        if self.noise_scale_min > self.noise_scale_max:
            raise ValueError(
                f"noise_scale_min = {self.noise_scale_min} must be <= noise_scale_max = "
                f"{self.noise_scale_max}"
            )
        return self
