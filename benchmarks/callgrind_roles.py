"""Instructions per control tick of each role of the closed loop (valgrind callgrind).

Load-independent counterpart of the wall-time table of ``bench_mission.py`` (issue 25):
one full mission (seed 0) runs under callgrind with instrumentation off, switched on only
inside sim-time windows spread over the mission (approach, stretch, tethered landing,
touchdown, tethered takeoff, return; 12 s, 6000 control ticks in all), so that the
warm-up (kernel loading, planning) costs no instrumented time. Each role's methods are
called through a C iterator of its own (``filter_next`` for the estimator, ...), so the
callgrind inclusive cost of that C function is the role's cost; the total is everything
instrumented (the windows; it includes the few million instructions of each switch of
the instrumentation, a few thousand per tick). Prints instructions per control tick of
each role, the rest of the runner and the total. (``--toggle-collect`` cannot be used:
a function entered while the instrumentation is off is never seen entered.)

Run (several minutes; the numba cache of the tree must be warm, e.g. after one mission):

    .venv/bin/python benchmarks/callgrind_roles.py [scenario] [controller]

Compare commits with the same script: ``PYTHONPATH=<other tree>/src`` runs another tree.
Not part of ``make bench``. Each wrapped call adds the wrapper's own few thousand
instructions to "runner (the rest)": read that line as an upper bound of the runner's own
scheduling.

Measured (issue 25, slope50 hierarchical seed 0, main 2291551 -> s25-tick: the log row
in one buffer, cheaper frozen records, instructions per control tick): log row 52.8k ->
39.3k, supervisor 131.9k -> 119.8k, estimator 207.8k -> 196.7k, rotor-drag feed-forward
41.5k -> 33.9k, sensors 45.2k -> 40.3k, controller 51.6k -> 48.2k, ground-effect
compensation 33.6k -> 31.5k, runner (the rest) 174.7k -> 169.0k, plant 235.3k ->
235.6k; total 1008.8k -> 948.8k (-5.9 %).
"""

from __future__ import annotations

import functools
import itertools
import math
import operator
import os
import re
import subprocess
import sys
import tempfile
from collections import deque

WINDOWS_S = ((6.0, 8.0), (22.0, 24.0), (30.0, 32.0), (33.0, 35.0), (38.0, 40.0), (62.0, 64.0))
"""Sim-time windows [s] in which instructions are counted (slope50's phases at seed 0)."""

ROLE_SYMBOLS = {
    "filter_next": "estimator (IMU predict, estimate, mocap update)",
    "filterfalse_next": "controller (incl. allocation)",
    "functools_reduce": "ground-effect compensation (incl. the controller)",
    "takewhile_next": "supervisor (reference)",
    "dropwhile_next": "plant (2 MuJoCo steps, rotors, hook)",
    "starmap_next": "sensors (2 IMU samples, mocap, the IMU's true biases)",
    "accumulate_next": "log row",
    "groupby_next": "rotor-drag feed-forward (incl. the compensation)",
    "methodcaller_call": "plant reads (rotor state, hook point, contact peaks, magnet)",
    "islice_next": "supervisor command_sent (fault monitor)",
}


def _via(kind: str):
    """Call a function through a C iterator (or reduce) named by ``kind``."""
    calls = {
        "filter": lambda f: deque(filter(lambda _: f(), (0,)), maxlen=0),
        "filterfalse": lambda f: deque(itertools.filterfalse(lambda _: f(), (0,)), maxlen=0),
        "takewhile": lambda f: deque(itertools.takewhile(lambda _: f() or False, (0,)), maxlen=0),
        "dropwhile": lambda f: deque(itertools.dropwhile(lambda _: f() or True, (0,)), maxlen=0),
        "starmap": lambda f: deque(itertools.starmap(f, ((),)), maxlen=0),
        "accumulate": lambda f: deque(itertools.accumulate((0, 0), lambda a, b: f()), maxlen=0),
        "reduce": lambda f: functools.reduce(lambda a, b: f(), (0,), 0),
        "groupby": lambda f: deque(itertools.groupby((0,), lambda _: f()), maxlen=0),
        "methodcaller": lambda f: operator.methodcaller("__call__")(f),
        "islice": lambda f: deque(itertools.islice(iter(lambda: f() or 0, 1), 1), maxlen=0),
    }
    return calls[kind]


def _wrap(cls: type, name: str, kind: str) -> None:
    original = cls.__dict__[name]
    static = isinstance(original, staticmethod)
    fn = original.__func__ if static else original
    call = _via(kind)

    def wrapper(*args, **kwargs):
        box = []
        call(lambda: box.append(fn(*args, **kwargs)))
        return box[0]

    setattr(cls, name, staticmethod(wrapper) if static else wrapper)


def _instrument(on: bool) -> None:
    subprocess.run(["callgrind_control", "-i", "on" if on else "off", str(os.getpid())],
                   check=True, stdout=subprocess.DEVNULL)  # fmt: skip


