"""Real-time factor of the MuJoCo plant with sensors, the runner and trivial roles.

Cases (each the best of ``REPEATS`` runs of ``DURATION`` simulated seconds, one core):

1. ``mj_step``: bare MuJoCo step of the scene, hovering (no contacts) and landed (four
   contacts and the cable limit): the floor.
2. ``plant``: :meth:`Plant.step` (rotor lag, thrust actuators, hook check), hovering; with
   every ``[aero]`` effect off (the plain plant), and 5 cm above the landing pose with
   the effects on (surface factors and rotor drag every step), there also through the
   Python bindings (``Plant(..., compiled_step=False)``: the compiled physics step's
   plain form, issue 25; about 1.2x slower).
3. ``runner/hover``: the full multi-rate loop (IMU 1 kHz, mocap 120 Hz, control 500 Hz,
   log) with the truth estimator and an open-loop constant-speed controller.
4. ``runner/changing``: as 3, with a controller whose command changes every tick (no
   settled-rotor shortcut), closer to a real controller's load on the plant.
5. ``runner/landed``: as 3, landed on the 50 deg slope, motors off, cable holding: four
   lander contacts (elliptic cones) and the cable limit in the constraint solver.

Then a profile of case 4 shows what dominates. Run: ``make bench`` or
``python benchmarks/bench_plant.py``.
"""

from __future__ import annotations

import cProfile
import io
import math
import pstats
import time

import mujoco
import numpy as np

from tetherland import GRAVITY
from tetherland.config import load_scenario, with_overrides
from tetherland.interfaces import Command
from tetherland.sim.baselines import ConstantSpeedController
from tetherland.sim.plant import Plant
from tetherland.sim.runner import Runner
from tetherland.state import RigidBodyState

DURATION = 5.0
REPEATS = 3


class ChangingController:
    """Hover speeds with a tiny alternating offset: the rotor lag never settles."""

    def __init__(self, w: float) -> None:
        self._cmd = (
            Command(rotor_speeds=np.full(4, w + 0.5)),
            Command(rotor_speeds=np.full(4, w - 0.5)),
        )
        self._i = 0

    def update(self, t, estimate, reference) -> Command:
        self._i ^= 1
        return self._cmd[self._i]


def best(fn) -> float:
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    sc = load_scenario("slope50")
    v = sc.vehicle
    w_hover = math.sqrt(v.mass * GRAVITY / 4 / v.thrust_coefficient)
    plant = Plant(sc)
    s0 = plant.start_state()
    air = RigidBodyState.at_rest(s0.p_W + np.array([0.0, 0.0, 1.5]), s0.q_WB)
    n = round(DURATION / plant.dt)
    rows = []

    def bare() -> None:
        plant.reset(air, rotor_speeds=np.full(4, w_hover))
        m, d = plant.model, plant.data
        for _ in range(n):
            mujoco.mj_step(m, d)

    rows.append(("mj_step (hover)", best(bare)))

    def bare_landed() -> None:
        plant.reset(plant.landed_state(), cable_engaged=True)
        m, d = plant.model, plant.data
        for _ in range(n):
            mujoco.mj_step(m, d)

    rows.append(("mj_step (landed)", best(bare_landed)))

    def plant_only() -> None:
        plant.reset(air, rotor_speeds=np.full(4, w_hover))
        plant.step(n)

    rows.append(("plant (hover)", best(plant_only)))

    # [aero] (issue 23): the per-step surface factors and drag kernel, near the surface
    # and with every effect off (the plain plant)
    plain = Plant(with_overrides(sc, ["aero.ground_effect=false", "aero.rotor_drag=[0, 0]"]))

    def plant_plain() -> None:
        plain.reset(air, rotor_speeds=np.full(4, w_hover))
        plain.step(n)

    rows.append(("plant (hover, no aero)", best(plant_plain)))
    landed0 = plant.landed_state()
    z_S = plant.layout.geometry.surface.z_S
    near = RigidBodyState.at_rest(landed0.p_W + 0.05 * z_S, landed0.q_WB)

    def plant_near() -> None:
        plant.reset(near, rotor_speeds=np.full(4, w_hover))
        plant.step(n)

    rows.append(("plant (5 cm up, aero)", best(plant_near)))
    # the same through the Python bindings (the compiled step's plain form, same bits)
    python_step = Plant(sc, compiled_step=False)

    def plant_near_python() -> None:
        python_step.reset(near, rotor_speeds=np.full(4, w_hover))
        python_step.step(n)

    rows.append(("  (same, Python step)", best(plant_near_python)))

    hover_speeds = np.full(4, w_hover)
    hover = Runner(sc, ConstantSpeedController.hover(v), seed=0)
    rows.append(
        (
            "runner/hover",
            best(lambda: hover.run(DURATION, initial_state=air, rotor_speeds=hover_speeds)),
        )
    )
    changing = Runner(sc, ChangingController(w_hover), seed=0)

    def run_changing() -> None:
        changing.run(DURATION, initial_state=air, rotor_speeds=hover_speeds)

    rows.append(("runner/changing", best(run_changing)))
    landed = Runner(sc, ConstantSpeedController.motors_off(), seed=0)
    landed_state = landed.plant.landed_state()
    rows.append(
        (
            "runner/landed",
            best(lambda: landed.run(DURATION, initial_state=landed_state, cable_engaged=True)),
        )
    )

    print(
        f"tetherland plant benchmark: {DURATION:g} s simulated, best of {REPEATS}, "
        f"mujoco {mujoco.__version__}, one core"
    )
    print(f"{'case':<24} {'wall [s]':>9} {'us/step':>9} {'x real time':>12}")
    for name, wall in rows:
        print(f"{name:<24} {wall:9.3f} {wall / n * 1e6:9.2f} {DURATION / wall:12.1f}")

    prof = cProfile.Profile()
    prof.enable()
    run_changing()
    prof.disable()
    out = io.StringIO()
    pstats.Stats(prof, stream=out).sort_stats("tottime").print_stats(12)
    print("\nprofile of runner/changing (tottime = time inside the function itself):")
    print("\n".join(line for line in out.getvalue().splitlines() if line.strip())[:3000])


if __name__ == "__main__":
    main()
