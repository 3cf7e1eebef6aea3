"""The landing-method role: two implementations, one registry, pluggable controllers."""

from __future__ import annotations

import pytest

from tetherland.cli import main
from tetherland.config import load_scenario, with_overrides
from tetherland.control import HierarchicalController
from tetherland.errors import ConfigError
from tetherland.interfaces import ControlMode
from tetherland.methods import METHODS, LandingMethod, Planners, get_method, method_names
from tetherland.runs import run_mission


def test_every_registered_method_implements_the_role():
    assert method_names() == ("tethered", "free-flight")
    for name, method in METHODS.items():
        assert isinstance(method, LandingMethod) and method.name == name
        assert set(method.expects.required_conditions) <= {1, 2, 3, 4, 5}
    # the tethered method promises more than the contact-free one
    tethered, free = METHODS["tethered"].expects, METHODS["free-flight"].expects
    assert tethered.required_conditions == (1, 2, 3, 4, 5) and 4 not in free.required_conditions
    assert tethered.tension and tethered.takeoff and tethered.return_home
    assert not (free.tension or free.takeoff or free.return_home)


def test_unknown_methods_are_one_line_errors(capsys, tmp_path):
    with pytest.raises(ConfigError, match="--method must be one of tethered, free-flight"):
        get_method("rocket", "--method")
    assert main(["mission", "slope50", "--method", "rocket", "--out", str(tmp_path)]) == 2
    assert capsys.readouterr().err.count("\n") == 1


class CountingController:
    """A user's tethered controller: the hierarchical law, counting its calls."""

    def __init__(self, scenario):
        self.inner = HierarchicalController(scenario)
        self.calls = 0

    def reset(self):
        self.inner.reset()

    def update(self, t, estimate, reference):
        assert reference.mode == ControlMode.TETHERED
        self.calls += 1
        return self.inner.update(t, estimate, reference)


@pytest.mark.slow
def test_a_users_tethered_controller_flies_the_tethered_phases():
    sc = with_overrides(load_scenario("slope50"), ["mission.abort_time=32"])
    mine = CountingController(sc)
    result = run_mission(sc, controller=mine, seed=0, planners=Planners())
    t_tethered = result.record.times["t_tethered"]
    ticks = (32.0 - t_tethered) * sc.controller.rate_hz
    assert mine.calls == pytest.approx(ticks, abs=2)
    assert result.record.controller == "CountingController"
    assert result.summary["outcome"] == "aborted" and not result.summary["crashed"]
