"""Time per call of each controller and of the UKF predict/update steps (issue 5).

Targets: controller update < 100 us, UKF predict < 150 us on the project's 2-core machine.
Run: .venv/bin/python benchmarks/bench_control_estimation.py
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from tetherland.config import load_scenario
from tetherland.control import DflController, FreeFlightController, HierarchicalController
from tetherland.estimation import Ukf, UkfEstimator, UkfNoise, initial_covariance
from tetherland.estimation.ukf import NavState
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import ImuSample, MocapSample, Reference
from tetherland.planning import Planner
from tetherland.planning.tracking import TrajectoryTrack
from tetherland.rotations import rotmat_to_quat
from tetherland.sim.analytic import estimate_of
from tetherland.state import RigidBodyState


def per_call_us(fn, n: int = 3000, repeats: int = 5) -> float:
    """Median over ``repeats`` of the mean time per call [us]."""
    fn()  # warm up (numba, caches)
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        samples.append((time.perf_counter() - t0) / n * 1e6)
    return statistics.median(samples)


def main() -> None:
    sc = load_scenario("slope50")
    traj = Planner().plan(sc, "landing").require()
    track = TrajectoryTrack(traj, 0.0, 500.0)
    nom, out = traj.nominal(1.0), traj.output(1.0)
    x = np.concatenate(([out.phi[0], 0.0, out.phi[1], 0.0], rotmat_to_quat(nom.R_WB), nom.omega_B))
    est = estimate_of(x, 1.0, LandingGeometry.from_scenario(sc), sc.tether.length)
    ref_t = track.reference(1.0)
    ref_f = Reference(t=1.0, p_W=np.array([est.body.p_W, np.zeros(3), np.zeros(3)]))
    rows = []
    for name, ctrl, ref in (
        ("free-flight controller", FreeFlightController(sc), ref_f),
        ("hierarchical controller", HierarchicalController(sc), ref_t),
        ("DFL controller", DflController(sc), ref_t),
    ):
        rows.append((name, per_call_us(lambda c=ctrl, r=ref: c.update(1.0, est, r)), 100.0))

    noise = UkfNoise.from_config(sc.sensors)
    ukf = Ukf(noise, NavState(np.zeros(3), np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(3),
                              np.zeros(3)), initial_covariance())  # fmt: skip
    clock = [0.0]
    f, w = np.array([0.0, 0.0, 9.81]), np.zeros(3)

    def predict() -> None:
        clock[0] += 1e-3
        ukf.predict(clock[0], f, w)

    rows.append(("UKF predict (one 1 kHz IMU sample)", per_call_us(predict), 150.0))
    q0 = np.array([1.0, 0.0, 0.0, 0.0])
    update = per_call_us(lambda: ukf.update_pose(clock[0] - 0.005, np.zeros(3), q0))
    rows.append(("UKF update (mocap pose, 5 ms late)", update, None))

    level = RigidBodyState.at_rest(np.array([0.0, 0.0, 1.0]))  # consistent with the IMU signal
    estimator = UkfEstimator(sc, level, 0.0)
    t_imu = [0.0]

    def tick() -> None:  # one 500 Hz control tick: two IMU samples, then the estimate
        for _ in range(2):
            t_imu[0] += 1e-3
            estimator.predict(ImuSample(t_imu[0], f, w))
        estimator.estimate()

    rows.append(("estimator per control tick (2 IMU samples + estimate)", per_call_us(tick), None))

    def mocap() -> None:
        tick()
        estimator.update(MocapSample(t_imu[0] - 0.005, t_imu[0], level.p_W, level.q_WB))

    rows.append(("estimator tick + mocap update", per_call_us(mocap), None))
    print(f"{'step':58s} {'us/call':>9s} {'target':>8s}")
    for name, us, target in rows:
        mark = "" if target is None else ("  ok" if us < target else "  OVER")
        print(f"{name:58s} {us:9.1f} {'' if target is None else f'{target:8.0f}'}{mark}")


if __name__ == "__main__":
    main()
