"""Cost of the live view (issue 16, item 2) on the full mission.

Target: with ``--live`` and no viewer connected the mission loop slows down by less than
10 %. Runs the slope50 mission alternately without and with a :class:`LiveView` (unpaced,
no client) and prints the median wall time of each and their ratio; then, with a client
subscribed to every channel, the wall time per control tick of publishing.
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
from tetherland.mission import run_mission
from tetherland.planning import Planner
from tetherland.viz.live import LiveView


def main() -> None:
    name = sys.argv[1] if len(sys.argv) > 1 else "slope50"
    rounds = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    scenario = load_scenario(name)
    planner = Planner()
    run_mission(scenario, seed=0, planner=planner)  # compile the solvers once
    plain, live = [], []
    with LiveView(scenario, port=0, speed=0.0) as view:
        for _ in range(rounds):
            plain.append(run_mission(scenario, seed=0, planner=planner).wall_time_s)
            live.append(run_mission(scenario, seed=0, planner=planner, observers=[view])
                        .wall_time_s)  # fmt: skip
    a, b = statistics.median(plain), statistics.median(live)
    print(f"{name} mission loop, median of {rounds}: {a:.2f} s without, {b:.2f} s with --live "
          f"and no viewer: {100 * (b / a - 1):+.1f} % (target < +10 %)")  # fmt: skip
    with LiveView(scenario, port=0, speed=0.0) as view:
        client = Client(view.url, duration=600.0).start()
        client.subscribed.wait(10)
        while not view.publisher.watched:
            time.sleep(0.01)
        result = run_mission(scenario, seed=0, planner=planner, observers=[view])
    ticks = len(result.log)
    print(f"with a viewer subscribed to every channel: {result.wall_time_s:.2f} s, "
          f"{1e3 * (result.wall_time_s - a) / ticks:.2f} ms per control tick for publishing, "
          f"{result.summary['sim_time_s'] / result.wall_time_s:.1f}x real time")  # fmt: skip


if __name__ == "__main__":
    main()
