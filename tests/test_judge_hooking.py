"""The hooking attempts judged on the plant's truth (issue 22, item 6: hooking failures by
kind: missed, bounced, wrong side, tangled, hook did not release).

The logs are built from a told story of the hook's crown relative to the bar's axis (in
the anchor frame F_A: x_A toward the landing point, y_A along the bar), its caught state
and the line's tension; every expected outcome follows from the story and the
mechanism's own numbers (the hook's reach, the catch load).
"""

from __future__ import annotations

import numpy as np
import pytest

from tetherland import GRAVITY
from tetherland.config import Scenario, load_scenario, scenario_from_dict
from tetherland.geometry import LandingGeometry
from tetherland.sim.log import BASE_COLUMNS, SimLog, row_width
from tetherland.verdict import Expectations, RunRecord, judge
from tetherland.verdict.hooking import HookingOutcome, ReleaseOutcome, judge_hooking
from tetherland.verdict.record import PhaseSpan

DT = 0.01
"""Tick of the built logs [s] (coarser than the missions': the rules count no ticks)."""


@pytest.fixture(scope="module", params=[None, 0.0], ids=["rising", "flat"])
def bar(request: pytest.FixtureRequest) -> Scenario:
    """The bar mechanism, the default rising arms or the flat arm."""
    data = load_scenario("slope50").model_dump(mode="python")
    data["mechanism"]["kind"], data["anchor"]["h_A"] = "bar", 0.0
    if request.param is not None:
        data["mechanism"]["hook_arm_rise_deg"] = request.param
    return scenario_from_dict(data, "slope50")


def near(s: Scenario) -> float:
    """The farthest crown-to-axis distance at which a part of the hook can touch the bar,
    from the hook's dimensions, bounded leg by leg from the crown: the arm, ``hook_reach``
    out and its fall ``hook_reach tan(hook_arm_rise_deg)`` down (0 for flat arms), a
    tip's length up, the two radii."""
    m = s.mechanism
    assert m.hook_tip_angle_deg == 0.0  # tips straight up: the outer reach is the arm's
    fall = m.hook_reach * np.tan(np.radians(m.hook_arm_rise_deg))
    return m.hook_reach + fall + m.hook_tip_length + m.hook_radius + m.bar_radius


def catch_load(s: Scenario) -> float:
    return s.mechanism.catch_threshold * s.mechanism.hook_mass * GRAVITY


def story(s: Scenario, t_end: float, crown_A: list[tuple[float, float, float, float]],
          caught: list[tuple[float, float]], tension: list[tuple[float, float, float]],
          ) -> SimLog:  # fmt: skip
    """A log: ``crown_A`` = (from t, x_A, y_A, z_A) of the crown relative to p_A, held from
    t on; ``caught`` = (from, to) intervals of the plant's caught state; ``tension`` =
    (from, to, N) intervals of the true line tension (the hook's weight otherwise)."""
    geo = LandingGeometry.from_scenario(s)
    t = np.round(np.arange(0.0, t_end + DT / 2, DT), 9)
    log = SimLog(BASE_COLUMNS, np.zeros((len(t), row_width(BASE_COLUMNS))), {})
    log["t"][:] = t
    log["q_WB"][:] = (1.0, 0.0, 0.0, 0.0)  # the vehicle is not judged here: level, at the origin
    crown = np.zeros((len(t), 3))
    for t0, x, y, z in crown_A:
        crown[t >= t0] = geo.p_A + geo.R_WA @ np.array([x, y, z])
    log["hook_p_W"][:] = crown
    state = np.zeros(len(t))
    for t0, t1 in caught:
        state[(t >= t0) & (t < t1)] = 1.0
    log["hook"][:] = state
    force = np.full(len(t), s.mechanism.hook_mass * GRAVITY)
    for t0, t1, f in tension:
        force[(t >= t0) & (t < t1)] = f
    log["tension"][:] = force
    return log


def record(s: Scenario, phases: list[tuple[str, float, float]]) -> RunRecord:
    return RunRecord(
        method="tethered", seed=0, truth=s.model_dump(mode="json"),
        belief=s.model_dump(mode="json"), expects=Expectations(), finished=True,
        phases=tuple(PhaseSpan(n, a, b, "") for n, a, b in phases), hook_attempts=1,
    )  # fmt: skip


