"""A model-consistent synthetic IMU + motion-capture world for testing the UKF.

The truth is integrated with the filter's own discretisation from smooth true IMU
signals, so that the test measures the filter's statistics, not integration error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tetherland import GRAVITY
from tetherland.estimation import NavState
from tetherland.rotations import exp_so3, quat_multiply, rotmat_to_quat, rotvec_to_quat

G_W = np.array([0.0, 0.0, -GRAVITY])


@dataclass
class SyntheticRun:
    t: np.ndarray  # IMU times (n,)
    f_m: np.ndarray  # measured specific force (n, 3)
    w_m: np.ndarray  # measured rate (n, 3)
    truth: list[NavState]  # truth after each IMU sample
    mocap: list[tuple[float, float, np.ndarray, np.ndarray]]  # (t_meas, t_delivered, p, q)
    x0: NavState


def simulate(
    rng: np.random.Generator,
    duration: float,
    *,
    dt: float = 1e-3,
    gyro_noise: float = 0.005,
    accel_noise: float = 0.05,
    gyro_bias_walk: float = 1e-4,
    accel_bias_walk: float = 1e-3,
    gyro_bias0: float = 0.005,
    accel_bias0: float = 0.05,
    position_noise: float = 0.001,
    attitude_noise: float = math.radians(0.3),
    mocap_rate: float = 120.0,
    latency: float = 0.005,
    dropout: tuple[float, float] | None = None,
) -> SyntheticRun:
    n = round(duration / dt)
    t = dt * np.arange(1, n + 1)
    f_true = np.column_stack(
        (0.8 * np.sin(1.3 * t), 0.6 * np.cos(0.7 * t), GRAVITY + 0.5 * np.sin(2.1 * t))
    )
    w_true = np.column_stack((0.4 * np.sin(1.1 * t), 0.3 * np.cos(1.7 * t), 0.2 * np.sin(0.5 * t)))
    b_g = rng.normal(0.0, gyro_bias0, 3)
    b_a = rng.normal(0.0, accel_bias0, 3)
    p, v = np.zeros(3), np.zeros(3)
    q = rotmat_to_quat(exp_so3([0.05, -0.03, 0.2]))
    x0 = NavState(p.copy(), v.copy(), q.copy(), np.zeros(3), np.zeros(3))
    f_m = np.empty((n, 3))
    w_m = np.empty((n, 3))
    truth: list[NavState] = []
    for k in range(n):
        b_g = b_g + rng.normal(0.0, gyro_bias_walk * math.sqrt(dt), 3)
        b_a = b_a + rng.normal(0.0, accel_bias_walk * math.sqrt(dt), 3)
        from tetherland.rotations import quat_to_rotmat

        a = quat_to_rotmat(q) @ f_true[k] + G_W
        p = p + v * dt + 0.5 * dt * dt * a
        v = v + a * dt
        q = quat_multiply(q, rotvec_to_quat(w_true[k] * dt))
        q /= np.linalg.norm(q)
        f_m[k] = f_true[k] + b_a + rng.normal(0.0, accel_noise, 3)
        w_m[k] = w_true[k] + b_g + rng.normal(0.0, gyro_noise, 3)
        truth.append(NavState(p.copy(), v.copy(), q.copy(), b_g.copy(), b_a.copy()))
    mocap = []
    period = round(1.0 / (mocap_rate * dt))
    delay = round(latency / dt)
    for k in range(period - 1, n - delay, period):
        t_meas = t[k]
        if dropout is not None and dropout[0] <= t_meas < dropout[1]:
            continue
        s = truth[k]
        p_meas = s.p_W + rng.normal(0.0, position_noise, 3)
        q_meas = quat_multiply(s.q_WB, rotvec_to_quat(rng.normal(0.0, attitude_noise, 3)))
        mocap.append((t_meas, t[k + delay], p_meas, q_meas))
    return SyntheticRun(t, f_m, w_m, truth, mocap, x0)
