"""Wall time of the design search (`tetherland design`) and of the feasibility map.

Run: ``.venv/bin/python benchmarks/bench_design.py [--repeats 3] [--map]``

* search: :func:`search_designs` for the default vehicle at 50, 80 and 90 deg (default
  hooking pass) and at 90 and 94 deg (overshoot 5 cm, capture radius 5 cm), with a
  planner whose solvers are already built; the first line is a cold call that builds them;
* map (``--map``): the whole feasibility map of ``tetherland design --out`` (37 slopes x
  11 cable lengths, plus the steepest slope per length).

The counts (candidates analysed, candidates planned) show how the analysis pre-filter
keeps the OCP to a short list. The machine's load average is printed before and after:
other jobs on a shared machine inflate the numbers.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

from tetherland.config import load_scenario
from tetherland.design import feasibility_map, search_designs
from tetherland.planning import Planner

RELAXED = ["mission.hooking.overshoot=0.05", "tether.capture_radius=0.05"]
CASES = ((50.0, []), (80.0, []), (90.0, []), (90.0, RELAXED), (94.0, RELAXED))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--map", action="store_true", help="also time the feasibility map")
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    planner = Planner()
    t0 = time.perf_counter()
    first = search_designs(load_scenario("slope50"), 50.0, planner=planner)
    print(f"{'cold (builds the solvers)':28} {time.perf_counter() - t0:8.2f} s  "
          f"({first.candidates} analysed, {first.planned} planned)")  # fmt: skip
    for slope, extra in CASES:
        scenario = load_scenario("slope50", extra)
        times, result = [], None
        for _ in range(args.repeats):
            t = time.perf_counter()
            result = search_designs(scenario, slope, planner=planner)
            times.append(time.perf_counter() - t)
        assert result is not None
        label = f"search {slope:g} deg" + (" (relaxed pass)" if extra else "")
        print(
            f"{label:28} {statistics.median(times):8.2f} s  ({result.candidates} analysed, "
            f"{result.planned} planned, {'feasible' if result.feasible else result.binding})"
        )
    if args.map:
        t = time.perf_counter()
        fmap = feasibility_map(load_scenario("slope50", RELAXED), planner=planner)
        print(f"{'feasibility map':28} {time.perf_counter() - t:8.2f} s  ({len(fmap.cells)} cells)")
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
