"""The judge on the plant's truth alone (issue 22, item 3).

Touchdowns are contacts of the landers with the landing surface over the whole run (not
the start pad, not the phases the robot declares), the rest is the interval in which the
true rotor thrust is below the motors-off level, the slide is measured from the first
touchdown until spin-up and a bounce is judged at the contact that starts the rest. The
logs here are built tick by tick from a known motion, so every expected value follows
from that motion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.cli import main
from tetherland.config import Scenario, load_scenario, with_overrides
from tetherland.config.verdict import motors_off_thrust, spin_down_time
from tetherland.geometry import LandingGeometry, landed_rotation
from tetherland.interfaces import ControlMode
from tetherland.rotations import rotmat_to_quat
from tetherland.sim.log import BASE_COLUMNS, SimLog, row_width
from tetherland.verdict import Expectations, Outcome, RunRecord, judge
from tetherland.verdict.touchdown import LogTooOldError, onsets, rest_after

DT = 0.002
"""Control period of the built logs [s] (500 Hz, as the missions)."""


@pytest.fixture(scope="module")
def truth() -> Scenario:
    return load_scenario("slope50")


@dataclass
class Motion:
    """A landing told as what happens when (every time in s, every offset in m).

    The landers' centre p_RL comes down along -z_S onto the desired landing point at
    ``descent`` m/s and touches at ``t_touch``; it slides along x_S at ``slide_speed``
    from ``t_touch`` to ``t_off`` (the hold with the thrust on); the thrust is off from
    ``t_off`` to ``t_on``; the log ends at ``t_end``. ``bounce`` = (t_lift, t_back,
    speed, shift): contact lost at t_lift and regained at t_back, arriving at ``speed``
    along -z_S, ``shift`` along x_S from the first touchdown.
    """

    t_touch: float = 1.0
    descent: float = 0.05
    slide_speed: float = 0.0
    t_off: float = 1.5
    t_on: float = 3.0
    t_end: float = 3.5
    bounce: tuple[float, float, float, float] | None = None
    mode_off: tuple[float, float] | None = None  # the robot's declared MOTORS_OFF interval
    thrust_off: bool = True  # False: the thrust stays at hover (a robot whose mode lies)
    pad: bool = True  # on the start pad (the ground) for the first 0.2 s


def build_log(truth: Scenario, m: Motion) -> SimLog:
    """The plant's truth of ``m``, every control tick (the columns the judge reads)."""
    geo = LandingGeometry.from_scenario(truth)
    R = landed_rotation(geo.surface.R_WS, math.radians(truth.planner.heading_deg))
    x_S, z_S = geo.surface.x_S, geo.surface.z_S
    t = np.round(np.arange(0.0, m.t_end + DT / 2, DT), 9)
    n = len(t)
    log = SimLog(BASE_COLUMNS, np.full((n, row_width(BASE_COLUMNS)), np.nan),
                 {"status": "terminated"})  # fmt: skip
    height = np.maximum(m.descent * (m.t_touch - t), 0.0)  # above the surface, along z_S
    slide = m.slide_speed * (np.clip(t, m.t_touch, m.t_off) - m.t_touch)  # along x_S
    v = np.outer(np.where(t < m.t_touch, -m.descent, 0.0), z_S)
    v += np.outer(np.where((t >= m.t_touch) & (t < m.t_off), m.slide_speed, 0.0), x_S)
    touching = t >= m.t_touch
    if m.bounce is not None:
        t_lift, t_back, speed, shift = m.bounce
        up = (t >= t_lift) & (t < t_back)
        height[up] = speed * (t_back - t[up])
        v[up] = -speed * z_S
        slide[t >= t_back] += shift
        touching &= ~up
    log["t"][:] = t
    log["p_W"][:] = geo.p_L + np.outer(slide, x_S) + np.outer(height, z_S) + geo.h_R * R[:, 2]
    log["q_WB"][:] = rotmat_to_quat(R)
    log["v_W"][:] = v
    log["omega_B"][:] = 0.0
    log["specific_force_B"][:] = R.T @ np.array([0.0, 0.0, GRAVITY])  # unaccelerated
    off = (t >= m.t_off) & (t < m.t_on) if m.thrust_off else np.zeros(n, bool)
    hover = truth.vehicle.mass * GRAVITY / 4
    log["rotor_thrusts"][:] = np.where(off, 0.0, hover)[:, None]
    log["rotor_speeds"][:] = 0.0
    log["lander_surface_forces"][:] = np.where(touching, 2.0, 0.0)[:, None]
    on_pad = t < 0.2 if m.pad else np.zeros(n, bool)
    log["lander_ground_forces"][:] = np.where(on_pad, hover, 0.0)[:, None]
    log["rotor_thrusts"][on_pad] = 0.0  # motors off on the start pad
    log["lander_forces"][:] = log["lander_surface_forces"] + log["lander_ground_forces"]
    log["frame_force"][:] = 0.0
    log["tension"][:] = 0.0
    log["phase"][:] = 0.0
    mode = np.full(n, float(ControlMode.TETHERED))
    if m.mode_off is not None:
        mode[(t >= m.mode_off[0]) & (t < m.mode_off[1])] = float(ControlMode.MOTORS_OFF)
    log["mode"][:] = mode
    return log


