"""The safe hover after an abort ends once the vehicle is still (docs/faults.md): a vehicle
recovering from a lost cable or a fault is not in its safe state while it still moves,
so the supervisor holds the hover past ``mission.safe_hover_time`` until its estimated
speed has stayed under ``safe_hover_settle_speed`` for ``settle_time``, at most
``safe_hover_max_time`` longer."""

from __future__ import annotations

import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.interfaces import StateEstimate
from tetherland.mission import MissionSupervisor, Phase, plan_mission
from tetherland.mission.hooking import shortest_leg
from tetherland.sim.plant import Plant
from tetherland.state import RigidBodyState

T_ABORT = 1.0
"""Mission time of the abort [s]."""


@pytest.fixture(scope="module")
def slope50_plan():
    s = load_scenario("slope50")
    return s, plan_mission(s, Plant(s).start_state())


def _hold_end(s) -> float:
    """End of the hold: the hover point is where the vehicle is, a leg of the mission's
    shortest duration, then ``safe_hover_time`` [s]."""
    return T_ABORT + shortest_leg(s) + s.mission.safe_hover_time


def _end_of_safe_hover(s, plan, speed_at) -> tuple[float, str]:
    """Abort at :data:`T_ABORT` with the vehicle hovering where it is and tick the
    supervisor with estimates moving at ``speed_at(t)`` m/s (along x_W); returns the time
    the run ends (the move to ABORTED) and the supervisor's message for it."""
    sup = MissionSupervisor(s, plan)
    dt = 1.0 / s.controller.rate_hz
    p = np.array(plan.start.p_W, dtype=float) + np.array([0.0, 0.0, 1.0])
    q = np.array([1.0, 0.0, 0.0, 0.0])

    def est(t: float) -> StateEstimate:
        v = np.array([speed_at(t), 0.0, 0.0])
        return StateEstimate(t=t, body=RigidBodyState(p.copy(), v, q, np.zeros(3)))

    sup.abort(T_ABORT, est(T_ABORT), "test abort")
    assert sup.phase == Phase.SAFE_HOVER
    limit = T_ABORT + s.mission.safe_hover_time + s.mission.safe_hover_max_time + 1.0
    for k in range(round(T_ABORT / dt), round(limit / dt)):
        t = k * dt
        sup.reference(t, est(t))
        if sup.phase == Phase.ABORTED:
            return t, sup.records[-1].exit_reason
    pytest.fail("the safe hover never ended")


def test_a_still_vehicle_ends_the_safe_hover_after_its_hold(slope50_plan):
    s, plan = slope50_plan
    t_end, why = _end_of_safe_hover(s, plan, lambda t: 0.0)
    dt = 1.0 / s.controller.rate_hz
    assert t_end == pytest.approx(_hold_end(s), abs=1.5 * dt)
    assert why == "safe hover held: run ended"


@pytest.mark.parametrize("moving_for", [-0.2, 0.5, 3.0])
def test_a_moving_vehicle_holds_the_safe_hover_until_still(slope50_plan, moving_for: float):
    """Moving at 3x the settle speed until ``moving_for`` s past the hold's end (before it:
    < 0), then still: the run ends ``settle_time`` after the last moving tick, not at the
    hold's end."""
    s, plan = slope50_plan
    m = s.mission
    t_still = _hold_end(s) + moving_for
    fast = 3.0 * m.safe_hover_settle_speed
    t_end, why = _end_of_safe_hover(s, plan, lambda t: fast if t < t_still else 0.0)
    dt = 1.0 / s.controller.rate_hz
    assert t_end == pytest.approx(t_still + m.settle_time, abs=1.5 * dt)
    assert why == "safe hover held: run ended"


def test_a_vehicle_that_never_settles_ends_the_hover_after_the_longest_hold(slope50_plan):
    s, plan = slope50_plan
    m = s.mission
    t_end, why = _end_of_safe_hover(s, plan, lambda t: 2.0 * m.safe_hover_settle_speed)
    dt = 1.0 / s.controller.rate_hz
    assert t_end == pytest.approx(_hold_end(s) + m.safe_hover_max_time, abs=1.5 * dt)
    assert why == "safe hover held, the vehicle not still: run ended"
