"""UKF kernels: sigma points, prediction and delayed pose update (docs/theory.md section 8).

The filter's maths is documented in :mod:`tetherland.estimation.ukf`. This module holds it
twice:

- ``*_reference`` functions: plain numpy, the equations as written (sigma points of the
  error state, the process model through every IMU sample, the unscented mean on the
  attitude manifold, the delayed-fusion update). Readable, slow, used by the tests.
- compiled kernels (numba, ``cache=True``) that do the same on preallocated arrays, in
  place, without a single allocation per sigma point: :func:`predict_into` carries all 31
  sigma points through every IMU sample of a control tick in one call and appends the
  mean history to a ring buffer; :func:`update_pose_into` fuses one late pose. A property
  test checks both against the references to 1e-9.

Vectors: x = [p_W (3), v_W (3), q_WB (4, scalar-first), b_g (3), b_a (3)]; error state
e = [dp, dv, dtheta_B, db_g, db_a] (15); q_true = q_hat * exp(dtheta).

Packed arguments of the kernels:

- ``imu`` (m, 7): rows [t, f_B (3), omega_B (3)], the first ``n`` used;
- ``clock`` (10,): [t, f_B (3) and omega_B (3) of the last sample, mean f_B of the last
  prediction (3)], updated by :func:`predict_into`;
- ``par`` (12,): [gamma, accel_noise, gyro_noise, gyro_bias_walk, accel_bias_walk, floor,
  R_diag (6)] (see :func:`pack_params`);
- ``hist`` (H, 8): ring buffer of the mean history rows [t, p_W (3), q_WB (4)] and
  ``ring`` = [head, count] (int64): the oldest row is ``hist[head]``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland import GRAVITY
from tetherland.rotations import quat_conjugate, quat_multiply, quat_to_rotmat

N_ERR = 15
N_SIG = 2 * N_ERR + 1
GRAVITY_Z = -GRAVITY
HIST_WIDTH = 8
"""Columns of a history row: t, p_W (3), q_WB (4)."""
TIME_TOL = 1e-9
"""Slack when matching a measurement time to the history [s]."""
REJECTED = -1.0
"""What :func:`update_pose_into` returns for a measurement older than the history."""
_SMALL_ANGLE = 1e-8
SERIES_ANGLE = 0.05
"""Rotation angle below which the compiled exp map uses its Taylor series [rad]."""


# ------------------------------------------------------------------ the filter's workspace
# One float array holds the whole state of a :class:`~tetherland.estimation.ukf.Ukf` (its
# arrays are views of it), so that a compiled step takes one argument, not ten (each
# array argument costs a compiled call about 650 instructions of unboxing). In order:
WS_X = slice(0, 16)
"""State x [p_W, v_W, q_WB, b_g, b_a]."""
WS_P = slice(16, 16 + N_ERR * N_ERR)
"""Error covariance P (15, 15), row-major."""
WS_CLOCK = slice(WS_P.stop, WS_P.stop + 10)
"""``clock`` (see the module docstring)."""
WS_WM = slice(WS_CLOCK.stop, WS_CLOCK.stop + N_SIG)
"""Mean weights (31)."""
WS_WC = slice(WS_WM.stop, WS_WM.stop + N_SIG)
"""Covariance weights (31)."""
WS_PAR = slice(WS_WC.stop, WS_WC.stop + 12)
"""``par`` (:func:`pack_params`)."""
WS_RING = slice(WS_PAR.stop, WS_PAR.stop + 2)
"""``ring`` [head, count], two int64 stored in the bits of two floats."""
WS_HIST = WS_RING.stop
"""Start of ``hist`` (H, :data:`HIST_WIDTH`), row-major, to the end of the workspace."""


def workspace_size(history_rows: int) -> int:
    """Length of the workspace of a filter with ``history_rows`` history rows."""
    return WS_HIST + history_rows * HIST_WIDTH


_X0, _X1, _P0, _P1 = WS_X.start, WS_X.stop, WS_P.start, WS_P.stop
_C0, _C1 = WS_CLOCK.start, WS_CLOCK.stop
_WM0, _WM1, _WC0, _WC1 = WS_WM.start, WS_WM.stop, WS_WC.start, WS_WC.stop
_PAR0, _PAR1, _R0, _R1 = WS_PAR.start, WS_PAR.stop, WS_RING.start, WS_RING.stop


@njit(cache=True)
def workspace_views(ws: np.ndarray):
    """(x, P, clock, wm, wc, par, hist, ring): the views of the kernels' arguments into
    the workspace ``ws`` (the layout ``WS_*``); Python takes the same views with numpy."""
    return (
        ws[_X0:_X1], ws[_P0:_P1].reshape((N_ERR, N_ERR)), ws[_C0:_C1], ws[_WM0:_WM1],
        ws[_WC0:_WC1], ws[_PAR0:_PAR1], ws[WS_HIST:].reshape((-1, HIST_WIDTH)),
        ws[_R0:_R1].view(np.int64),
    )  # fmt: skip


def pack_params(gamma: float, noise: np.ndarray, R_diag: np.ndarray) -> np.ndarray:
    """``par`` of the kernels from gamma, the 5 process-noise values and the 6 R entries."""
    return np.concatenate(([gamma], noise, R_diag)).astype(float)


# ================================================================== plain references


def qexp_reference(phi: np.ndarray) -> np.ndarray:
    """exp(phi): quaternion of the rotation vector phi (series below 1e-8 rad)."""
    angle = float(np.linalg.norm(phi))
    s = 0.5 - angle * angle / 48.0 if angle < _SMALL_ANGLE else math.sin(0.5 * angle) / angle
    return np.concatenate(([math.cos(0.5 * angle)], s * np.asarray(phi, dtype=float)))


def qlog_reference(q: np.ndarray) -> np.ndarray:
    """log(q): rotation vector (shortest rotation) of a unit quaternion."""
    q = -q if q[0] < 0.0 else q
    s = float(np.linalg.norm(q[1:]))
    scale = 2.0 / max(q[0], 1e-12) if s < _SMALL_ANGLE else 2.0 * math.atan2(s, q[0]) / s
    return scale * q[1:]


def sqrt_factor_reference(P: np.ndarray) -> np.ndarray:
    """S with S S^T = P: Cholesky, or the eigen-decomposition if P is not numerically PD."""
    Ps = 0.5 * (P + P.T)
    try:
        return np.linalg.cholesky(Ps)
    except np.linalg.LinAlgError:
        w, V = np.linalg.eigh(Ps)
        return V * np.sqrt(np.maximum(w, 1e-15))


def sigma_points_reference(
    x: np.ndarray, P: np.ndarray, gamma: float
) -> tuple[np.ndarray, np.ndarray]:
    """Error offsets D (31, 15) = [0, +gamma S, -gamma S] (columns of S) and the states
    X (31, 16) = x [+] D: vector parts added, attitude q * exp(dtheta)."""
    S = gamma * sqrt_factor_reference(P)
    D = np.vstack((np.zeros(N_ERR), S.T, -S.T))
    X = np.empty((N_SIG, 16))
    X[:, 0:6] = x[0:6] + D[:, 0:6]
    X[:, 6:10] = [quat_multiply(x[6:10], qexp_reference(d)) for d in D[:, 6:9]]
    X[:, 10:16] = x[10:16] + D[:, 9:15]
    return D, X


def process_noise_reference(dt: float, noise: np.ndarray) -> np.ndarray:
    """Diagonal of the discrete process noise Q_d over one IMU interval ``dt``.

    ``noise`` = [accel_noise, gyro_noise, gyro_bias_walk, accel_bias_walk, floor]; every
    entry is at least floor^2: velocity (sigma_a dt)^2, position a quarter of that times
    dt^2, attitude (sigma_g dt)^2, biases sigma_b^2 dt.
    """
    var_v, var_th = (noise[0] * dt) ** 2, (noise[1] * dt) ** 2
    per_axis = np.array(
        [0.25 * var_v * dt * dt, var_v, var_th, noise[2] ** 2 * dt, noise[3] ** 2 * dt]
    )
    return np.repeat(np.maximum(per_axis, noise[4] ** 2), 3)


def propagate_reference(X: np.ndarray, dt: float, f_B: np.ndarray, omega_B: np.ndarray) -> None:
    """One IMU sample through every sigma state (in place), the process model of
    :mod:`tetherland.estimation.ukf`: a_W = R_WB (f_B - b_a) + g_W, p += v dt + a dt^2/2,
    v += a dt, q = q * exp((omega_B - b_g) dt)."""
    for s in range(X.shape[0]):
        q = X[s, 6:10]
        a_W = quat_to_rotmat(q) @ (f_B - X[s, 13:16]) + np.array([0.0, 0.0, GRAVITY_Z])
        X[s, 0:3] += X[s, 3:6] * dt + 0.5 * dt * dt * a_W
        X[s, 3:6] += a_W * dt
        X[s, 6:10] = quat_multiply(q, qexp_reference((omega_B - X[s, 10:13]) * dt))


def unscented_mean_reference(
    X: np.ndarray, wm: np.ndarray, wc: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Mean state and error covariance of the sigma states X (31, 16).

    Linear parts by the weights wm; the attitude as the weighted mean of the rotation
    vectors log(q_0^-1 q_s) around the centre point, mapped back with exp.
    """
    q_ref = X[0, 6:10]
    dth = np.array([qlog_reference(quat_multiply(quat_conjugate(q_ref), q)) for q in X[:, 6:10]])
    lin = np.hstack((X[:, 0:6], X[:, 10:16]))
    lin_mean, dth_mean = wm @ lin, wm @ dth
    dev = np.hstack((lin[:, 0:6] - lin_mean[0:6], dth - dth_mean, lin[:, 6:12] - lin_mean[6:12]))
    P = (dev.T * wc) @ dev
    q = quat_multiply(q_ref, qexp_reference(dth_mean))
    x = np.concatenate((lin_mean[0:6], q / np.linalg.norm(q), lin_mean[6:12]))
    return x, P


