"""State-estimator settings: what the robot's estimator models (issue 23).

The estimator reads its rates and noise from ``[sensors]``; this section holds what its
*models* include beyond the rigid body, cable and motor lag.
"""

from __future__ import annotations

from tetherland.config.base import Section


class EstimatorConfig(Section):
    """The robot's state estimator (UKF): the models of its prediction."""

    ground_effect_belief: bool = True
    """The estimator multiplies the predicted rotor thrusts by the ground-effect factor of
    the believed surface at the estimated pose (the surface-push and tension estimates then
    do not read the ground effect as a push of the surface); false: the estimators and the
    controllers' integrals absorb it."""
