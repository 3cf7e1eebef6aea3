"""Real-time factor of the full mission and where the time goes (issues 6, 13 and 25).

Target (issue 25, item 2): the full ``slope50`` and ``wall90`` missions at 30x real time
or more on one core, hierarchical and DFL, with everything the plant simulates by
default (median over seeds). Prints the median real-time factor of each controller and
the current factor against the target, then the wall time per 2 ms control tick of each
role (estimator, controller, supervisor, plant, sensors, log row, the rest of the
runner), next to the numbers of commit d57bf1a (before the compiled loop of issue 13,
measured with this script on the same machine).

Wall time on the shared machine varies by 30 % and more: compare commits back to back
(the same run for both, e.g. ``PYTHONPATH=<other tree>/src``), and use instruction counts
(``bench_callgrind.sh``) for changes of a few percent.

Each run also prints its real-time factor on process CPU time (user + system of this
process over the run), which other agents' load on a shared machine changes far less
than the wall time: compare trees by that one, runs interleaved (A B A B).

Run: .venv/bin/python benchmarks/bench_mission.py [scenarios] [runs] [controller ...]
(``scenarios`` comma-separated, default ``slope50,wall90``: issue 25 asks both.)

Measured (issue 25, s25-loop against main a9476d0): the per-call savings of the loop's
glue in CHANGELOG.md; whole missions moved by less than the shared machine's noise.
"""

from __future__ import annotations

import statistics
import sys
import time
from collections import defaultdict

from tetherland.config import load_scenario, with_overrides
from tetherland.control import SwitchingController
from tetherland.estimation import UkfEstimator
from tetherland.methods import Planners
from tetherland.mission import MissionSupervisor
from tetherland.runs import run_mission
from tetherland.sim.log_row import LogRow
from tetherland.sim.plant import Plant
from tetherland.sim.sensors import Imu, Mocap

BEFORE_COMMIT = "d57bf1a"
BEFORE_RTF = {"hierarchical": 8.4, "dfl": 8.1}
"""Median real-time factor on slope50 at commit d57bf1a (3 seeds, this script). The machine
is shared: its speed varies by 25 % and more between sessions (d57bf1a measured 11.7x in a
quieter one), so compare runs made back to back."""
BEFORE_TICK_US = {
    "estimator (IMU predict, estimate, mocap update)": 84.2,
    "controller (incl. allocation)": 61.9,
    "supervisor (reference)": 23.7,
    "plant (2 MuJoCo steps, rotors, hook)": 21.0,
    "sensors (2 IMU samples, mocap)": 6.5,
    "log row": 9.4,
    "runner (scheduling, the rest)": 15.9,
}
"""Wall time per control tick at commit d57bf1a, hierarchical controller, seed 0, measured
with this script right before the after-numbers of CHANGELOG.md [us]."""
TARGET_RTF = {"hierarchical": 30.0, "dfl": 30.0}
"""Issue 25, item 2: every default mission (slope50, wall90) at 30x real time, both
controllers, on one core."""

ROLES = (
    (UkfEstimator, "predict", "estimator (IMU predict, estimate, mocap update)"),
    (UkfEstimator, "predict_rows", "estimator (IMU predict, estimate, mocap update)"),
    (UkfEstimator, "estimate", "estimator (IMU predict, estimate, mocap update)"),
    (UkfEstimator, "update", "estimator (IMU predict, estimate, mocap update)"),
    (UkfEstimator, "command_sent", "estimator (IMU predict, estimate, mocap update)"),
    (SwitchingController, "update", "controller (incl. allocation)"),
    (MissionSupervisor, "reference", "supervisor (reference)"),
    (Plant, "step", "plant (2 MuJoCo steps, rotors, hook)"),
    (Imu, "sample", "sensors (2 IMU samples, mocap)"),
    (Imu, "sample_into", "sensors (2 IMU samples, mocap)"),
    (Mocap, "measure", "sensors (2 IMU samples, mocap)"),
    (LogRow, "write", "log row"),
)


