"""Fly the whole mission with your own tethered controller (any Controller works)."""

from tetherland.config import load_scenario
from tetherland.control import HierarchicalController
from tetherland.runs import run_mission


class RecordingController:
    """Gamma_HC^b wrapped to record the largest link tracking error it saw: a stand-in for
    your own control law (it needs ``update``; ``reset`` is called when tethered control
    starts)."""

    def __init__(self, scenario):
        self.inner, self.worst = HierarchicalController(scenario), 0.0

    def reset(self):
        self.inner.reset()

    def update(self, t, estimate, reference):
        command = self.inner.update(t, estimate, reference)
        self.worst = max(self.worst, abs(command.diagnostics.get("e_phi", 0.0)))
        return command


scenario = load_scenario("slope50")
mine = RecordingController(scenario)
result = run_mission(scenario, controller=mine, seed=1)  # the UKF estimates, plant = truth
print(result.verdict.outcome.value, result.summary["landing"]["conditions"])
print(f"largest link error under my controller: {mine.worst:.4f} rad")
assert result.success