def inner(scenario_name: str, controller: str) -> None:
    """The run under valgrind: prints ``ticks=N`` (control ticks counted)."""
    from tetherland.config import load_scenario, with_overrides
    from tetherland.control import SwitchingController
    from tetherland.control.ground_effect import GroundEffectCompensation
    from tetherland.control.rotor_drag import RotorDragCompensation
    from tetherland.estimation import UkfEstimator
    from tetherland.methods import Planners
    from tetherland.mission import MissionSupervisor
    from tetherland.runs import run_mission
    from tetherland.sim.plant import Plant
    from tetherland.sim.sensors import Imu, Mocap

    try:
        from tetherland.sim.log_row import LogRow

        log_row: tuple[type, tuple[str, ...], str] = (LogRow, ("write",), "accumulate")
    except ImportError:  # a tree before sim/log_row.py (main 2291551 and older)
        from tetherland.sim.runner import Runner

        log_row = (Runner, ("_write_row",), "accumulate")
    planners = Planners()
    scenario = load_scenario(scenario_name)
    short = ["mission.abort_time=0.5", "mission.safe_hover_time=0.5"]  # warm-up
    run_mission(with_overrides(scenario, short), planners=planners, controller=controller)
    for cls, names, kind in (
        (UkfEstimator, ("predict", "estimate", "update", "command_sent"), "filter"),
        (SwitchingController, ("update",), "filterfalse"),
        (GroundEffectCompensation, ("update",), "reduce"),
        (MissionSupervisor, ("reference",), "takewhile"),
        (Plant, ("step",), "dropwhile"),
        (Imu, ("sample", "bias_into"), "starmap"),
        (Mocap, ("measure",), "starmap"),
        log_row,
        (RotorDragCompensation, ("update",), "groupby"),
        (Plant, ("rotor_state_into", "hook_point_into", "contact_peaks_into", "set_magnet",
                 "set_latch"), "methodcaller"),
        (MissionSupervisor, ("command_sent",), "islice"),
    ):
        for name in names:
            _wrap(cls, name, kind)
    edges = [*sorted(e for w in WINDOWS_S for e in w), math.inf]
    state = {"k": 0, "i": 0, "k_on": 0, "ticks": 0}

    def observer(t: float, plant: object) -> None:
        state["k"] += 1
        if t >= edges[state["i"]]:
            state["i"] += 1
            on = state["i"] % 2 == 1
            if on:
                state["k_on"] = state["k"]
            else:
                state["ticks"] += state["k"] - state["k_on"]
            _instrument(on)

    run_mission(scenario, seed=0, planners=planners, controller=controller,
                observers=[observer])  # fmt: skip
    if state["i"] % 2 == 1:
        _instrument(False)
        state["ticks"] += state["k"] - state["k_on"]
    print(f"ticks={state['ticks']}")


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--inner":
        inner(sys.argv[2], sys.argv[3])
        return
    scenario = sys.argv[1] if len(sys.argv) > 1 else "slope50"
    controller = sys.argv[2] if len(sys.argv) > 2 else "hierarchical"
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "cg.out")
        run = subprocess.run(
            ["valgrind", "--tool=callgrind", "--instr-atstart=no", f"--callgrind-out-file={out}",
             sys.executable, __file__, "--inner", scenario, controller],
            capture_output=True, text=True, check=True,
        )  # fmt: skip
        ticks = int(re.search(r"^ticks=(\d+)", run.stdout, re.M).group(1))
        annotated = subprocess.run(["callgrind_annotate", "--inclusive=yes", out],
                                   capture_output=True, text=True, check=True).stdout  # fmt: skip
    cost: dict[str, int] = {}
    total = 0
    for line in annotated.splitlines():
        if "PROGRAM TOTALS" in line:
            total = int(line.split()[0].replace(",", ""))
        m = re.match(r"\s*([\d,]+)\s+\([^)]*\)\s+\S*:(\w+)", line)
        if m and m.group(2) in ROLE_SYMBOLS and ROLE_SYMBOLS[m.group(2)] not in cost:
            cost[ROLE_SYMBOLS[m.group(2)]] = int(m.group(1).replace(",", ""))
    controller_key, wrapper_key = ROLE_SYMBOLS["filterfalse_next"], ROLE_SYMBOLS["functools_reduce"]
    drag_key = ROLE_SYMBOLS["groupby_next"]
    if drag_key in cost:  # the outer wrapper's own part
        own = cost.pop(drag_key) - cost.get(wrapper_key, cost.get(controller_key, 0))
        cost["rotor-drag feed-forward (around the compensation)"] = own
    if wrapper_key in cost:  # the wrapper's own part
        own = cost.pop(wrapper_key) - cost.get(controller_key, 0)
        cost["ground-effect compensation (around the controller)"] = own
    cost["runner (scheduling, the rest)"] = total - sum(cost.values())
    print(f"instructions per control tick ({scenario}, {controller}, seed 0, {ticks} ticks "
          f"in {len(WINDOWS_S)} windows):")  # fmt: skip
    for key, value in sorted(cost.items(), key=lambda kv: -kv[1]):
        print(f"  {key:52s} {value / ticks / 1e3:8.1f} k")
    print(f"  {'total':52s} {total / ticks / 1e3:8.1f} k")


if __name__ == "__main__":
    main()
