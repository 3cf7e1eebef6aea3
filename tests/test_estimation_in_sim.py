"""The UKF estimator in the MuJoCo loop with the plant's sensor models (truth from the plant)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland.estimation import UkfEstimator
from tetherland.interfaces import Estimator
from tetherland.rotations import quat_conjugate, quat_multiply, quat_to_rotvec
from tetherland.sim import Plant, Runner
from tetherland.sim.baselines import ConstantSpeedController
from tetherland.state import RigidBodyState


@pytest.fixture(scope="module")
def hover_log(slope50):
    plant = Plant(slope50)
    x0 = RigidBodyState.at_rest(plant.start_state().p_W + np.array([0.0, 0.0, 1.0]))
    ctrl = ConstantSpeedController.hover(slope50.vehicle)
    speeds = ctrl.update(0.0, None, None).rotor_speeds  # type: ignore[arg-type]
    est = UkfEstimator(slope50, x0, 0.0, rotor_speeds0=speeds)
    assert isinstance(est, Estimator)
    log = Runner(slope50, ctrl, estimator=est, seed=3, plant=plant).run(
        3.0, initial_state=x0, rotor_speeds=speeds
    )
    return log, est


def test_pose_and_velocity_track_the_truth(hover_log):
    log, _ = hover_log
    settled = log["t"] > 0.3
    pos = np.linalg.norm(log["est_p_W"] - log["p_W"], axis=1)[settled]
    vel = np.linalg.norm(log["est_v_W"] - log["v_W"], axis=1)[settled]
    att = [
        np.linalg.norm(quat_to_rotvec(quat_multiply(quat_conjugate(a), b)))
        for a, b in zip(log["est_q_WB"][settled], log["q_WB"][settled], strict=True)
    ]
    assert pos.max() < 3e-3  # mocap 1 mm noise
    assert vel.max() < 0.02
    assert math.degrees(max(att)) < 0.5  # mocap 0.3 deg noise


def test_innovations_are_consistent(hover_log):
    _, est = hover_log
    assert 0.5 < est.last_nis < 30.0  # one chi-square(6) draw, far from divergence
    assert est.ukf.rejected_late == 0


def test_no_tension_is_estimated_in_free_flight(hover_log):
    log, _ = hover_log
    assert np.abs(log["est_tension"][log["t"] > 0.3]).max() < 0.1
