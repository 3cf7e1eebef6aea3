"""State and cable-tension estimation (docs/theory.md section 8)."""

from tetherland.estimation.estimator import UkfEstimator
from tetherland.estimation.tension import (
    MotorLagThrust,
    TensionEstimate,
    TensionEstimator,
    ThresholdDwell,
    tension_from_forces,
)
from tetherland.estimation.ukf import NavState, Ukf, UkfNoise, initial_covariance

__all__ = [
    "MotorLagThrust",
    "NavState",
    "TensionEstimate",
    "TensionEstimator",
    "ThresholdDwell",
    "Ukf",
    "UkfEstimator",
    "UkfNoise",
    "initial_covariance",
    "tension_from_forces",
]
