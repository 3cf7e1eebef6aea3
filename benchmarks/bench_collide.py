"""Cost of reading every part's contacts at the physics rate (issue 22, item 2).

Prints one JSON line: the wall time of the first 10 s of the slope50 mission (seed 0,
the whole closed loop: UKF, controllers, supervisor, plant) and of 10 s of the bare plant
(``Plant.step``) hovering and landed (four lander contacts, cable taut), best of
three. Wall times on a shared machine vary by tens of percent; the load-independent
measure is callgrind's instruction count of ``Plant.step`` (docs/theory.md section 9.1).
It uses only interfaces older than the change, so the same script measures the commit
before it; on a shared machine compare runs made back to back, alternating:

    git worktree add --detach /tmp/base <commit before>
    for i in 1 2 3; do
        PYTHONPATH=/tmp/base/src .venv/bin/python benchmarks/bench_collide.py
        .venv/bin/python benchmarks/bench_collide.py
    done
"""

from __future__ import annotations

import json
import math
import time

import numpy as np

from bench_plant import best
from tetherland import GRAVITY
from tetherland.config import load_scenario
from tetherland.runs import run_mission
from tetherland.sim.plant import Plant
from tetherland.state import RigidBodyState

SPAN = 10.0
"""Simulated time measured [s]."""


class _Clock:
    """Observer: wall time from the first control tick to the first at ``SPAN``."""

    def __init__(self) -> None:
        self.start: float | None = None
        self.wall: float | None = None

    def __call__(self, t: float, plant: Plant) -> None:
        if self.start is None:
            self.start = time.perf_counter()
        elif self.wall is None and t >= SPAN:
            self.wall = time.perf_counter() - self.start


def main() -> None:
    sc = load_scenario("slope50")
    clock = _Clock()
    run_mission(sc, seed=0, observers=[clock])
    plant = Plant(sc)
    n = round(SPAN / plant.dt)
    w_hover = math.sqrt(sc.vehicle.mass * GRAVITY / 4 / sc.vehicle.thrust_coefficient)
    s0 = plant.start_state()
    air = RigidBodyState.at_rest(s0.p_W + np.array([0.0, 0.0, 1.5]), s0.q_WB)

    def hover() -> None:
        plant.reset(air, rotor_speeds=np.full(4, w_hover))
        plant.step(n)

    def landed() -> None:
        plant.reset(plant.landed_state(), cable_engaged=True)
        plant.step(n)

    print(json.dumps({
        "mission_first_10s_wall_s": clock.wall,
        "plant_hover_10s_wall_s": best(hover),
        "plant_landed_10s_wall_s": best(landed),
    }))  # fmt: skip


if __name__ == "__main__":
    main()
