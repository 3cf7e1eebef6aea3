"""Mission-glue workloads for instruction counts (valgrind callgrind), beside hotpaths.py.

The per-tick pieces of the mission's own logic, each on its own and without a planner
(quick under valgrind), counted as in :mod:`hotpaths` (the hot path runs ``n`` times
inside ``math.fsum``, which callgrind collects with ``--toggle-collect=math_fsum``):

    valgrind --tool=callgrind --toggle-collect=math_fsum --callgrind-out-file=/dev/null \\
        .venv/bin/python benchmarks/hotpaths_glue.py WORKLOAD N

Workloads: ``rotation`` (``quat_to_rotmat`` of an estimate's quaternion), ``path`` (one
free-flight reference sample inside a move, :meth:`Path.sample`), ``faults`` (one
:meth:`FaultMonitor.check` in free flight, airborne: the rotor rule's cable torque and the
motion-capture rule, a new estimate every call) and ``estimator`` (hotpaths.py's: one
control tick of :class:`UkfEstimator`) and ``row`` (one log row of a tethered tick as the
runner writes it, :class:`~tetherland.sim.log_row.LogRow`). Instructions per call =
collected / N.

``tick`` counts N control ticks of a whole runner loop (:func:`climb_runner`: the UKF, the
free-flight controller in the mission's believed-aero wrappers, a climbing free-flight
reference, the tethered method's diagnostic columns, slope50's plant) in one run and
prints ``ticks=N``: instructions per control tick = collected / N. Everything of a tick
is in it (2 physics steps, sensors, estimator, controller, log row, the runner's own
scheduling); a change to the runner's glue, the log row or the records shows as the
difference between two source trees (the same workload file run against both).

Measured (issue 25, N = 2000, main 2900ad9 -> s25-mission 272a5f2, the same workload file
against both source trees): ``rotation`` 20.8k -> 5.7k (compiled, the matrix allocated in
Python), ``path`` 22.8k -> 11.5k (compiled rows), ``faults`` 21.8k -> 21.8k (a compiled
attachment geometry measured 22.1k: its call costs what the arithmetic does, so it stays
in Python), ``estimator`` 278.4k -> 265.6k.

Measured (issue 25, main 2291551 -> s25-tick, the same bits on the default missions):
``row`` (N = 2000) 53.0k -> 43.4k per row (:class:`~tetherland.sim.log_row.LogRow`: the
runner's parts are views of one row buffer, the estimate, reference and command one
concatenate), ``tick`` (N = 500) 639.9k -> 584.4k per control tick (the row, the frozen
records through :func:`~tetherland.records.fast_init`, the loop's copies through
Ellipsis views).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path as FilePath

import numpy as np

sys.path.insert(0, str(FilePath(__file__).parent))

from hotpaths import _counted, _estimator
from tetherland.config import load_scenario
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import StateEstimate
from tetherland.mission.faults import FaultMonitor
from tetherland.mission.paths import Path
from tetherland.mission.phases import Phase
from tetherland.rotations import quat_to_rotmat
from tetherland.state import LinkState, RigidBodyState


def _estimates(n: int) -> list[StateEstimate]:
    """``n`` estimates laid out as the estimator's (views into one array each)."""
    rng = np.random.default_rng(1)
    out = []
    for k in range(n):
        x = np.zeros(30)
        x[0:3] = rng.normal(size=3)
        q = rng.normal(size=4)
        x[6:10] = q / np.linalg.norm(q)
        body = RigidBodyState(x[0:3], x[3:6], x[6:10], x[10:13])
        out.append(StateEstimate(k * 2e-3, body, x[16:19], x[13:16], np.eye(15) * 1e-4,
                                 LinkState(0.1, 0.2, 0.0, 0.0), 0.5, x[27:30]))  # fmt: skip
    return out


def workload(name: str) -> Callable[[], None]:
    """The call that ``name`` counts."""
    k = [0]
    if name == "rotation":
        quats = [e.body.q_WB for e in _estimates(64)]

        def call() -> None:
            k[0] += 1
            quat_to_rotmat(quats[k[0] % 64])

    elif name == "path":
        path = Path(0.0, np.zeros(3), 1.0, 1.0).to(np.array([5.0, 1.0, 2.0]))
        span = path.t_end - 0.02

        def call() -> None:
            k[0] += 1
            path.sample(0.01 + (k[0] * 2e-3) % span)

    elif name == "faults":
        sc = load_scenario("slope50")
        monitor = FaultMonitor(sc, LandingGeometry.from_scenario(sc))
        estimates = _estimates(256)

        def call() -> None:
            k[0] += 1
            monitor.check(5.0 + k[0] * 2e-3, estimates[k[0] % 256], Phase.APPROACH, True)

    elif name == "estimator":
        call = _estimator()
    elif name == "row":
        call = _log_row()
    else:
        raise SystemExit(
            f"unknown workload {name!r}: rotation, path, faults, estimator, row or tick"
        )
    return call


