"""State and cable-tension estimation (docs/theory.md section 8)."""

from tetherland.estimation.estimator import UkfEstimator
from tetherland.estimation.tension import (
    CableEstimate,
    MotorLagThrust,
    TensionEstimate,
    TensionEstimator,
    TensionTare,
    ThresholdDwell,
    elastic_tension,
    tension_from_forces,
)
from tetherland.estimation.ukf import NavState, Ukf, UkfNoise, initial_covariance

__all__ = [
    "CableEstimate",
    "MotorLagThrust",
    "NavState",
    "TensionEstimate",
    "TensionEstimator",
    "TensionTare",
    "ThresholdDwell",
    "Ukf",
    "UkfEstimator",
    "UkfNoise",
    "elastic_tension",
    "initial_covariance",
    "tension_from_forces",
]