def away(s: Scenario) -> tuple[float, float, float]:
    """The pass's end, crown relative to the bar's axis in F_A: ``pass_offset`` on the far
    side of the bar, ``pass_depth + pass_margin`` under its axis (the bar where believed)
    [m]; beyond the hook's reach of the bar (:func:`near`)."""
    m = s.mechanism
    p = (-m.pass_offset, 0.0, -(m.pass_depth + m.pass_margin))
    assert float(np.linalg.norm(p)) > near(s)
    return p


def test_a_hook_caught_held_and_released_is_caught_then_released(bar):
    phases = [("hooking", 1.0, 2.0), ("stretch", 2.0, 3.0), ("tethered_landing", 3.0, 5.0),
              ("release", 5.0, 6.0), ("unhook", 6.0, 7.0)]  # fmt: skip
    log = story(bar, 8.0, [(0.0, *away(bar)), (2.0, 0.0, 0.0, -0.008), (6.5, *away(bar))],
                caught=[(2.2, 6.5)], tension=[(2.5, 5.0, 9.0)])  # fmt: skip
    report = judge_hooking(log, record(bar, phases), bar)
    (a,) = report.attempts
    assert a.outcome is HookingOutcome.CAUGHT and a.t_caught == pytest.approx(2.2)
    assert (a.t_start, a.t_end) == (1.0, 3.0)  # the pass to the tethered landing
    assert a.min_distance_m == pytest.approx(0.008, abs=1e-12)
    assert report.release is ReleaseOutcome.RELEASED and report.t_lost is None
    # the judge puts it in summary.json
    assert judge(log, record(bar, phases)).summary["hooking"] == report.to_dict()


def test_a_hook_still_caught_after_the_unhooking_did_not_release(bar):
    phases = [("hooking", 1.0, 2.0), ("tethered_landing", 3.0, 5.0), ("unhook", 6.0, 7.0)]
    log = story(bar, 8.0, [(0.0, 0.0, 0.0, -0.008)], caught=[(2.0, 9.0)], tension=[])
    assert judge_hooking(log, record(bar, phases), bar).release is ReleaseOutcome.NOT_RELEASED


def test_a_hook_that_comes_off_under_the_landing_load_is_lost_at_that_time(bar):
    phases = [("hooking", 1.0, 2.0), ("tethered_landing", 3.0, 5.0)]
    log = story(bar, 6.0, [(0.0, 0.0, 0.0, -0.008), (4.0, 0.1, 0.0, -0.2)],
                caught=[(2.0, 4.0)], tension=[(3.0, 4.0, 9.0)])  # fmt: skip
    report = judge_hooking(log, record(bar, phases), bar)
    assert report.outcome is HookingOutcome.CAUGHT  # caught when the landing started
    assert report.t_lost == pytest.approx(4.0)


def test_caught_then_off_before_the_landing_is_a_bounce_and_the_retry_counts_apart(bar):
    phases = [("hooking", 1.0, 2.0), ("stretch", 2.0, 4.0), ("retry", 4.0, 5.0),
              ("hooking", 5.0, 6.0), ("tethered_landing", 7.0, 8.0)]  # fmt: skip
    log = story(bar, 8.0, [(0.0, *away(bar)), (2.0, 0.0, 0.0, -0.008), (3.0, *away(bar)),
                           (6.0, 0.0, 0.0, -0.008)],
                caught=[(2.2, 2.6), (6.3, 9.0)], tension=[])  # fmt: skip
    report = judge_hooking(log, record(bar, phases), bar)
    assert [a.outcome for a in report.attempts] == [HookingOutcome.BOUNCED, HookingOutcome.CAUGHT]
    assert [(a.t_start, a.t_end) for a in report.attempts] == [(1.0, 5.0), (5.0, 7.0)]