def _log_row() -> Callable[[], None]:
    """One log row as the runner writes it at a control tick of a tethered phase (an
    estimate with biases and link, a tethered reference, a command with torque, the
    tethered method's diagnostics), into a log that grows as in a run."""
    from tetherland.interfaces import Command, ControlMode, Reference
    from tetherland.methods.tethered import DIAGNOSTICS
    from tetherland.sim.log import BASE_COLUMNS, LogWriter, diagnostic_columns

    columns = BASE_COLUMNS + diagnostic_columns(DIAGNOSTICS)
    estimates = _estimates(64)
    Y = np.arange(20.0).reshape(5, 4)
    refs = [Reference(k * 2e-3, ControlMode.TETHERED, 9, output=Y, yaw=0.1, thrust_ff=9.0)
            for k in range(64)]  # fmt: skip
    cmd = Command(np.full(4, 520.0), 9.5, np.array([0.01, -0.02, 0.0]))
    sd = np.arange(40.0)
    args = (sd[0:3], sd[6:12])
    k = [0]
    try:
        from tetherland.sim.log_row import LogRow
    except ImportError:  # a tree before sim/log_row.py (main 2291551 and older)
        from tetherland.sim.runner import Runner

        nan3 = np.full(3, np.nan)
        parts = [np.zeros(9), np.zeros(13), *args, np.zeros(15), np.zeros(11), np.zeros(3),
                 np.zeros(19), *([nan3] * 11), np.zeros(len(DIAGNOSTICS))]  # fmt: skip
        writer = LogWriter(columns, 1)

        def call() -> None:
            k[0] += 1
            i = k[0] % 64
            Runner._write_row(writer, parts, i * 2e-3, estimates[i], refs[i], cmd, True, 0.1, 1.0)

        return call
    row = LogRow(columns)
    writer = LogWriter(columns, 1)

    def call() -> None:
        k[0] += 1
        i = k[0] % 64
        row.write(writer, *args, i * 2e-3, estimates[i], refs[i], cmd, True, 0.1, 1.0)

    return call


def climb_runner():
    """The ``tick`` workload's closed loop: a runner composed as a mission's (the UKF, the
    switching controller inside the believed-aero wrappers, compiled as a mission's stack,
    the tethered method's diagnostics), flying slope50's vehicle from the start pad up a
    free-flight path. (Earlier versions of this file wrapped the free-flight law alone:
    compare trees with the same workload file, as always.)"""
    from tetherland.control import SwitchingController
    from tetherland.control.stack import with_aero_belief
    from tetherland.estimation import UkfEstimator
    from tetherland.interfaces import Reference
    from tetherland.methods.tethered import DIAGNOSTICS
    from tetherland.sim.plant import Plant
    from tetherland.sim.runner import Runner

    sc = load_scenario("slope50")
    plant = Plant(sc)
    start = plant.start_state()
    path = Path(0.0, start.p_W, 1.0, 1.0).to(start.p_W + np.array([0.6, 0.3, 1.2]))

    class Climb:
        def reference(self, t: float, estimate: StateEstimate) -> Reference:
            return Reference(t=t, phase=int(Phase.TAKEOFF), p_W=path.sample(t), yaw=0.0)

    controller = with_aero_belief(SwitchingController(sc), sc)
    hover = np.full(4, np.sqrt(sc.vehicle.mass * 9.81 / (4 * sc.vehicle.thrust_coefficient)))
    estimator = UkfEstimator(sc, start, 0.0, rotor_speeds0=hover)
    runner = Runner(sc, controller, estimator=estimator, reference=Climb(), plant=plant,
                    diagnostic_keys=DIAGNOSTICS)  # fmt: skip
    return runner, start, hover


def _tick(n: int) -> None:
    """``n`` control ticks of :func:`climb_runner`'s loop (one run, counted whole)."""
    runner, start, hover = climb_runner()
    runner.run(0.1, initial_state=start, rotor_speeds=hover)  # warm-up
    logs = []
    _counted(lambda: logs.append(runner.run(n * 2e-3, initial_state=start, rotor_speeds=hover)))
    print(f"ticks={len(logs[0])} status={logs[0].status.value}")


def _repeat(call: Callable[[], None], n: int) -> None:
    for _ in range(n):
        call()


def main() -> None:
    name, n = sys.argv[1], int(sys.argv[2])
    if name == "tick":
        _tick(n)
        return
    call = workload(name)
    _repeat(call, 100)  # warm-up: compiled kernels loaded, caches filled
    _counted(lambda: _repeat(call, n))


if __name__ == "__main__":
    main()