def record_of(truth: Scenario, belief: Scenario | None = None) -> RunRecord:
    return RunRecord(
        method="tethered", seed=0, truth=truth.model_dump(mode="json"),
        belief=(belief or truth).model_dump(mode="json"), expects=Expectations(), finished=True,
    )  # fmt: skip


def landing_of(truth: Scenario, m: Motion) -> tuple[dict, object]:
    verdict = judge(build_log(truth, m), record_of(truth))
    return verdict.summary["landing"], verdict


def test_a_clean_landing_and_rest_succeed_with_the_rest_from_the_true_thrust(truth):
    landing, verdict = landing_of(truth, Motion())
    assert verdict.success, verdict.reason
    # the touchdown is the first tick on the surface, not the start pad at t = 0
    assert landing["t_L"] == pytest.approx(1.0)
    assert landing["touchdown_speed_mps"] == pytest.approx(0.05)  # the descent, at t_L-
    assert landing["position_error_m"] == pytest.approx(0.0, abs=1e-12)
    assert landing["rest_interval_s"] == pytest.approx([1.5, 3.0])
    assert landing["slip_m"] == pytest.approx(0.0, abs=1e-12) and landing["bounces"] == []


def test_a_slide_between_touchdown_and_motors_off_fails_condition_5(truth):
    """2 cm of sliding during the hold (thrust on), then a still rest: the old judge saw
    only the motors-off interval (slip 0); the slide counts from the first touchdown."""
    speed, hold = 0.04, 0.5
    landing, verdict = landing_of(truth, Motion(slide_speed=speed))
    assert landing["slip_m"] == pytest.approx(speed * hold)  # 2 cm > verdict.rest_slip = 1 cm
    assert speed * hold > truth.verdict.rest_slip
    assert landing["conditions"] == {"1": True, "2": True, "3": True, "4": True, "5": False}
    assert verdict.outcome is Outcome.LANDING_CONDITIONS
    assert "(5) slip 0.02 m > 0.01" in verdict.reason
    # over the rest alone nothing moved: the rest speed is zero
    assert landing["rest_speed_mps"] == pytest.approx(0.0, abs=1e-12)


def test_a_bounce_is_judged_at_the_contact_that_starts_the_rest(truth):
    """Contact lost at 1.1 s and regained at 1.3 s, arriving at 0.3 m/s 4 cm down the
    slope: (1) and (3) fail there, although the first touchdown met them."""
    landing, verdict = landing_of(truth, Motion(bounce=(1.1, 1.3, 0.3, 0.04)))
    assert landing["t_L"] == pytest.approx(1.0)
    assert landing["touchdown_speed_mps"] == pytest.approx(0.05)  # the first touchdown
    assert landing["rest_contact_t"] == pytest.approx(1.3)
    (bounce,) = landing["bounces"]
    assert bounce["t"] == pytest.approx(1.3)
    assert bounce["touchdown_speed_mps"] == pytest.approx(0.3)
    assert bounce["position_error_m"] == pytest.approx(0.04)
    assert bounce["conditions"] == {"1": False, "2": True, "3": False, "4": True}
    assert landing["conditions"] == {"1": False, "2": True, "3": False, "4": True, "5": False}
    assert "(1) missed at the bounce at t = 1.300 s" in verdict.reason
    # the slide from the first touchdown includes the 4 cm the bounce moved
    assert landing["slip_m"] == pytest.approx(0.04)