@pytest.mark.parametrize("margin", [-0.001, 0.001])
def test_never_caught_is_a_bounce_within_the_hooks_reach_of_the_bar_else_a_miss(bar, margin):
    """The crown passes the bar's axis at the hook's reach -/+ 1 mm, the line never
    loaded: a part of the hook could touch the bar (bounced) or could not (missed)."""
    d = near(bar) + margin
    phases = [("hooking", 1.0, 2.0), ("stretch", 2.0, 4.0)]
    log = story(bar, 4.0, [(0.0, *away(bar)), (2.0, 0.0, 0.0, -d), (3.0, *away(bar))],
                caught=[], tension=[])  # fmt: skip
    (a,) = judge_hooking(log, record(bar, phases), bar).attempts
    assert a.min_distance_m == pytest.approx(d, abs=1e-12)
    assert a.outcome is (HookingOutcome.BOUNCED if margin < 0 else HookingOutcome.MISSED)
    assert a.max_free_tension_N == pytest.approx(bar.mechanism.hook_mass * GRAVITY)


def test_a_hook_along_the_bar_beyond_its_end_is_measured_from_the_end(bar):
    """On the axis's line but 8 cm past the bar's end: 8 cm from the bar, not 0, beyond
    the hook's reach (6.3 cm for the defaults, 5.1 cm with flat arms)."""
    half = 0.5 * bar.mechanism.bar_length
    phases = [("hooking", 1.0, 2.0)]
    log = story(bar, 3.0, [(0.0, 0.0, half + 0.08, 0.0)], caught=[], tension=[])
    (a,) = judge_hooking(log, record(bar, phases), bar).attempts
    assert a.min_distance_m == pytest.approx(0.08, abs=1e-12)
    assert near(bar) < 0.08 and a.outcome is HookingOutcome.MISSED


@pytest.mark.parametrize(("z", "kind"), [(-0.15, HookingOutcome.WRONG_SIDE),
                                         (-0.01, HookingOutcome.TANGLED)])  # fmt: skip
def test_a_line_loaded_without_the_catch_is_wrong_side_away_from_the_bar_else_tangled(
        bar, z, kind):  # fmt: skip
    """The line pulled at 1.5 times the catch load while the plant says not caught: with
    the crown 15 cm under the axis (on the surface under the bar) the hook snagged on
    something else; with it 1 cm from the axis the line is wound on the bar."""
    load = catch_load(bar)
    phases = [("hooking", 1.0, 2.0), ("stretch", 2.0, 4.0)]
    log = story(bar, 4.0, [(0.0, *away(bar)), (2.0, 0.0, 0.0, z)], caught=[],
                tension=[(2.5, 3.0, 1.5 * load)])  # fmt: skip
    (a,) = judge_hooking(log, record(bar, phases), bar).attempts
    assert a.outcome is kind and a.max_free_tension_N == pytest.approx(1.5 * load)
    # just under the catch load it is not loaded: a bounce at the bar, or a miss
    log = story(bar, 4.0, [(0.0, *away(bar)), (2.0, 0.0, 0.0, z)], caught=[],
                tension=[(2.5, 3.0, 0.99 * load)])  # fmt: skip
    (a,) = judge_hooking(log, record(bar, phases), bar).attempts
    d = min(abs(z), float(np.linalg.norm(away(bar))))  # the story's closest crown
    assert a.min_distance_m == pytest.approx(d, abs=1e-12)
    assert a.outcome is (HookingOutcome.BOUNCED if d <= near(bar) else HookingOutcome.MISSED)


def test_the_point_hook_is_judged_on_its_caught_state_alone():
    """The default mechanism (``disk``): no line that can load without the catch; a loaded
    cable never caught is still a miss, and the hook point's distance is not measured."""
    disk = load_scenario("slope50")
    assert disk.mechanism.kind == "disk"
    phases = [("hooking", 1.0, 2.0), ("retry", 3.0, 4.0), ("hooking", 4.0, 5.0),
              ("tethered_landing", 6.0, 7.0)]  # fmt: skip
    log = story(disk, 7.0, [(0.0, 0.0, 0.0, 0.0)], caught=[(4.5, 9.0)],
                tension=[(2.0, 2.5, 5.0)])  # fmt: skip
    report = judge_hooking(log, record(disk, phases), disk)
    assert [a.outcome for a in report.attempts] == [HookingOutcome.MISSED, HookingOutcome.CAUGHT]
    assert all(a.min_distance_m is None for a in report.attempts)
