"""Cost of the live view (issue 16, item 2) on the full mission.

Target: with ``--live`` and no viewer connected the mission loop slows down by less than
10 %. Runs the slope50 mission alternately without and with a :class:`LiveView` (unpaced,
no client) and prints the median wall time of each and their ratio, and the time spent
inside the view itself (timed around each call, so independent of the machine's load);
then, with a client (in this process) subscribed to every channel, the cost of publishing
at 100 Hz (the default) and at every control tick.
Run: .venv/bin/python benchmarks/bench_live.py [scenario] [rounds]
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from foxglove_client import Client  # the tests' Foxglove WebSocket client
from tetherland.config import load_scenario
from tetherland.methods import Planners
from tetherland.runs import run_mission
from tetherland.viz.live import LiveView


class Timed:
    """Wraps an observer and adds up the wall time spent in it."""

    def __init__(self, view: LiveView) -> None:
        self.view, self.spent = view, 0.0

    def bind(self, runner, writer) -> None:
        self.view.bind(runner, writer)

    def __call__(self, t, plant) -> None:
        t0 = time.perf_counter()
        self.view(t, plant)
        self.spent += time.perf_counter() - t0


def main() -> None:
    name = sys.argv[1] if len(sys.argv) > 1 else "slope50"
    rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    scenario = load_scenario(name)
    planners = Planners()
    run_mission(scenario, seed=0, planners=planners)  # compile the solvers once
    plain, live, inside = [], [], []
    with LiveView(scenario, port=0, speed=0.0) as view:
        timed = Timed(view)
        for _ in range(rounds):
            plain.append(run_mission(scenario, seed=0, planners=planners).record.wall_time_s)
            timed.spent = 0.0
            result = run_mission(scenario, seed=0, planners=planners, observers=[timed])
            live.append(result.record.wall_time_s)
            inside.append(timed.spent / result.record.wall_time_s)
    a, b = statistics.median(plain), statistics.median(live)
    ticks = len(result.log)
    print(f"{name} mission loop, median of {rounds}: {a:.2f} s without, {b:.2f} s with --live "
          f"and no viewer ({100 * (b / a - 1):+.1f} %, machine load included); time inside "
          f"the view: {100 * statistics.median(inside):.1f} % of the loop, "
          f"{1e6 * timed.spent / ticks:.1f} us per control tick (target < 10 %)")  # fmt: skip
    for rate in (100.0, scenario.controller.rate_hz):
        with LiveView(scenario, port=0, speed=0.0, rate_hz=rate) as view:
            client = Client(view.url, duration=600.0).start()
            client.subscribed.wait(10)
            while not view.publisher.watched:
                time.sleep(0.01)
            result = run_mission(scenario, seed=0, planners=planners, observers=[view])
        wall = result.record.wall_time_s
        print(f"with a viewer subscribed to every channel, {rate:g} Hz: {wall:.2f} s, "
              f"{1e3 * (wall - a) / ticks:.2f} ms per control tick for publishing, "
              f"{result.summary['sim_time_s'] / wall:.1f}x real time")  # fmt: skip


if __name__ == "__main__":
    main()