def _timed(cls: type, name: str, key: str, acc: dict[str, float]) -> None:
    original = getattr(cls, name)
    static = isinstance(cls.__dict__[name], staticmethod)

    def wrapper(*args, **kwargs):
        t0 = time.perf_counter()
        try:
            return original(*args, **kwargs)
        finally:
            acc[key] += time.perf_counter() - t0

    setattr(cls, name, staticmethod(wrapper) if static else wrapper)


def main() -> None:
    names = (sys.argv[1] if len(sys.argv) > 1 else "slope50,wall90").split(",")
    runs = int(sys.argv[2]) if len(sys.argv) > 2 else 3
    controllers = sys.argv[3:] or ["hierarchical", "dfl"]
    for name in names:
        print(f"== {name}")
        scenario_report(name, runs, controllers)


def scenario_report(name: str, runs: int, controllers: list[str]) -> None:
    """The real-time factors of ``runs`` seeds of each controller on scenario ``name``,
    then the wall time per control tick of each role (seed 0, hierarchical)."""
    scenario = load_scenario(name)
    planners = Planners()
    # first run in a process: numba loads its cached kernels (see bench_control_estimation)
    t0 = time.perf_counter()
    short = ["mission.abort_time=0.5", "mission.safe_hover_time=0.5"]  # a 1 s run
    run_mission(with_overrides(scenario, short), planners=planners)
    print(f"warm-up (kernel loading, planner compilation): {time.perf_counter() - t0:.2f} s")
    for controller in controllers:
        rtfs = []
        for seed in range(runs):
            cpu0 = time.process_time()
            s = run_mission(scenario, controller=controller, seed=seed, planners=planners).summary
            cpu = time.process_time() - cpu0  # the whole run_mission (plan, loop, verdict)
            rtfs.append(s["real_time_factor"])
            print(
                f"{controller} seed {seed}: success={s['success']} sim {s['sim_time_s']:.1f} s, "
                f"wall {s['wall_time_s']:.2f} s, {s['real_time_factor']:.1f}x real time "
                f"(on CPU time of the whole run: {s['sim_time_s'] / cpu:.1f}x)"
            )
        before = BEFORE_RTF.get(controller) if name == "slope50" else None
        target = TARGET_RTF.get(controller, 0.0)
        now = statistics.median(rtfs)
        print(
            f"median real-time factor ({name}, {controller}, {runs} runs): "
            f"{now:.1f}x (before, {BEFORE_COMMIT}: "
            f"{before if before else '-'}x; target >= {target:.0f}x)"
        )
        print(f"current factor: {now:.1f}x of the {target:.0f}x target "
              f"({'met' if now >= target else 'not met'}; {now / target:.2f} of it)")  # fmt: skip

    acc: dict[str, float] = defaultdict(float)
    originals = [(cls, method, cls.__dict__[method]) for cls, method, _ in ROLES]
    for cls, method, key in ROLES:
        _timed(cls, method, key, acc)
    try:
        result = run_mission(scenario, seed=0, planners=planners)
    finally:  # the next scenario's runs untimed
        for cls, method, original in originals:
            setattr(cls, method, original)
    ticks = len(result.log)
    print(f"\nwall time per 2 ms control tick (hierarchical, seed 0, {ticks} ticks, "
          f"timers add about 0.3 us per call):")  # fmt: skip
    rest = result.record.wall_time_s - sum(acc.values())
    rows = [*((key, value / ticks * 1e6) for key, value in acc.items()),
            ("runner (scheduling, the rest)", rest / ticks * 1e6)]  # fmt: skip
    print(f"  {'':50s} {'now':>8s} {BEFORE_COMMIT:>8s}")
    for key, us in sorted(rows, key=lambda kv: -kv[1]):
        print(f"  {key:50s} {us:6.1f} us {BEFORE_TICK_US.get(key, float('nan')):6.1f} us")
    total = sum(us for _, us in rows)
    print(f"  {'total':50s} {total:6.1f} us {sum(BEFORE_TICK_US.values()):6.1f} us")


if __name__ == "__main__":
    main()
