"""The guarded touchdown's multi-signal contact rule (issue 15) and its campaign regressions."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from legacy_random import LegacySource
from tetherland.campaign.jobs import Job, run_job
from tetherland.campaign.spec import CampaignSpec, Sweep
from tetherland.config import load_scenario, with_overrides
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import ControlMode, Feedforward, Reference, StateEstimate
from tetherland.mission import Phase
from tetherland.mission.contact import (
    LATERAL_CLEARANCE,
    ContactGeometry,
    ContactRule,
    SlowApproach,
    contact_hold,
    guarded_descent,
)
from tetherland.rotations import quat_to_rotmat, rotmat_to_quat
from tetherland.state import LinkState, RigidBodyState

RATE = 500.0  # control rate of the synthetic ticks [Hz]


@pytest.fixture(scope="module")
def scenario():
    return load_scenario("slope50", ["tether.length=1.2", "tether.hook_drop=1.0"])


@pytest.fixture(scope="module")
def geo(scenario):
    return LandingGeometry.from_scenario(scenario)


def rot_x(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def landed_pose(geo, height: float = 0.0, tilt: float = 0.0):
    """Centre of mass ``height`` above the landed one, z_B tilted by ``tilt`` about x_S."""
    R_WS = np.column_stack((geo.surface.x_S, geo.surface.y_S, geo.surface.z_S))
    R_WB = R_WS @ rot_x(tilt)
    return geo.p_R_landed + height * geo.surface.z_S, R_WB


def estimate(geo, scenario, t, *, phi, phi_dot, height=0.0, normal=0.0, tension=3.0):
    """An estimate at the landed pose with the given link and an external force made of
    the cable pull along -d and a surface push ``normal`` along z_S."""
    p_W, R_WB = landed_pose(geo, height)
    r_att = np.asarray(scenario.vehicle.cable_attachment, dtype=float)
    d = p_W + R_WB @ r_att - geo.p_A
    d /= np.linalg.norm(d)
    f_W = -tension * d + normal * geo.surface.z_S
    body = RigidBodyState(p_W, np.zeros(3), rotmat_to_quat(R_WB), np.zeros(3))
    return StateEstimate(
        t=t, body=body, link=LinkState(phi, 0.0, phi_dot, 0.0), tension=tension,
        external_force_B=R_WB.T @ f_W,
    )  # fmt: skip


def test_clearance_of_the_lowest_lander_tip(scenario, geo):
    """Landed flat: 0; raised by h: h; tilted by a about x_S: h_R (1 - cos a) - w sin a
    (the tip at -w drops by w sin a, the landers plane rises by h_R (1 - cos a))."""
    cg = ContactGeometry.from_scenario(scenario)
    v = scenario.vehicle
    assert cg.clearance(*landed_pose(geo)) == pytest.approx(0.0, abs=1e-12)
    assert cg.clearance(*landed_pose(geo, 0.02)) == pytest.approx(0.02, abs=1e-12)
    a = math.radians(4.0)
    expected = v.h_R * (1.0 - math.cos(a)) - v.lander_half_width * math.sin(a)
    assert cg.clearance(*landed_pose(geo, 0.0, a)) == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize("tension", [0.0, 2.0, 9.0])
def test_the_surface_push_is_separated_from_the_cable_pull(scenario, geo, tension):
    """f = -f_L d + N z_S: the estimate is N whatever the tension."""
    cg = ContactGeometry.from_scenario(scenario)
    est = estimate(geo, scenario, 0.0, phi=geo.phi_star, phi_dot=0.0, normal=0.7, tension=tension)
    R_WB = quat_to_rotmat(est.body.q_WB)
    assert cg.normal_force(est.body.p_W, R_WB, est.external_force_B) == pytest.approx(0.7)


def feed(rule, geo, scenario, duration, *, lag_deg, rate_deg, normal, height=0.0, t0=0.0,
         spike_at=None):  # fmt: skip
    """Feed ``duration`` seconds of ticks with a constant lag above phi_d; return the
    first time the rule confirms contact (None if never)."""
    phi = geo.phi_star
    phi_d = phi - math.radians(lag_deg)
    n = round(duration * RATE)
    for k in range(n + 1):
        t = t0 + k / RATE
        f = normal if spike_at is None or abs(t - spike_at) > 0.5 / RATE else 5.0
        est = estimate(geo, scenario, t, phi=phi, phi_dot=math.radians(rate_deg),
                       height=height, normal=f)  # fmt: skip
        if rule.update(t, est, phi_d).confirmed:
            return t - t0
    return None


def test_contact_needs_the_stall_the_clearance_and_the_surface_force(scenario, geo):
    """Every signal alone or in pairs is not contact; all three for the dwell are."""
    cfg = scenario.mission
    rule = ContactRule(scenario)
    # the anchor-belief case: the link held 1 deg above its reference near the surface,
    # but nothing pushes back (a gust or a belief error, not the surface)
    assert feed(rule, geo, scenario, 2.0, lag_deg=1.0, rate_deg=0.0, normal=0.0) is None
    # the surface pushes, but the link still moves: not stopped yet
    rule.reset()
    assert feed(rule, geo, scenario, 2.0, lag_deg=1.0, rate_deg=2.0, normal=0.5) is None
    # stalled and pushed, but 3 cm above the believed surface: not the surface
    rule.reset()
    high = feed(rule, geo, scenario, 2.0, lag_deg=1.0, rate_deg=0.0, normal=0.5, height=0.03)
    assert high is None
    # every signal: confirmed after the dwell (the force filter needs a few time constants)
    rule.reset()
    t = feed(rule, geo, scenario, 2.0, lag_deg=1.0, rate_deg=0.0, normal=0.5)
    assert t is not None
    tau = cfg.contact.surface_force_time_constant
    t_force = tau * math.log(0.5 / (0.5 - cfg.contact.surface_force))  # filter at the threshold
    assert cfg.contact.dwell <= t <= t_force + cfg.contact.dwell + 2.0 / RATE


def test_a_link_creeping_up_is_held_but_a_descending_one_lags(scenario, geo):
    """Pressed landers on a wall let the vehicle creep up (the link rises slowly against
    the descending reference): stalled while it rises slower than contact.creep_rate_deg_s
    (contact after the dwell); rising faster (a bounce, a gust) or descending faster than
    contact.stall_rate_deg_s (still moving toward the reference) is not contact."""
    cfg = scenario.mission
    assert cfg.contact.stall_rate_deg_s < cfg.contact.creep_rate_deg_s  # the premise
    rule = ContactRule(scenario)
    creep = 0.7 * cfg.contact.creep_rate_deg_s
    t = feed(rule, geo, scenario, 2.0, lag_deg=1.0, rate_deg=creep, normal=0.5)
    assert t is not None and t >= cfg.contact.dwell
    for rate in (1.2 * cfg.contact.creep_rate_deg_s, -1.2 * cfg.contact.stall_rate_deg_s):
        rule.reset()
        assert feed(rule, geo, scenario, 2.0, lag_deg=1.0, rate_deg=rate, normal=0.5) is None


def test_an_impact_counts_as_the_force_signal_for_the_dwell(scenario, geo):
    """A single 5 N sample (touchdown impact) with no lasting push: contact when the stall
    lasts the dwell after it (the impact is remembered for twice the dwell)."""
    cfg = scenario.mission
    rule = ContactRule(scenario)
    t = feed(rule, geo, scenario, 1.0, lag_deg=1.0, rate_deg=0.0, normal=0.0, spike_at=0.1)
    assert t is not None and t == pytest.approx(0.1 + cfg.contact.dwell, abs=1.5 / RATE)
    rule.reset()  # no impact, no push: never
    assert feed(rule, geo, scenario, 1.0, lag_deg=1.0, rate_deg=0.0, normal=0.0) is None


def test_a_gust_cannot_fake_contact_for_the_dwell(scenario, geo):
    """A push shorter than the dwell (and no impact) is not contact; the dwell restarts."""
    cfg = scenario.mission
    rule = ContactRule(scenario)
    short = 0.5 * cfg.contact.dwell
    assert feed(rule, geo, scenario, short, lag_deg=1.0, rate_deg=0.0, normal=0.5) is None
    assert feed(rule, geo, scenario, 1.0, lag_deg=1.0, rate_deg=3.0, normal=0.5, t0=short) is None


def test_guarded_descent_and_hold(scenario):
    """phi_d falls at touchdown.descent_rate_deg_s down to touchdown.search_depth_deg; the
    hold presses contact.press_deg below the contact elevation, at rest."""
    cfg = scenario.mission
    out = np.zeros((5, 4))
    out[0] = [-1.0, 0.01, 0.8, 0.2]
    ref = Reference(t=0.0, mode=ControlMode.TETHERED, output=out, thrust_ff=9.0)
    rate = math.radians(cfg.touchdown.descent_rate_deg_s)
    g = guarded_descent(cfg.touchdown, ref, 1.0, 7)
    assert g.output[0, 0] == pytest.approx(-1.0 - rate)
    assert g.output[1, 0] == pytest.approx(-rate) and g.phase == 7
    deep = guarded_descent(cfg.touchdown, ref, 100.0, 7)
    assert deep.output[0, 0] == pytest.approx(-1.0 - math.radians(cfg.touchdown.search_depth_deg))
    assert deep.output[1, 0] == 0.0
    body = RigidBodyState(np.zeros(3), np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(3))
    est = StateEstimate(t=2.0, body=body, link=LinkState(-1.02, 0.0, 0.0, 0.0))
    hold = contact_hold(cfg.contact, 2.0, est, g, 7)
    assert hold.output[0, 0] == pytest.approx(-1.02 - math.radians(cfg.contact.press_deg))
    assert np.all(hold.output[1:] == 0.0) and hold.output[0, 1:].tolist() == out[0, 1:].tolist()


def test_the_slow_approach_caps_the_reference_speed_near_the_surface(scenario, geo):
    """alpha = (v0 + k c) / (l |phi_d'|) within reach, 1 far away; the clock advances by
    alpha dt and the k-th derivative rows (and the feed-forward rates) scale by alpha^k."""
    cfg = scenario.mission
    rule = ContactRule(scenario)
    slow = SlowApproach(cfg.touchdown, rule.geometry, scenario.tether.length, LATERAL_CLEARANCE)
    l, v0, gain = scenario.tether.length, cfg.touchdown.approach_speed, cfg.touchdown.approach_gain
    rate = math.radians(5.0)  # 0.1 m/s of reference speed at l = 1.2 m
    c = 0.01
    slow.start(10.0)
    est = estimate(geo, scenario, 10.0, phi=geo.phi_star, phi_dot=0.0, height=c)
    tau = slow.advance(10.1, est, rate)
    alpha = (v0 + gain * c) / (l * rate)
    assert 0.0 < alpha < 1.0
    assert slow.alpha == pytest.approx(alpha) and tau == pytest.approx(10.0 + 0.1 * alpha)
    far = estimate(geo, scenario, 10.1, phi=geo.phi_star, phi_dot=0.0, height=0.5)
    assert slow.advance(10.2, far, rate) == pytest.approx(tau + 0.1) and slow.alpha == 1.0
    slow.advance(10.3, est, rate)
    out = np.arange(20.0).reshape(5, 4)
    ff = Feedforward(omega_B=np.ones(3), omega_dot_B=np.ones(3), f_R=9.0, f_R_dot=1.0,
                     f_R_ddot=1.0, tension=2.0)  # fmt: skip
    ref = Reference(t=1.0, mode=ControlMode.TETHERED, output=out, thrust_ff=9.0, feedforward=ff)
    scaled = slow.scale(ref, 10.3)
    assert scaled.t == 10.3
    for k in range(5):
        assert scaled.output[k] == pytest.approx(alpha**k * out[k])
    f = scaled.feedforward
    assert f.omega_B == pytest.approx(alpha * ff.omega_B)
    assert f.omega_dot_B == pytest.approx(alpha**2 * ff.omega_dot_B)
    assert (f.f_R, f.tension) == (9.0, 2.0) and f.f_R_ddot == pytest.approx(alpha**2)


def test_the_rate_hold_backs_the_clock_while_the_frame_rotates_near_the_surface(scenario, geo):
    """Within touchdown.hold_clearance and above touchdown.hold_rate (roll-pitch only) the
    clock runs backwards at touchdown.hold_retreat, never before the plan's start, for at
    most touchdown.hold_max_time in total; a yaw rate, a rotation far from the surface, or a
    slow one leave the slowed clock of the previous test."""
    from dataclasses import replace

    cfg = scenario.mission
    slow = SlowApproach(
        cfg.touchdown, ContactRule(scenario).geometry, scenario.tether.length, LATERAL_CLEARANCE
    )
    l, v0, gain = scenario.tether.length, cfg.touchdown.approach_speed, cfg.touchdown.approach_gain
    rate = math.radians(5.0)
    c = 0.5 * cfg.touchdown.hold_clearance
    alpha = min(1.0, (v0 + gain * c) / (l * rate))

    def spinning(height, omega_B, t):
        est = estimate(geo, scenario, t, phi=geo.phi_star, phi_dot=0.0, height=height)
        return replace(est, body=replace(est.body, omega_B=np.asarray(omega_B, dtype=float)))

    w = 1.5 * cfg.touchdown.hold_rate
    back = cfg.touchdown.hold_retreat
    assert back > 0.0
    slow.start(9.0)
    dt = 0.01
    slow.advance(10.0, spinning(1.0, [0.0, 0.0, 0.0], 10.0), rate)  # far: tau = t = 10
    tau = slow.advance(10.0 + dt, spinning(c, [0.6 * w, 0.8 * w, 0.0], 10.0), rate)
    assert slow.alpha == -back and tau == pytest.approx(10.0 - back * dt)
    assert slow.held == pytest.approx(dt)
    tau = slow.advance(10.0 + 2 * dt, spinning(c, [0.6 * w, 0.8 * w, 0.0], 10.0), rate)
    assert tau == pytest.approx(10.0 - 2 * back * dt)
    tau = 10.0 - 2 * back * dt
    # a yaw rate does not hold, nor a roll rate below the threshold
    tau2 = slow.advance(10.0 + 3 * dt, spinning(c, [0.0, 0.0, 10.0 * w], 10.0), rate)
    assert slow.alpha == pytest.approx(alpha) and tau2 == pytest.approx(tau + dt * alpha)
    tau3 = slow.advance(10.0 + 4 * dt, spinning(c, [0.9 * cfg.touchdown.hold_rate, 0, 0], 10), rate)
    assert tau3 == pytest.approx(tau2 + dt * alpha)
    # far from the surface: the plan's own clock
    far = 2.0 * cfg.touchdown.hold_clearance + 0.5
    tau4 = slow.advance(10.0 + 5 * dt, spinning(far, [w, 0.0, 0.0], 10.0), rate)
    assert slow.alpha == 1.0 and tau4 == pytest.approx(tau3 + dt)
    # never before the plan's start
    early = SlowApproach(
        cfg.touchdown, ContactRule(scenario).geometry, scenario.tether.length, LATERAL_CLEARANCE
    )
    early.start(10.0)
    assert early.advance(10.0 + dt, spinning(c, [w, 0.0, 0.0], 10.0), rate) == 10.0
    # the hold ends after touchdown.hold_max_time in total
    t = 10.0 + 5 * dt
    steps = math.ceil(cfg.touchdown.hold_max_time / dt) + 2
    for _ in range(steps):
        t += dt
        slow.advance(t, spinning(c, [w, 0.0, 0.0], t), rate)
    assert slow.held == pytest.approx(cfg.touchdown.hold_max_time, abs=1.01 * dt)
    assert slow.alpha == pytest.approx(alpha)


def test_the_swing_hold_backs_the_clock_away_from_a_swing_along_a_wall():
    """wall90: within touchdown.hold_clearance the clock runs backwards at
    touchdown.hold_retreat while the estimated sideways link speed l |delta'| exceeds
    touchdown.hold_lateral_speed (the frame itself not rotating), and only stands still
    (alpha = 0) once the landers are sensed on the surface (``touched``); a slower swing,
    or a swing farther from the wall, leaves the slowed clock; with the default (0) a
    swing never holds (slopes)."""
    from dataclasses import replace

    wall = load_scenario("wall90")
    td = wall.mission.touchdown
    assert td.hold_lateral_speed > 0.0 and scenario_default_swing_hold() == 0.0
    assert td.hold_retreat > 0.0
    wall_geo = LandingGeometry.from_scenario(wall)
    rule = ContactRule(wall)
    l = wall.tether.length
    rate = math.radians(10.0)  # 7 cm/s of reference speed at l = 0.4 m
    c = 0.5 * td.hold_clearance
    alpha = min(1.0, (td.approach_speed + td.approach_gain * c) / (l * rate))
    assert alpha < 1.0

    def swinging(speed: float, t: float, height: float = c) -> StateEstimate:
        est = estimate(wall_geo, wall, t, phi=wall_geo.phi_star, phi_dot=0.0, height=height)
        return replace(est, link=replace(est.link, delta_dot=speed / l))

    fast, slow_swing = 1.5 * td.hold_lateral_speed, 0.9 * td.hold_lateral_speed
    dt = 0.01
    slow = SlowApproach(td, rule.geometry, l, LATERAL_CLEARANCE)
    slow.start(9.0)
    tau0 = slow.advance(10.0, swinging(0.0, 10.0), rate)
    tau = slow.advance(10.0 + dt, swinging(-fast, 10.0 + dt), rate)  # either sign
    assert slow.alpha == -td.hold_retreat and tau == pytest.approx(tau0 - td.hold_retreat * dt)
    assert slow.held == pytest.approx(dt)
    tau2 = slow.advance(10.0 + 2 * dt, swinging(slow_swing, 10.0 + 2 * dt), rate)
    assert slow.alpha == pytest.approx(alpha) and tau2 == pytest.approx(tau + alpha * dt)
    slow.advance(10.0 + 3 * dt, swinging(fast, 10.0 + 3 * dt, 2.0 * td.hold_clearance), rate)
    assert slow.alpha > 0.0  # farther than hold_clearance: no hold
    slow.touched = True  # on the surface: a swing stops the clock, no retreat
    tau4 = slow.advance(10.0 + 4 * dt, swinging(fast, 10.0 + 4 * dt), rate)
    tau5 = slow.advance(10.0 + 5 * dt, swinging(fast, 10.0 + 5 * dt), rate)
    assert slow.alpha == 0.0 and tau5 == tau4
    # the default: no swing hold
    off = SlowApproach(
        td.model_copy(update={"hold_lateral_speed": 0.0}), rule.geometry, l, LATERAL_CLEARANCE
    )
    off.start(9.0)
    off.advance(10.0, swinging(0.0, 10.0), rate)
    off.advance(10.0 + dt, swinging(10.0 * fast, 10.0 + dt), rate)
    assert off.alpha == pytest.approx(alpha)


def scenario_default_swing_hold() -> float:
    """``mission.touchdown.hold_lateral_speed`` of the slope scenarios [m/s]."""
    return load_scenario("slope50").mission.touchdown.hold_lateral_speed


# ---------------------------------------------------------------------- campaign regressions
STUDY = ["tether.length=1.2", "tether.hook_drop=1.0"]
"""The 1000-run slope study of docs/results.md: base overrides, 100 runs per slope, seed 2026."""


def study_run(slope: float, seed: int | None = None, *, runs: int = 100,
              index: int | None = None, extra: tuple[str, ...] = ()) -> Job:  # fmt: skip
    """The campaign job of the study (``runs`` per slope) whose per-run seed is ``seed``, or
    whose run index is ``index``, at ``slope``; ``extra`` overrides go on the study's
    scenario (the draw is the same: it depends on the seeds only)."""
    base = load_scenario("slope50", [*STUDY, *extra])
    spec = CampaignSpec(
        scenario=base.model_dump(mode="json"), runs=runs, methods=("tethered",),
        sweep=Sweep.parse("surface.slope_deg=20,35,50,60,70"), seed=2026,
    )  # fmt: skip
    (run,) = [
        r for r in spec.expand()
        if r.sweep_value == slope and (r.seed == seed if index is None else r.index == index)
    ]  # fmt: skip
    return Job(scenario=spec.scenario, run=run)


SHARED_STUDY_RUNS = {(70.0, 3556918803)}
"""Study runs that two tests below fly (slope, per-run seed): flown once per process."""


@functools.cache
def _flown_once(slope: float, seed: int):
    return run_job(study_run(slope, seed), LegacySource(seed))


def fly_study_run(slope: float, seed: int):
    """The study's run ``seed`` at ``slope`` flown exactly as the study drew it (its
    campaign job with :class:`LegacySource`): its record and its result. The runs in
    :data:`SHARED_STUDY_RUNS` are flown once per process (the flight is deterministic)."""
    if (slope, seed) in SHARED_STUDY_RUNS:
        return _flown_once(slope, seed)
    return run_job(study_run(slope, seed), LegacySource(seed))


@pytest.mark.slow
@pytest.mark.parametrize(
    ("slope", "seed"),
    [(60.0, 2046954335), (70.0, 3556918803), (70.0, 1375799514), (70.0, 1787690056)],
)  # fmt: skip
def test_previously_failing_study_runs_land(slope, seed):
    """The study's failures at 60-70 deg, each flown exactly as the campaign does, now land
    with conditions 1-5 and complete the mission: 2046954335, 3556918803 and 1375799514
    (the guarded descent stopped above the surface: the estimated link 0.8 deg off on a
    1 cm anchor belief error and a gust), 1787690056 (a gust's roll swing met the surface
    at 0.34 rad/s: the rate hold waits it out; later, with the rotor drag and the press
    descent on, it bounced at t = 35.1 s, conditions (2) and (3): the preload and the press
    descent began at 34.82 s on a link the rate hold's retreat had stopped 1.6 deg below
    its reference, and drove the landers into the surface; since the retreat rule of
    :meth:`MissionSupervisor._lock_on_contact` the preload waits until the link is back at
    the reference); 705352918 has its own test below."""
    record, _ = fly_study_run(slope, seed)  # as the study drew it
    assert record["status"] == "ok", record["error"]
    verdict = record["verdict"]
    assert verdict["success"], verdict["reason"]
    landing = verdict["landing"]
    assert landing["conditions"] == {str(i): True for i in range(1, 6)}
    tol = load_scenario("slope50").verdict
    assert landing["touchdown_speed_mps"] < tol.touchdown_speed
    assert landing["slip_m"] < tol.rest_slip
    assert verdict["return_completed"]


@pytest.mark.slow
def test_the_rest_begins_on_loaded_landers():
    """Study run 705352918 at 70 deg (first a false hook-jam alarm on the return, the
    free-flight tension estimate's 1.1 N bias, then fixed). Judged on the truth it failed
    again: in the touchdown hold the vehicle stood on two landers, the other two about 1 cm
    up, floated 3 mm off the surface for the hold's last 0.3 s and fell back at 0.14 m/s
    when the motors went off (conditions 3, 4 at the contact that starts the rest). With
    the spin-down (``mission.touchdown.spin_down_time``) the landers take the load while
    the thrust is shed: the contact that starts the rest is under way when the rest
    begins, every lander carries load then, and the mission succeeds with 1-5."""
    from tetherland.config.verdict import motors_off_thrust
    from tetherland.verdict.touchdown import find_touchdowns

    seed = 705352918
    record, result = run_job(study_run(70.0, seed), LegacySource(seed))
    assert record["status"] == "ok", record["error"]
    verdict = result.verdict.summary
    assert verdict["success"], verdict["reason"]
    landing = verdict["landing"]
    assert landing["conditions"] == {str(i): True for i in range(1, 6)}
    truth = result.plant_scenario
    tol = truth.verdict
    found = find_touchdowns(
        result.log, tol.touchdown_force, motors_off_thrust(truth.vehicle),
        truth.sim.contact_time_constant,
    )  # fmt: skip
    assert found.rest is not None and found.rest_contact is not None
    assert found.rest_contact < found.rest.start  # landed before the thrust went
    forces = np.nan_to_num(result.log["lander_surface_forces"][found.rest.start])
    assert np.all(forces > tol.touchdown_force), forces  # on all four landers
    for bounce in landing["bounces"]:  # the contacts on the way: none too fast
        assert bounce["touchdown_speed_mps"] < tol.touchdown_speed
        assert bounce["touchdown_accel_mps2"] < tol.touchdown_accel
    assert verdict["return"]["completed"]


def test_contact_settings_are_validated():
    """Every new contact field names itself and its range on bad input."""
    from tetherland.errors import ConfigError

    base = load_scenario("slope50")
    for bad in ("mission.contact.clearance=0", "mission.contact.stall_rate_deg_s=-1",
                "mission.contact.creep_rate_deg_s=0",
                "mission.contact.press_deg=20", "mission.contact.impact_force=0"):  # fmt: skip
        with pytest.raises(ConfigError, match=bad.split("=")[0].split(".")[1]):
            with_overrides(base, [bad])


@pytest.mark.slow
def test_the_motors_go_off_on_the_surface_not_above_it():
    """The 70 deg run 3556918803 used to believe contact 2.1 cm above the surface (the link
    lagged 0.8 deg on a 1 cm anchor error and a gust) and dropped the vehicle when the
    motors went off (a drop the judge counts as slip once a lander has grazed). Now the
    landers carry load through the hold and when the motors go off, and the true
    clearance at that moment is below a millimetre."""
    record, result = fly_study_run(70.0, 3556918803)  # as the study drew it
    assert record["status"] == "ok", record["error"]
    plant = result.plant_scenario
    assert result.summary["success"], result.summary["reason"]
    log = result.log
    phase = log["phase"]
    off = int(np.argmax(phase == int(Phase.MOTORS_OFF)))
    hold = np.nonzero(phase == int(Phase.TOUCHDOWN))[0]
    t_L = result.flight.reference.times["t_L"]
    held = hold[log["t"][hold] > t_L + 0.2]  # after the hold has settled
    assert held.size > 0 and held[-1] == off - 1
    # loaded: the surface presses a lander at some physics step of the tick (the touch
    # sensors read once a tick miss single-step contacts)
    loaded = log["lander_surface_forces"][held].sum(axis=1) > 0.0
    assert loaded.mean() > 0.8  # a lander chatters (unloads for single ticks) early in the hold
    assert np.all(loaded[log["t"][held] > log["t"][off] - 0.05])  # loaded when motors go off
    R_WB = quat_to_rotmat(log["q_WB"][off])
    assert ContactGeometry.from_scenario(plant).clearance(log["p_W"][off], R_WB) < 1e-3


def _tared_run(scenario, geo, *, bias, push, tare):
    """1 s of ticks with the landers 3 cm above the surface (free flight, the estimate
    reading only its ``bias``), then 2 s landed and stalled with ``bias + push``; the time
    after landing at which the rule confirms (None: never), with the tare on or off."""
    sc = with_overrides(scenario, [f"mission.contact.tare_time_constant={0.2 if tare else 0}"])
    rule = ContactRule(sc)
    assert feed(rule, geo, sc, 1.0, lag_deg=1.0, rate_deg=0.0, normal=bias, height=0.03) is None
    if tare:
        assert rule.tare == pytest.approx(bias, abs=1e-9)  # the free-flight reading
    return feed(rule, geo, sc, 2.0, lag_deg=1.0, rate_deg=0.0, normal=bias + push,
                t0=1.0 + 1.0 / RATE)  # fmt: skip


def test_the_tare_removes_the_estimates_own_bias(scenario, geo):
    """A thrust or mass belief a few per cent off reads as a surface force b in free
    flight. A light true push N (above the threshold, N + b below it) is missed without
    the tare and confirmed with it once the filtered N - 0 crosses the threshold:
    t = tau ln(N / (N - threshold)) + dwell after landing. A positive bias alone (no push)
    is a false contact without the tare and none with it."""
    cfg = scenario.mission.contact
    b, push = -0.2, 0.25
    assert push > cfg.surface_force > push + b  # the premise: missed only for the bias
    assert _tared_run(scenario, geo, bias=b, push=push, tare=False) is None
    t = _tared_run(scenario, geo, bias=b, push=push, tare=True)
    tau = cfg.surface_force_time_constant
    expected = tau * math.log(push / (push - cfg.surface_force)) + cfg.dwell
    assert t == pytest.approx(expected, abs=2.0 / RATE)
    # a positive bias of the same size fakes the surface force on a stalled link ...
    assert _tared_run(scenario, geo, bias=-b, push=0.0, tare=False) is not None
    # ... which the tare reads as what it is
    assert _tared_run(scenario, geo, bias=-b, push=0.0, tare=True) is None
