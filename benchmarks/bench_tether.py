"""Cost per physics step of each cable model (docs/tether.md).

:meth:`Plant.step` on slope50 with the cable engaged, the vehicle hanging taut below the
anchor on constant rotor speeds, for the ideal tendon, the massless elastic cable
(Dyneema, nylon) and the massive chain of 5, 10 and 20 links; and the same plants in free
flight with the cable disengaged (the parked chain still costs its joints). Each case is
the best of ``REPEATS`` runs of ``STEPS`` steps, one core; ratios are to the ideal cable
in the same run. Run: ``make bench`` or ``python benchmarks/bench_tether.py``.
"""

from __future__ import annotations

import math
import time

import mujoco
import numpy as np

from tetherland import GRAVITY
from tetherland.config import load_scenario
from tetherland.sim.plant import Plant
from tetherland.state import RigidBodyState

STEPS = 5000
REPEATS = 3
CASES = (
    ("ideal", ['tether.material="ideal"']),
    ("elastic dyneema", []),
    ("elastic nylon", ['tether.material="nylon"']),
    ("chain 5 (dyneema)", ["tether.segments=5"]),
    ("chain 10 (dyneema)", ["tether.segments=10"]),
    ("chain 20 (steel)", ['tether.material="steel"', "tether.segments=20"]),
)


def best(fn) -> float:
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    rows = []
    for name, overrides in CASES:
        sc = load_scenario("slope50", overrides)
        plant = Plant(sc)
        v = sc.vehicle
        w = math.sqrt(0.5 * v.mass * GRAVITY / 4 / v.thrust_coefficient)  # half the weight
        hang = plant.layout.geometry.p_A - np.array([0.0, 0.0, sc.tether.length + 0.005])
        taut = RigidBodyState.at_rest(hang)
        s0 = plant.start_state()
        air = RigidBodyState.at_rest(s0.p_W + np.array([0.0, 0.0, 1.5]), s0.q_WB)
        w_hover = math.sqrt(v.mass * GRAVITY / 4 / v.thrust_coefficient)

        def engaged(plant=plant, taut=taut, w=w) -> None:
            plant.reset(taut, rotor_speeds=np.full(4, w), cable_engaged=True)
            plant.step(STEPS)

        def free(plant=plant, air=air, w=w_hover) -> None:
            plant.reset(air, rotor_speeds=np.full(4, w))
            plant.step(STEPS)

        rows.append((name, plant.model.nv, best(engaged), best(free)))
    ideal_taut, ideal_free = rows[0][2], rows[0][3]
    print(
        f"tetherland cable benchmark: Plant.step, {STEPS} steps, best of {REPEATS}, "
        f"mujoco {mujoco.__version__}, one core"
    )
    head = ('cable', 'nv', 'taut us/step', 'x ideal', 'free us/step', 'x ideal')
    print(f"{head[0]:<20} {head[1]:>3} {head[2]:>13} {head[3]:>8} {head[4]:>13} {head[5]:>8}")
    for name, nv, t_taut, t_free in rows:
        print(
            f"{name:<20} {nv:>3} {t_taut / STEPS * 1e6:13.2f} {t_taut / ideal_taut:8.2f} "
            f"{t_free / STEPS * 1e6:13.2f} {t_free / ideal_free:8.2f}"
        )


if __name__ == "__main__":
    main()
