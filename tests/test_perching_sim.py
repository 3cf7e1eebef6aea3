"""Contact-free perching closed loop in the MuJoCo plant (truth estimation) and its verdict."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland.analysis import analyze
from tetherland.config import load_scenario
from tetherland.estimation import UkfEstimator
from tetherland.interfaces import ControlMode
from tetherland.perching import PerchVerdict, run_perching
from tetherland.planning.perching import PerchingPlanner

VERDICT_FIELDS = {
    "position_error_m", "attitude_error_rad", "touchdown_speed_mps",
    "touchdown_angular_rate_rps", "touchdown_accel_mps2", "slip_m", "conditions", "success",
}  # fmt: skip


@pytest.fixture(scope="module")
def planner() -> PerchingPlanner:
    return PerchingPlanner()


@pytest.fixture(scope="module")
def run20(planner):
    sc = load_scenario("slope50", ["surface.slope_deg=20"])
    return sc, *run_perching(sc, sc, seed=0, planner=planner)


@pytest.fixture(scope="module")
def run50(planner):
    sc = load_scenario("slope50")
    return sc, *run_perching(sc, sc, seed=0, planner=planner)


def test_perch_on_20_degrees_succeeds(run20):
    sc, log, v = run20
    # the analysis says the contact-free landing is feasible here (tan 20 deg < mu = 0.6)
    assert analyze(sc).free_flight.feasible
    assert v.success, v.reason
    assert v.position_error_m < 0.03
    assert v.attitude_error_rad < math.radians(3.0)
    assert v.touchdown_speed_mps < 0.1
    assert v.touchdown_angular_rate_rps < 0.3
    assert v.slip_m < 0.01
    assert not v.crashed
    assert all(v.conditions[n] for n in (1, 2, 3, 5))
    assert not v.conditions[4]  # a sloped touchdown accelerates (section 6.4.1)
    # contact on time, motors off right after touchdown
    planned = log.metadata["perching"]["planned_touchdown_s"]
    assert abs(v.touchdown_time_s - planned) < 0.02
    assert 0.0 <= v.motors_off_time_s - v.touchdown_time_s <= 0.01 + 1e-9
    off = log["mode"] == int(ControlMode.MOTORS_OFF)
    assert np.all(log["cmd_rotor_speeds"][off] == 0.0)
    assert log.metadata["perching"]["verdict"]["success"] is True


def test_perch_on_slope50_slides_off_after_motors_off(run50):
    sc, log, v = run50
    a = analyze(sc).free_flight
    assert not a.condition5_holds_motors_off  # tan 50 deg > mu = 0.6
    assert log is not None and v.touchdown_time_s is not None
    # it reached the landing point with the right attitude ...
    assert v.conditions[1] and v.conditions[2]
    # ... and slid down once the motors were off: failure for the chapter's reason (6.7)
    assert v.slip_m > 0.05
    assert not v.conditions[5] and not v.success
    assert "5" in v.reason


def test_verdict_has_the_mission_field_names(run20):
    d = run20[2].to_dict()
    assert VERDICT_FIELDS <= set(d)
    assert set(d["conditions"]) == {"1", "2", "3", "4", "5"}
    failed = PerchVerdict.failed("why").to_dict()
    assert VERDICT_FIELDS <= set(failed) and failed["success"] is False
    assert failed["position_error_m"] is None  # NaN becomes null in JSON


def test_no_plan_means_no_run(planner):
    sc = load_scenario("slope50", ["vehicle.f_max=2.6"])
    log, v = run_perching(sc, sc, seed=0, planner=planner)
    assert log is None and not v.success and "no perching plan" in v.reason


def test_estimator_factory_is_used(planner):
    """The lead plugs the UKF in through the factory (here with noise-free sensors)."""
    sc = load_scenario("flat", ["sensors.noise_scale=0"])
    calls = []

    def factory(scenario, initial, t0, rotor_speeds0):
        calls.append((scenario.name, initial.p_W.copy(), t0, rotor_speeds0.copy()))
        return UkfEstimator(scenario, initial, t0, rotor_speeds0=rotor_speeds0)

    log, v = run_perching(sc, sc, seed=0, estimator_factory=factory, planner=planner)
    assert len(calls) == 1 and calls[0][0] == "flat" and calls[0][2] == 0.0
    np.testing.assert_allclose(calls[0][1], log["p_W"][0])
    assert log.metadata["estimator"] == "UkfEstimator"
    assert v.touchdown_time_s is not None and v.position_error_m < 0.03
