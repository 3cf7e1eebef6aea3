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
control tick of :class:`UkfEstimator`). Instructions per call = collected / N.

Measured (issue 25, N = 2000, main 2900ad9 -> s25-mission 272a5f2, the same workload file
against both source trees): ``rotation`` 20.8k -> 5.7k (compiled, the matrix allocated in
Python), ``path`` 22.8k -> 11.5k (compiled rows), ``faults`` 21.8k -> 21.8k (a compiled
attachment geometry measured 22.1k: its call costs what the arithmetic does, so it stays
in Python), ``estimator`` 278.4k -> 265.6k.
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
    else:
        raise SystemExit(f"unknown workload {name!r}: rotation, path, faults, estimator or tick")
    return call


def climb_runner():
    """The ``tick`` workload's closed loop: a runner composed as a mission's (the UKF, the
    free-flight controller inside the believed-aero wrappers, the tethered method's
    diagnostics), flying slope50's vehicle from the start pad up a free-flight path."""
    from tetherland.control import FreeFlightController
    from tetherland.control.rotor_drag import with_aero_belief
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

    controller = with_aero_belief(FreeFlightController(sc), sc)
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
