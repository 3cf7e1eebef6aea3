"""Compile (or load) every compiled kernel of the closed loop once: ``python -m tetherland.warmup``.

numba compiles a kernel on its first call and caches the machine code on disk
(``cache=True``, in ``__pycache__`` beside the source). On a fresh installation that first
call costs about 20 s of CPU for all kernels together, paid by the first mission or the
first test that needs them (by every test worker at once). Running this module right
after installation pays it once; later processes only load the cache (about 0.1 s). The
calls use the same argument types as the mission loop, so the loop finds every
specialisation it needs.
"""

from __future__ import annotations

import time

import numpy as np

from tetherland.config import load_scenario
from tetherland.control import DflController, FreeFlightController, HierarchicalController
from tetherland.control.tracking import FreeFlightTracker
from tetherland.estimation import UkfEstimator
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import ControlMode, Feedforward, ImuSample, MocapSample, Reference
from tetherland.state import RigidBodyState, link_state_of


def warm_up() -> float:
    """Call every kernel once with the loop's argument types; returns the time taken [s]."""
    t0 = time.perf_counter()
    sc = load_scenario("slope50")
    geo = LandingGeometry.from_scenario(sc)
    start = RigidBodyState.at_rest(geo.p_A + np.array([-0.5, 0.0, 0.5]))
    est = UkfEstimator(sc, start, 0.0)
    f, w = np.array([0.0, 0.0, 9.81]), np.zeros(3)
    est.predict(ImuSample(1e-3, f, w))
    est.update(MocapSample(5e-4, 1e-3, start.p_W, start.q_WB))
    est.predict(ImuSample(2e-3, f, w))
    e = est.estimate()
    held = np.zeros((3, 3))
    held.setflags(write=False)  # a free-flight path's pause hands out read-only rows
    for rows in (np.zeros((3, 3)), held):
        FreeFlightController(sc).update(2e-3, e, Reference(t=2e-3, p_W=rows))
    FreeFlightTracker(sc).update(2e-3, e, Reference(t=2e-3, p_W=np.zeros((5, 3))))
    output = np.zeros((5, 4))
    output[0, 0] = e.link.phi if e.link is not None else 0.5
    ff = Feedforward(omega_B=np.zeros(3), omega_dot_B=np.zeros(3), f_R=sc.vehicle.mass * 9.81)
    ref = Reference(t=2e-3, mode=ControlMode.TETHERED, output=output, feedforward=ff)
    HierarchicalController(sc).update(2e-3, e, ref)
    DflController(sc).update(2e-3, e, ref)
    x = np.concatenate((start.p_W, start.q_WB, start.v_W, start.omega_B))
    link_state_of(x, np.asarray(sc.vehicle.cable_attachment, dtype=float), geo.p_A, geo.R_WA)
    return time.perf_counter() - t0


def main() -> None:
    print(f"compiled kernels ready ({warm_up():.1f} s)")


if __name__ == "__main__":
    main()