def predict_reference(
    x: np.ndarray,
    P: np.ndarray,
    t_prev: float,
    imu: np.ndarray,
    wm: np.ndarray,
    wc: np.ndarray,
    par: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Unscented prediction through the IMU rows ``imu`` (k, 7) = [t, f_B, omega_B].

    Every sigma point goes through every sample; mean and covariance are formed once and
    the process noise of every sample is added. Returns the new x, P, the history rows
    (k, 8) [t, p_W, q_WB] (the centre point after each sample but the last, the new mean
    after the last) and the ``clock`` after the samples.
    """
    _, X = sigma_points_reference(x, P, par[0])
    Qd = np.zeros(N_ERR)
    hist = np.empty((imu.shape[0], HIST_WIDTH))
    t_last = t_prev
    for j, row in enumerate(imu):
        dt = row[0] - t_last
        t_last = row[0]
        Qd += process_noise_reference(dt, par[1:6])
        propagate_reference(X, dt, row[1:4], row[4:7])
        hist[j] = np.concatenate(([row[0]], X[0, 0:3], X[0, 6:10]))
    x_new, P_new = unscented_mean_reference(X, wm, wc)
    P_new += np.diag(Qd)
    hist[-1, 1:4], hist[-1, 4:8] = x_new[0:3], x_new[6:10]
    clock = np.concatenate((imu[-1], imu[:, 1:4].mean(axis=0)))
    return x_new, 0.5 * (P_new + P_new.T), hist, clock


def update_pose_reference(
    x: np.ndarray,
    P: np.ndarray,
    p_then: np.ndarray,
    q_then: np.ndarray,
    p_meas: np.ndarray,
    q_meas: np.ndarray,
    wm: np.ndarray,
    wc: np.ndarray,
    par: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, float]:
    """Unscented update with a pose measured when the estimate was (p_then, q_then).

    z = [p_W, dtheta] of the sigma points; the innovation is formed against the estimate
    at the measurement time, [p_meas - p_then - (z_p - p_now), log(q_then^-1 q_meas) -
    z_theta], and applied to the current state (delayed fusion, Larsen et al. 1998):
    K = P_xz S^-1, x [+]= K nu, P -= K S K^T. Returns x, P and the NIS nu^T S^-1 nu.
    """
    D, X = sigma_points_reference(x, P, par[0])
    Z = np.hstack((X[:, 0:3], D[:, 6:9]))
    z_mean, d_mean = wm @ Z, wm @ D
    dZ, dD = Z - z_mean, D - d_mean
    S = (dZ.T * wc) @ dZ + np.diag(par[6:12])
    Pxz = (dD.T * wc) @ dZ
    innov = np.concatenate(
        (
            p_meas - p_then - (z_mean[0:3] - x[0:3]),
            qlog_reference(quat_multiply(quat_conjugate(q_then), q_meas)) - z_mean[3:6],
        )
    )
    K = np.linalg.solve(S, Pxz.T).T
    dx = K @ innov
    q = quat_multiply(x[6:10], qexp_reference(dx[6:9]))
    x_new = np.concatenate((x[0:6] + dx[0:6], q / np.linalg.norm(q), x[10:16] + dx[9:15]))
    P_new = P - K @ S @ K.T
    return x_new, 0.5 * (P_new + P_new.T), float(innov @ np.linalg.solve(S, innov))


# ================================================================== compiled kernels
# Scalar quaternion helpers return tuples (no allocation); LLVM inlines them.


@njit(cache=True)
def _qmul(
    aw: float, ax: float, ay: float, az: float, bw: float, bx: float, by: float, bz: float
):  # fmt: skip
    return (
        aw * bw - ax * bx - ay * by - az * bz,
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
    )


@njit(cache=True)
def _qexp(x: float, y: float, z: float):
    # exp of a rotation vector. Below SERIES_ANGLE the Taylor series of cos(a/2) and
    # sin(a/2)/a are exact to double precision (first dropped terms < 1e-18) and much
    # cheaper than sin/cos: IMU increments and most sigma offsets are that small.
    a2 = x * x + y * y + z * z
    if a2 < SERIES_ANGLE * SERIES_ANGLE:
        s = 0.5 - a2 * (1.0 / 48.0 - a2 * (1.0 / 3840.0 - a2 / 645120.0))
        c = 1.0 - a2 * (1.0 / 8.0 - a2 * (1.0 / 384.0 - a2 * (1.0 / 46080.0 - a2 / 10321920.0)))
    else:
        angle = math.sqrt(a2)
        s = math.sin(0.5 * angle) / angle
        c = math.cos(0.5 * angle)
    return c, s * x, s * y, s * z


@njit(cache=True)
def _qlog(w: float, x: float, y: float, z: float):
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    s = math.sqrt(x * x + y * y + z * z)
    scale = 2.0 / max(w, 1e-12) if s < _SMALL_ANGLE else 2.0 * math.atan2(s, w) / s
    return scale * x, scale * y, scale * z


@njit(cache=True)
def _sqrt_factor_into(P: np.ndarray, S: np.ndarray) -> None:
    """S S^T = (P + P^T)/2: Cholesky (lower), else the clamped eigen-decomposition."""
    n = P.shape[0]
    for j in range(n):
        d = P[j, j]
        for k in range(j):
            d -= S[j, k] * S[j, k]
        if not d > 0.0:  # not positive definite (or NaN): LAPACK's potrf fails here too
            Ps = np.empty((n, n))
            for a in range(n):
                for b in range(n):
                    Ps[a, b] = 0.5 * (P[a, b] + P[b, a])
            w, V = np.linalg.eigh(Ps)
            for c in range(n):
                r = math.sqrt(max(w[c], 1e-15))
                for i in range(n):
                    S[i, c] = V[i, c] * r
            return
        d = math.sqrt(d)
        S[j, j] = d
        for i in range(j + 1, n):
            a = 0.5 * (P[i, j] + P[j, i])
            for k in range(j):
                a -= S[i, k] * S[j, k]
            S[i, j] = a / d
        for i in range(j):
            S[i, j] = 0.0


@njit(cache=True)
def _sigma_offsets_into(P: np.ndarray, gamma: float, D: np.ndarray) -> None:
    """D (31, 15) = [0, +gamma S, -gamma S] (rows: columns of S)."""
    S = np.empty((N_ERR, N_ERR))
    _sqrt_factor_into(P, S)
    for i in range(N_ERR):
        D[0, i] = 0.0
    for j in range(N_ERR):
        for i in range(N_ERR):
            v = gamma * S[i, j]
            D[1 + j, i] = v
            D[1 + N_ERR + j, i] = -v


@njit(cache=True)
def _weighted_outer_into(A: np.ndarray, B: np.ndarray, w: np.ndarray, out: np.ndarray) -> None:
    """out = sum_s w_s A[s]^T B[s] = (A.T * w) @ B (rows s summed in order; the inner loop
    runs along contiguous rows, so it vectorises)."""
    na, nb = A.shape[1], B.shape[1]
    for a in range(na):
        for b in range(nb):
            out[a, b] = 0.0
    for s in range(A.shape[0]):
        ws = w[s]
        for a in range(na):
            c = ws * A[s, a]
            for b in range(nb):
                out[a, b] += c * B[s, b]


@njit(cache=True)
def _ring_push(hist: np.ndarray, ring: np.ndarray, t: float, px: float, py: float, pz: float,
               qw: float, qx: float, qy: float, qz: float) -> None:  # fmt: skip
    cap = hist.shape[0]
    head, count = ring[0], ring[1]
    if count < cap:
        i = (head + count) % cap
        ring[1] = count + 1
    else:  # full: overwrite the oldest
        i = head
        ring[0] = (head + 1) % cap
    hist[i, 0] = t
    hist[i, 1], hist[i, 2], hist[i, 3] = px, py, pz
    hist[i, 4], hist[i, 5], hist[i, 6], hist[i, 7] = qw, qx, qy, qz


@njit(cache=True)
def predict_into(
    x: np.ndarray,
    P: np.ndarray,
    clock: np.ndarray,
    imu: np.ndarray,
    n: int,
    wm: np.ndarray,
    wc: np.ndarray,
    par: np.ndarray,
    hist: np.ndarray,
    ring: np.ndarray,
) -> None:
    """Compiled :func:`predict_reference` over ``imu[:n]`` from ``clock[0]``: x, P and
    ``clock`` updated in place and the history rows pushed to the ring (``hist``, ``ring``)."""
    D = np.empty((N_SIG, N_ERR))
    _sigma_offsets_into(P, par[0], D)
    X = np.empty((N_SIG, 16))
    qw0, qx0, qy0, qz0 = x[6], x[7], x[8], x[9]
    for s in range(N_SIG):
        for i in range(6):
            X[s, i] = x[i] + D[s, i]
            X[s, 10 + i] = x[10 + i] + D[s, 9 + i]
        ew, ex, ey, ez = _qexp(D[s, 6], D[s, 7], D[s, 8])
        X[s, 6], X[s, 7], X[s, 8], X[s, 9] = _qmul(qw0, qx0, qy0, qz0, ew, ex, ey, ez)
    Qd = np.zeros(N_ERR)
    fl = par[5] * par[5]
    t_last = clock[0]
    f_sum = np.zeros(3)
    for j in range(n):
        t = imu[j, 0]
        dt = t - t_last
        t_last = t
        var_v = (par[1] * dt) ** 2
        var_th = (par[2] * dt) ** 2
        q_p = max(0.25 * var_v * dt * dt, fl)
        q_v = max(var_v, fl)
        q_th = max(var_th, fl)
        q_bg = max(par[3] * par[3] * dt, fl)
        q_ba = max(par[4] * par[4] * dt, fl)
        for i in range(3):
            Qd[i] += q_p
            Qd[3 + i] += q_v
            Qd[6 + i] += q_th
            Qd[9 + i] += q_bg
            Qd[12 + i] += q_ba
        fx, fy, fz = imu[j, 1], imu[j, 2], imu[j, 3]
        ox, oy, oz = imu[j, 4], imu[j, 5], imu[j, 6]
        f_sum[0] += fx
        f_sum[1] += fy
        f_sum[2] += fz
        h = 0.5 * dt * dt
        for s in range(N_SIG):
            w, qx, qy, qz = X[s, 6], X[s, 7], X[s, 8], X[s, 9]
            bx, by, bz = fx - X[s, 13], fy - X[s, 14], fz - X[s, 15]
            # a_W = R(q) (f_B - b_a) + g_W (quaternion rotation, as ukf_kernels.rotate)
            tx = 2.0 * (qy * bz - qz * by)
            ty = 2.0 * (qz * bx - qx * bz)
            tz = 2.0 * (qx * by - qy * bx)
            ax = bx + w * tx + (qy * tz - qz * ty)
            ay = by + w * ty + (qz * tx - qx * tz)
            az = bz + w * tz + (qx * ty - qy * tx) + GRAVITY_Z
            X[s, 0] += X[s, 3] * dt + h * ax
            X[s, 1] += X[s, 4] * dt + h * ay
            X[s, 2] += X[s, 5] * dt + h * az
            X[s, 3] += ax * dt
            X[s, 4] += ay * dt
            X[s, 5] += az * dt
            ew, ex, ey, ez = _qexp(
                (ox - X[s, 10]) * dt, (oy - X[s, 11]) * dt, (oz - X[s, 12]) * dt
            )
            X[s, 6], X[s, 7], X[s, 8], X[s, 9] = _qmul(w, qx, qy, qz, ew, ex, ey, ez)
        if j < n - 1:
            _ring_push(hist, ring, t, X[0, 0], X[0, 1], X[0, 2], X[0, 6], X[0, 7], X[0, 8],
                       X[0, 9])  # fmt: skip
    # mean: linear parts by weights, attitude on the manifold around the centre point
    rw, rx, ry, rz = X[0, 6], X[0, 7], X[0, 8], X[0, 9]
    dev = np.empty((N_SIG, N_ERR))
    mean = np.zeros(N_ERR)
    for s in range(N_SIG):
        cw, cx, cy, cz = _qmul(rw, -rx, -ry, -rz, X[s, 6], X[s, 7], X[s, 8], X[s, 9])
        dev[s, 6], dev[s, 7], dev[s, 8] = _qlog(cw, cx, cy, cz)
        for i in range(6):
            dev[s, i] = X[s, i]
            dev[s, 9 + i] = X[s, 10 + i]
        ws = wm[s]
        for i in range(N_ERR):
            mean[i] += ws * dev[s, i]
    for s in range(N_SIG):
        for i in range(N_ERR):
            dev[s, i] -= mean[i]
    _weighted_outer_into(dev, dev, wc, P)
    for a in range(N_ERR):
        for b in range(a + 1, N_ERR):
            v = 0.5 * (P[a, b] + P[b, a])
            P[a, b] = v
            P[b, a] = v
        P[a, a] += Qd[a]
    ew, ex, ey, ez = _qexp(mean[6], mean[7], mean[8])
    qw, qx, qy, qz = _qmul(rw, rx, ry, rz, ew, ex, ey, ez)
    nq = math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    for i in range(6):
        x[i] = mean[i]
        x[10 + i] = mean[9 + i]
    x[6], x[7], x[8], x[9] = qw / nq, qx / nq, qy / nq, qz / nq
    _ring_push(hist, ring, t_last, x[0], x[1], x[2], x[6], x[7], x[8], x[9])
    for i in range(7):
        clock[i] = imu[n - 1, i]
    for i in range(3):
        clock[7 + i] = f_sum[i] / n


@njit(cache=True)
def history_index(hist: np.ndarray, ring: np.ndarray, t_meas: float) -> int:
    """Row of the newest history entry at or before ``t_meas`` (-1: older than the history)."""
    cap = hist.shape[0]
    head, count = ring[0], ring[1]
    if count == 0 or t_meas < hist[head, 0] - TIME_TOL:
        return -1
    k = count - 1
    while k > 0 and hist[(head + k) % cap, 0] > t_meas + TIME_TOL:
        k -= 1
    return (head + k) % cap


@njit(cache=True)
def update_pose_into(
    x: np.ndarray,
    P: np.ndarray,
    t_meas: float,
    p_meas: np.ndarray,
    q_meas: np.ndarray,
    wm: np.ndarray,
    wc: np.ndarray,
    par: np.ndarray,
    hist: np.ndarray,
    ring: np.ndarray,
) -> float:
    """Compiled :func:`update_pose_reference` (x, P in place) with the estimate at
    ``t_meas`` taken from the history; returns the NIS, or :data:`REJECTED` (nothing
    fused) when ``t_meas`` is older than the history."""
    k = history_index(hist, ring, t_meas)
    if k < 0:
        return REJECTED
    D = np.empty((N_SIG, N_ERR))
    _sigma_offsets_into(P, par[0], D)
    # z = [p_W (sigma), dtheta]; means of z and of the offsets D
    z_mean = np.zeros(6)
    d_mean = np.zeros(N_ERR)
    for s in range(N_SIG):
        ws = wm[s]
        for i in range(3):
            z_mean[i] += ws * (x[i] + D[s, i])
            z_mean[3 + i] += ws * D[s, 6 + i]
        for i in range(N_ERR):
            d_mean[i] += ws * D[s, i]
    dZ = np.empty((N_SIG, 6))
    dD = np.empty((N_SIG, N_ERR))
    for s in range(N_SIG):
        for i in range(3):
            dZ[s, i] = x[i] + D[s, i] - z_mean[i]
            dZ[s, 3 + i] = D[s, 6 + i] - z_mean[3 + i]
        for i in range(N_ERR):
            dD[s, i] = D[s, i] - d_mean[i]
    S = np.empty((6, 6))
    _weighted_outer_into(dZ, dZ, wc, S)
    for a in range(6):
        for b in range(a + 1, 6):
            v = 0.5 * (S[a, b] + S[b, a])
            S[a, b] = v
            S[b, a] = v
        S[a, a] += par[6 + a]
    Pxz = np.empty((N_ERR, 6))
    _weighted_outer_into(dD, dZ, wc, Pxz)
    innov = np.empty(6)
    for i in range(3):
        innov[i] = p_meas[i] - hist[k, 1 + i] - (z_mean[i] - x[i])
    cw, cx, cy, cz = _qmul(hist[k, 4], -hist[k, 5], -hist[k, 6], -hist[k, 7],
                           q_meas[0], q_meas[1], q_meas[2], q_meas[3])  # fmt: skip
    lx, ly, lz = _qlog(cw, cx, cy, cz)
    innov[3], innov[4], innov[5] = lx - z_mean[3], ly - z_mean[4], lz - z_mean[5]
    # K = Pxz S^-1 by the Cholesky factor of the SPD innovation covariance S
    Ls = np.empty((6, 6))
    _sqrt_factor_into(S, Ls)
    Kt = np.empty((6, N_ERR))  # solve S K^T = Pxz^T, column by column
    sol = np.empty(6)  # and S y = nu for the NIS
    for i in range(6):
        sol[i] = innov[i]
        for a in range(N_ERR):
            Kt[i, a] = Pxz[a, i]
    _chol_solve_columns(Ls, Kt)
    _chol_solve_vector(Ls, sol)
    nis = 0.0
    for i in range(6):
        nis += innov[i] * sol[i]
    dx = np.zeros(N_ERR)
    for a in range(N_ERR):
        for i in range(6):
            dx[a] += Kt[i, a] * innov[i]
    for i in range(6):
        x[i] += dx[i]
        x[10 + i] += dx[9 + i]
    ew, ex, ey, ez = _qexp(dx[6], dx[7], dx[8])
    qw, qx, qy, qz = _qmul(x[6], x[7], x[8], x[9], ew, ex, ey, ez)
    nq = math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    x[6], x[7], x[8], x[9] = qw / nq, qx / nq, qy / nq, qz / nq
    # P -= K S K^T (symmetric: K S = Pxz up to rounding; computed as written)
    KS = np.zeros((N_ERR, 6))
    for a in range(N_ERR):
        for b in range(6):
            acc = 0.0
            for i in range(6):
                acc += Kt[i, a] * S[i, b]
            KS[a, b] = acc
    for a in range(N_ERR):
        for b in range(a, N_ERR):
            acc = 0.0
            for i in range(6):
                acc += KS[a, i] * Kt[i, b]
            v = 0.5 * ((P[a, b] - acc) + (P[b, a] - acc))
            P[a, b] = v
            P[b, a] = v
    return nis


@njit(cache=True)
def predict_ws(ws: np.ndarray, imu: np.ndarray, n: int) -> None:
    """:func:`predict_into` on the filter's workspace ``ws`` (``WS_*``)."""
    x, P, clock, wm, wc, par, hist, ring = workspace_views(ws)
    predict_into(x, P, clock, imu, n, wm, wc, par, hist, ring)


@njit(cache=True)
def update_pose_ws(ws: np.ndarray, t_meas: float, p_meas: np.ndarray,
                   q_meas: np.ndarray) -> float:  # fmt: skip
    """:func:`update_pose_into` on the filter's workspace ``ws`` (``WS_*``)."""
    x, P, _, wm, wc, par, hist, ring = workspace_views(ws)
    return update_pose_into(x, P, t_meas, p_meas, q_meas, wm, wc, par, hist, ring)


@njit(cache=True)
def _chol_solve_vector(L: np.ndarray, b: np.ndarray) -> None:
    """b <- (L L^T)^-1 b (forward then back substitution)."""
    n = L.shape[0]
    for i in range(n):
        acc = b[i]
        for k in range(i):
            acc -= L[i, k] * b[k]
        b[i] = acc / L[i, i]
    for i in range(n - 1, -1, -1):
        acc = b[i]
        for k in range(i + 1, n):
            acc -= L[k, i] * b[k]
        b[i] = acc / L[i, i]


@njit(cache=True)
def _chol_solve_columns(L: np.ndarray, B: np.ndarray) -> None:
    """B <- (L L^T)^-1 B, column by column."""
    n, m = B.shape
    col = np.empty(n)
    for c in range(m):
        for i in range(n):
            col[i] = B[i, c]
        _chol_solve_vector(L, col)
        for i in range(n):
            B[i, c] = col[i]


# ------------------------------------------------------------------ small helpers (not hot)


@njit(cache=True)
def qmul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a * b of scalar-first quaternions."""
    return np.array(_qmul(a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]))


@njit(cache=True)
def qexp(x: float, y: float, z: float) -> np.ndarray:
    """Quaternion of the rotation vector (x, y, z) (exact, smooth through zero)."""
    return np.array(_qexp(x, y, z))


@njit(cache=True)
def qlog(q: np.ndarray) -> np.ndarray:
    """Rotation vector (shortest rotation) of a unit quaternion."""
    return np.array(_qlog(q[0], q[1], q[2], q[3]))


@njit(cache=True)
def qconj(q: np.ndarray) -> np.ndarray:
    return np.array([q[0], -q[1], -q[2], -q[3]])