def test_motors_off_above_the_surface_is_judged_at_the_fall(truth):
    """Contact lost at 1.1 s, the motors go off at 1.5 s with the vehicle in the air and
    it falls back at 1.6 s at 0.2 m/s: the contact that starts the rest is that fall."""
    landing, verdict = landing_of(truth, Motion(bounce=(1.1, 1.6, 0.2, 0.0)))
    assert landing["rest_interval_s"] == pytest.approx([1.5, 3.0])
    assert landing["rest_contact_t"] == pytest.approx(1.6)
    assert [b["t"] for b in landing["bounces"]] == pytest.approx([1.6])
    assert landing["bounces"][0]["touchdown_speed_mps"] == pytest.approx(0.2)
    assert not landing["conditions"]["3"] and not verdict.success


def test_a_gentle_bounce_in_place_passes(truth):
    """The same bounce arriving at 1 cm/s where it left: every touchdown meets (1)-(4)."""
    landing, verdict = landing_of(truth, Motion(bounce=(1.1, 1.3, 0.01, 0.0)))
    assert verdict.success, verdict.reason
    assert [b["t"] for b in landing["bounces"]] == pytest.approx([1.3])


@pytest.mark.parametrize(("lost_ticks", "bounce"), [(2, False), (3, True)])
def test_contact_lost_for_less_than_the_contact_time_constant_is_no_bounce(truth, lost_ticks,
                                                                          bounce):  # fmt: skip
    """sim.contact_time_constant = 5 ms: 2 ticks without contact (4 ms) are the soft contact's
    own transient, 3 ticks (6 ms) a bounce, judged (here at 0.3 m/s: (3) fails)."""
    assert truth.sim.contact_time_constant == 0.005
    t_back = 1.1 + lost_ticks * DT
    landing, verdict = landing_of(truth, Motion(bounce=(1.1, t_back, 0.3, 0.0)))
    assert [b["t"] for b in landing["bounces"]] == pytest.approx([t_back] if bounce else [])
    assert verdict.success is not bounce
    assert landing["conditions"]["3"] is not bounce


@pytest.mark.parametrize("lie", ["motors_off_with_thrust_on", "flying_with_motors_off"])
def test_the_robots_mode_does_not_decide_the_rest(truth, lie):
    """The robot's declared mode lies: the judge follows the true thrust."""
    if lie == "motors_off_with_thrust_on":
        m = Motion(mode_off=(1.5, 3.0), thrust_off=False)
        landing, verdict = landing_of(truth, m)
        assert landing["rest_interval_s"] is None and landing["conditions"]["5"] is False
        assert "(5) no rest: the true rotor thrust never went below" in verdict.reason
    else:
        landing, verdict = landing_of(truth, Motion(mode_off=None))
        assert verdict.success, verdict.reason
        assert landing["rest_interval_s"] == pytest.approx([1.5, 3.0])


def test_a_rest_shorter_than_min_rest_time_fails_condition_5(truth):
    landing, verdict = landing_of(truth, Motion(t_off=1.5, t_on=2.1))
    assert landing["rest_interval_s"] == pytest.approx([1.5, 2.1])
    assert landing["conditions"]["5"] is False
    assert "the rest lasted 0.6 s < verdict.min_rest_time = 1 s" in verdict.reason
    # a shorter min_rest_time in the truth accepts it
    strict = with_overrides(truth, ["verdict.min_rest_time=0.5", "mission.deploy_time=1"])
    ok = judge(build_log(truth, Motion(t_off=1.5, t_on=2.1)), record_of(strict))
    assert ok.success, ok.reason


def test_only_the_landing_surface_makes_a_touchdown(truth):
    """Touching the ground (the start pad) is not a touchdown, wherever the robot was."""
    log = build_log(truth, Motion())
    log["lander_surface_forces"][:] = 0.0
    log["lander_ground_forces"][log["t"] > 3.2] = 2.0  # landed back on the pad
    verdict = judge(log, record_of(truth))
    assert verdict.outcome is Outcome.NO_TOUCHDOWN
    assert verdict.reason == "no touchdown on the landing surface"


