"""Compiled (numba) kernels of the UKF: sigma points, prediction and pose update.

The filter's maths is documented in :mod:`tetherland.estimation.ukf`; these functions only
make it fast (the 31 sigma points through every 1 kHz IMU sample in a few microseconds).
Vectors: x = [p_W (3), v_W (3), q_WB (4, scalar-first), b_g (3), b_a (3)]; error state
e = [dp, dv, dtheta_B, db_g, db_a] (15); q_true = q_hat * exp(dtheta).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland import GRAVITY

N_ERR = 15
N_SIG = 2 * N_ERR + 1
GRAVITY_Z = -GRAVITY


@njit(cache=True)
def qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a * b of scalar-first quaternions."""
    return np.array(
        [
            a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
            a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
            a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
            a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
        ]
    )


@njit(cache=True)
def qexp(x: float, y: float, z: float) -> np.ndarray:
    """Quaternion of the rotation vector (x, y, z) (exact, smooth through zero)."""
    angle = math.sqrt(x * x + y * y + z * z)
    if angle < 1e-8:
        s = 0.5 - angle * angle / 48.0
    else:
        s = math.sin(0.5 * angle) / angle
    return np.array([math.cos(0.5 * angle), s * x, s * y, s * z])


@njit(cache=True)
def qlog(q: np.ndarray) -> np.ndarray:
    """Rotation vector (shortest rotation) of a unit quaternion."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    s = math.sqrt(x * x + y * y + z * z)
    if s < 1e-8:
        scale = 2.0 / max(w, 1e-12)
    else:
        scale = 2.0 * math.atan2(s, w) / s
    return np.array([scale * x, scale * y, scale * z])


@njit(cache=True)
def qconj(q: np.ndarray) -> np.ndarray:
    return np.array([q[0], -q[1], -q[2], -q[3]])


@njit(cache=True)
def rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """R(q) v."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    tx = 2.0 * (y * v[2] - z * v[1])
    ty = 2.0 * (z * v[0] - x * v[2])
    tz = 2.0 * (x * v[1] - y * v[0])
    return np.array(
        [
            v[0] + w * tx + (y * tz - z * ty),
            v[1] + w * ty + (z * tx - x * tz),
            v[2] + w * tz + (x * ty - y * tx),
        ]
    )


@njit(cache=True)
def sqrt_factor(P: np.ndarray) -> np.ndarray:
    """A matrix S with S S^T = P (Cholesky; eigen-decomposition if P is not numerically PD)."""
    Ps = 0.5 * (P + P.T)
    try:
        return np.linalg.cholesky(Ps)
    except Exception:
        w, V = np.linalg.eigh(Ps)
        for i in range(w.shape[0]):
            w[i] = math.sqrt(max(w[i], 1e-15))
        return V * w


@njit(cache=True)
def sigma_points(x: np.ndarray, P: np.ndarray, gamma: float) -> tuple[np.ndarray, np.ndarray]:
    """Error offsets D (31, 15) and full states X (31, 16) of the sigma points."""
    S = sqrt_factor(P) * gamma
    D = np.zeros((N_SIG, N_ERR))
    for j in range(N_ERR):
        for i in range(N_ERR):
            D[1 + j, i] = S[i, j]
            D[1 + N_ERR + j, i] = -S[i, j]
    X = np.empty((N_SIG, 16))
    q = x[6:10]
    for s in range(N_SIG):
        for i in range(6):
            X[s, i] = x[i] + D[s, i]
        dq = qmul(q, qexp(D[s, 6], D[s, 7], D[s, 8]))
        X[s, 6:10] = dq
        for i in range(6):
            X[s, 10 + i] = x[10 + i] + D[s, 9 + i]
    return D, X


