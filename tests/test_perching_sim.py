"""Contact-free perching closed loop in the MuJoCo plant (truth estimation), judged by the
one judge of every method."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.analysis import analyze
from tetherland.config import load_scenario
from tetherland.interfaces import ControlMode
from tetherland.methods import Planners
from tetherland.runs import run_mission, truth_estimator, ukf_estimator

LANDING_FIELDS = {
    "position_error_m", "attitude_error_rad", "touchdown_speed_mps",
    "touchdown_angular_rate_rps", "touchdown_accel_mps2", "slip_m", "conditions",
}  # fmt: skip


@pytest.fixture(scope="module")
def planners() -> Planners:
    return Planners()


def perch(sc, planners, estimator=truth_estimator):
    return run_mission(sc, method="free-flight", seed=0, planners=planners, estimator=estimator)


@pytest.fixture(scope="module")
def run20(planners):
    return perch(load_scenario("slope50", ["surface.slope_deg=20"]), planners)


@pytest.fixture(scope="module")
def run50(planners):
    return perch(load_scenario("slope50"), planners)


def test_perch_on_20_degrees_succeeds(run20):
    s = run20.summary
    # the analysis says the contact-free landing is feasible here (tan 20 deg < mu = 0.6)
    assert analyze(run20.plant_scenario).free_flight.feasible
    assert s["success"], s["reason"]
    landing = s["landing"]
    assert landing["position_error_m"] < 0.03
    assert landing["attitude_error_rad"] < math.radians(3.0)
    assert landing["touchdown_speed_mps"] < 0.1
    assert landing["touchdown_angular_rate_rps"] < 0.3
    assert landing["slip_m"] < 0.01
    assert not s["crashed"]
    assert all(landing["conditions"][n] for n in "1235")
    assert not landing["conditions"]["4"]  # a sloped touchdown accelerates (section 6.4.1)
    assert landing["required_conditions"] == ["1", "2", "3", "5"]
    # contact on time, motors off right after touchdown
    times = s["times"]
    assert abs(landing["t_L"] - times["t_L_plan"]) < 0.02
    assert 0.0 <= times["t_motors_off"] - landing["t_L"] <= 0.01 + 1e-9
    log = run20.log
    off = log["mode"] == int(ControlMode.MOTORS_OFF)
    assert np.all(log["cmd_rotor_speeds"][off] == 0.0)
    assert [p["name"] for p in s["phases"]] == ["hover", "maneuver", "motors_off"]


def test_perch_on_slope50_slides_off_after_motors_off(run50):
    s = run50.summary
    a = analyze(run50.plant_scenario).free_flight
    assert not a.condition5_holds_motors_off  # tan 50 deg > mu = 0.6
    landing = s["landing"]
    assert landing["reached"]
    # it reached the landing point with the right attitude ...
    assert landing["conditions"]["1"] and landing["conditions"]["2"]
    # ... and slid down once the motors were off: failure for the chapter's reason (6.7)
    assert landing["slip_m"] > 0.05
    assert not landing["conditions"]["5"] and not s["success"]
    assert "landing condition(s)" in s["reason"] and "(5) slip" in s["reason"]
    # at g (sin 50 - 0.6 cos 50) = 3.7 m/s^2 it leaves the 3 m patch sqrt(2 * 3 / 3.7) =
    # 1.3 s into the 1.5 s rest and falls onto the ground: the frame hits it (a crash)
    a = GRAVITY * (math.sin(math.radians(50)) - 0.6 * math.cos(math.radians(50)))
    t_off = math.sqrt(2 * run50.plant_scenario.surface.extent / a)
    log = run50.log
    crash = log["t"][np.argmax(log["frame_force"] > 0.0)]
    assert s["outcome"] == "crashed"
    assert crash - landing["rest_interval_s"][0] == pytest.approx(t_off, rel=0.2)


def test_both_methods_share_the_summary_layout(run20):
    tethered_keys = {
        "success", "outcome", "reason", "method", "scenario", "seed", "status", "aborted",
        "crashed", "phases", "times", "landing", "takeoff", "return", "switches",
        "tolerances", "sim_time_s", "wall_time_s", "provenance",
    }  # fmt: skip
    s = run20.summary
    assert tethered_keys <= set(s)
    assert LANDING_FIELDS <= set(s["landing"])
    assert set(s["landing"]["conditions"]) == {"1", "2", "3", "4", "5"}
    assert s["takeoff"] == {"required": False} and s["return"] == {"required": False}


def test_no_plan_means_no_run(planners):
    sc = load_scenario("slope50", ["vehicle.f_max=2.6"])
    result = perch(sc, planners)
    assert result.log is None and not result.success
    assert result.summary["outcome"] == "no_run" and "no perching plan" in result.summary["reason"]


def test_estimator_factory_is_used(planners):
    """An estimator is plugged in through the factory (here the UKF, noise-free sensors)."""
    sc = load_scenario("flat", ["sensors.noise_scale=0"])
    calls = []

    def factory(scenario, initial, t0, rotor_speeds0):
        calls.append((scenario.name, initial.p_W.copy(), t0, rotor_speeds0.copy()))
        return ukf_estimator(scenario, initial, t0, rotor_speeds0)

    result = perch(sc, planners, factory)
    log = result.log
    assert len(calls) == 1 and calls[0][0] == "flat" and calls[0][2] == 0.0
    np.testing.assert_allclose(calls[0][1], log["p_W"][0])
    assert log.metadata["estimator"] == "UkfEstimator"
    landing = result.summary["landing"]
    assert landing["reached"] and landing["position_error_m"] < 0.03