def test_the_rest_and_the_onsets_of_an_array():
    t = np.arange(10) * 0.1
    thrust = np.array([0, 0, 5, 5, 0, 0, 0, 5, 0, 0], float)
    assert onsets(thrust < 1) == (0, 4, 8)
    rest = rest_after(thrust, t, 1.0, 2)
    assert (rest.start, rest.end) == (4, 7) and rest.duration == pytest.approx(0.3)
    last = rest_after(thrust, t, 1.0, 7)  # resting to the end of the log
    assert (last.start, last.end, last.t_end) == (8, 10, pytest.approx(0.9))
    assert rest_after(thrust, t, 1.0, 10) is None


def test_a_log_without_the_contact_columns_is_refused_in_one_line(truth):
    log = build_log(truth, Motion())
    cols = tuple(c for c in log.columns if c.name != "lander_surface_forces")
    keep = np.concatenate([log[c.name].reshape(len(log), -1) for c in cols], axis=1)
    with pytest.raises(LogTooOldError, match="no lander_surface_forces column"):
        judge(SimLog(cols, keep, log.metadata), record_of(truth))


def test_the_motors_off_level_and_the_spin_down(truth):
    v = truth.vehicle
    level = motors_off_thrust(v)
    assert level == pytest.approx(0.02 * v.mass * GRAVITY)
    assert level < 4 * v.f_min  # no flying controller goes this low
    # from 4 f_max the thrust 4 f_max exp(-2 t / tau) reaches the level at spin_down_time
    t = spin_down_time(v)
    assert 4 * v.f_max * math.exp(-2 * t / v.motor_time_constant) == pytest.approx(level)


def test_a_deploy_time_shorter_than_the_rest_is_rejected_before_flying(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(["mission", "slope50", "--set", "mission.deploy_time=0.1", "--out", str(out)])
    assert code == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0
    assert err.startswith("error: mission.deploy_time = 0.1 s must be >= ")
    assert "verdict.min_rest_time" in err
    assert not out.exists()  # nothing flown, nothing written
    with pytest.raises(ValueError, match=r"verdict\.rest_settle"):
        load_scenario("slope50", ["verdict.min_rest_time=0.2"])


@pytest.mark.slow
def test_a_short_deployment_flown_through_the_api_fails_condition_5(truth):
    """The robot believes a 0.1 s deployment is fine (its belief's own verdict section
    allows it); the judge reads the truth's min_rest_time (1 s) and fails (5), giving why."""
    from tetherland.runs import run_mission

    belief = with_overrides(truth, [
        "mission.deploy_time=0.1", "verdict.min_rest_time=0.02", "verdict.rest_settle_time=0.01",
    ])  # fmt: skip
    result = run_mission(truth, belief, seed=0)
    landing = result.summary["landing"]
    start, end = landing["rest_interval_s"]
    # the motors are off for 0.1 s from t_G; the true thrust is below the level for that
    # less the motors' spin-down (about 2 tau from the landed hover's thrust), plus the end
    # of the supervisor's thrust ramp before t_G: the true thrust, lagging the command,
    # goes below the level no earlier than the commanded thrust does
    t_G, t_T = result.record.times["t_G"], result.record.times["t_T"]
    assert t_T - t_G == pytest.approx(0.1, abs=DT)
    log = result.log
    level = motors_off_thrust(truth.vehicle)
    commanded_low = log["t"][(log["t"] > result.record.times["t_L"]) & (log["cmd_thrust"] < level)]
    assert commanded_low[0] <= t_G
    assert commanded_low[0] - DT <= start < t_G + spin_down_time(truth.vehicle) + DT
    # spin-up: the thrust T_c (1 - exp(-t/tau))^2 passes the level within tau for any
    # command above 2.5 times it (the landed hover's is about 30 times)
    assert t_T < end <= t_T + truth.vehicle.motor_time_constant
    assert end - start < truth.verdict.min_rest_time
    assert landing["conditions"]["5"] is False
    assert "(5) the rest lasted" in result.summary["reason"]
    assert "< verdict.min_rest_time = 1 s" in result.summary["reason"]