@njit(cache=True)
def predict(
    x: np.ndarray,
    P: np.ndarray,
    t_prev: float,
    ts: np.ndarray,
    fs: np.ndarray,
    ws: np.ndarray,
    wm: np.ndarray,
    wc: np.ndarray,
    gamma: float,
    noise: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Unscented prediction through the IMU samples (ts, fs, ws).

    ``noise`` = [accel_noise, gyro_noise, gyro_bias_walk, accel_bias_walk, floor].
    Returns the new x, P and the centre point's position (k, 3) and attitude (k, 4) after
    each sample (the mean history for delayed measurements).
    """
    k = ts.shape[0]
    _, X = sigma_points(x, P, gamma)
    hist_p = np.empty((k, 3))
    hist_q = np.empty((k, 4))
    Qd = np.zeros(N_ERR)
    t_last = t_prev
    for j in range(k):
        dt = ts[j] - t_last
        t_last = ts[j]
        var_v = (noise[0] * dt) ** 2
        var_th = (noise[1] * dt) ** 2
        fl = noise[4] ** 2
        for i in range(3):
            Qd[i] += max(0.25 * var_v * dt * dt, fl)
            Qd[3 + i] += max(var_v, fl)
            Qd[6 + i] += max(var_th, fl)
            Qd[9 + i] += max(noise[2] ** 2 * dt, fl)
            Qd[12 + i] += max(noise[3] ** 2 * dt, fl)
        for s in range(N_SIG):
            q = X[s, 6:10]
            f_b = np.empty(3)
            for i in range(3):
                f_b[i] = fs[j, i] - X[s, 13 + i]
            acc = rotate(q, f_b)
            acc[2] += GRAVITY_Z
            for i in range(3):
                X[s, i] += X[s, 3 + i] * dt + 0.5 * dt * dt * acc[i]
                X[s, 3 + i] += acc[i] * dt
            dq = qexp(
                (ws[j, 0] - X[s, 10]) * dt, (ws[j, 1] - X[s, 11]) * dt, (ws[j, 2] - X[s, 12]) * dt
            )
            X[s, 6:10] = qmul(q, dq)
        hist_p[j] = X[0, 0:3]
        hist_q[j] = X[0, 6:10]
    # mean: linear parts by weights, attitude on the manifold around the centre point
    q_ref = X[0, 6:10].copy()
    q_ref_c = qconj(q_ref)
    dth = np.empty((N_SIG, 3))
    for s in range(N_SIG):
        dth[s] = qlog(qmul(q_ref_c, X[s, 6:10]))
    dth_mean = np.zeros(3)
    lin_mean = np.zeros(12)
    for s in range(N_SIG):
        dth_mean += wm[s] * dth[s]
        for i in range(6):
            lin_mean[i] += wm[s] * X[s, i]
            lin_mean[6 + i] += wm[s] * X[s, 10 + i]
    dev = np.empty((N_SIG, N_ERR))
    for s in range(N_SIG):
        for i in range(6):
            dev[s, i] = X[s, i] - lin_mean[i]
            dev[s, 9 + i] = X[s, 10 + i] - lin_mean[6 + i]
        for i in range(3):
            dev[s, 6 + i] = dth[s, i] - dth_mean[i]
    Pn = (dev.T * wc) @ dev
    for i in range(N_ERR):
        Pn[i, i] += Qd[i]
    q_new = qmul(q_ref, qexp(dth_mean[0], dth_mean[1], dth_mean[2]))
    q_new /= math.sqrt(q_new @ q_new)
    xn = np.empty(16)
    xn[0:6] = lin_mean[0:6]
    xn[6:10] = q_new
    xn[10:16] = lin_mean[6:12]
    return xn, 0.5 * (Pn + Pn.T), hist_p, hist_q


@njit(cache=True)
def update_pose(
    x: np.ndarray,
    P: np.ndarray,
    p_then: np.ndarray,
    q_then: np.ndarray,
    p_meas: np.ndarray,
    q_meas: np.ndarray,
    wm: np.ndarray,
    wc: np.ndarray,
    gamma: float,
    R_diag: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Unscented update with a pose measured when the estimate was (p_then, q_then).

    The innovation is formed against the estimate at the measurement time and applied to
    the current state (delayed fusion). Returns the new x, P and the NIS.
    """
    D, X = sigma_points(x, P, gamma)
    Z = np.empty((N_SIG, 6))
    for s in range(N_SIG):
        Z[s, 0:3] = X[s, 0:3]
        Z[s, 3:6] = D[s, 6:9]
    z_mean = wm @ Z
    d_mean = wm @ D
    dZ = Z - z_mean
    dD = D - d_mean
    S = (dZ.T * wc) @ dZ
    for i in range(6):
        S[i, i] += R_diag[i]
    Pxz = (dD.T * wc) @ dZ
    innov = np.empty(6)
    innov[0:3] = p_meas - p_then - (z_mean[0:3] - x[0:3])
    innov[3:6] = qlog(qmul(qconj(q_then), q_meas)) - z_mean[3:6]
    K = np.linalg.solve(S, Pxz.T).T
    dx = K @ innov
    xn = x.copy()
    for i in range(6):
        xn[i] += dx[i]
    q = qmul(x[6:10], qexp(dx[6], dx[7], dx[8]))
    xn[6:10] = q / math.sqrt(q @ q)
    for i in range(6):
        xn[10 + i] += dx[9 + i]
    Pn = P - K @ S @ K.T
    nis = float(innov @ np.linalg.solve(S, innov))
    return xn, 0.5 * (Pn + Pn.T), nis
