"""Real-time factor of the full mission and where the time goes (issue 6).

Target: at least 10x real time on one core. Prints the median over seeds and the wall
time per control tick of each role (plant, estimator, supervisor, controller, the rest).
Run: .venv/bin/python benchmarks/bench_mission.py [scenario] [runs]
"""

from __future__ import annotations

import statistics
import sys
import time
from collections import defaultdict

from tetherland.config import load_scenario
from tetherland.control import SwitchingController
from tetherland.estimation import UkfEstimator
from tetherland.mission import MissionSupervisor
from tetherland.runs import run_mission
from tetherland.sim.plant import Plant


def _timed(cls: type, name: str, key: str, acc: dict[str, float]) -> None:
    original = getattr(cls, name)

    def wrapper(self, *args, **kwargs):
        t0 = time.perf_counter()
        try:
            return original(self, *args, **kwargs)
        finally:
            acc[key] += time.perf_counter() - t0

    setattr(cls, name, wrapper)


def main() -> None:
    name = sys.argv[1] if len(sys.argv) > 1 else "slope50"
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    scenario = load_scenario(name)
    rtfs = []
    for seed in range(runs):
        result = run_mission(scenario, seed=seed)
        s = result.summary
        rtfs.append(s["real_time_factor"])
        print(f"seed {seed}: success={s['success']} sim {s['sim_time_s']:.1f} s, "
              f"wall {s['wall_time_s']:.2f} s, {s['real_time_factor']:.2f}x real time")  # fmt: skip
    print(f"median real-time factor ({name}, {runs} runs): {statistics.median(rtfs):.2f}x "
          "(target >= 10x)")  # fmt: skip

    acc: dict[str, float] = defaultdict(float)
    _timed(Plant, "step", "plant (MuJoCo step + rotors)", acc)
    _timed(UkfEstimator, "estimate", "estimator: estimate (UKF predict, link, tension)", acc)
    _timed(UkfEstimator, "update", "estimator: mocap update", acc)
    _timed(MissionSupervisor, "reference", "supervisor", acc)
    _timed(SwitchingController, "update", "controller (incl. allocation)", acc)
    t0 = time.perf_counter()
    result = run_mission(scenario, seed=0)
    total = time.perf_counter() - t0
    ticks = len(result.log)
    print(f"\nwall time per 2 ms control tick ({ticks} ticks, {total:.2f} s incl. planning):")
    rest = result.wall_time_s - sum(acc.values())
    for key, value in sorted(acc.items(), key=lambda kv: -kv[1]):
        print(f"  {key:52s} {value / ticks * 1e6:7.1f} us")
    print(f"  {'runner (sensors, log rows, scheduling)':52s} {rest / ticks * 1e6:7.1f} us")


if __name__ == "__main__":
    main()
