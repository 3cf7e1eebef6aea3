"""Unscented Kalman filter on IMU (process input) and motion capture (docs/theory.md section 8).

State: position p_W, velocity v_W, attitude q_WB (unit quaternion, kept outside the
filter vector), gyro bias b_g and accelerometer bias b_a. The filter works on the
15-dimensional error state

    e = [dp (3), dv (3), dtheta (3), db_g (3), db_a (3)],  q_true = q_hat * exp(dtheta)

(the attitude error is a rotation vector in F_B, so attitude never leaves SO(3)).

Process (one IMU sample of specific force f_B and rate omega_B over dt):
    a_W = R_WB (f_B - b_a) + g_W,   p += v dt + a dt^2/2,   v += a dt,
    q = q * exp((omega_B - b_g) dt),  biases random walks.
The accelerometer measures thrust, cable and contact forces, not gravity, so it is never
used as a tilt sensor; it only drives the velocity through the process model.

Motion capture (position and attitude) arrives late (latency). :meth:`Ukf.update_pose`
forms the innovation against the estimate stored at the measurement time and applies it
to the current state and covariance (Larsen et al. 1998, "Incorporation of time delayed
measurements in a discrete-time Kalman filter"; exact for a constant error over the
delay, which a few milliseconds of latency make negligible). This costs one update
instead of re-propagating every IMU sample since the measurement.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland import GRAVITY
from tetherland.config import SensorsConfig
from tetherland.estimation import ukf_kernels as kernels
from tetherland.geometry import FloatArray

N_ERR = 15
_G_W = np.array([0.0, 0.0, -GRAVITY])
_NOISE_FLOOR = 1e-9


@dataclass(frozen=True)
class UkfNoise:
    """Noise intensities the filter assumes.

    Attributes
    ----------
    gyro_noise : float
        Gyro white noise per sample [rad/s].
    accel_noise : float
        Accelerometer white noise per sample [m/s^2].
    gyro_bias_walk, accel_bias_walk : float
        Bias random-walk intensities [rad/s/sqrt(s)], [m/s^2/sqrt(s)].
    position_noise : float
        Motion-capture position noise per axis [m].
    attitude_noise : float
        Motion-capture attitude noise per axis [rad].
    """

    gyro_noise: float
    accel_noise: float
    gyro_bias_walk: float
    accel_bias_walk: float
    position_noise: float
    attitude_noise: float

    @classmethod
    def from_config(cls, sensors: SensorsConfig, inflation: float = 1.0) -> UkfNoise:
        """Noise from the scenario's sensor settings (times ``inflation`` >= 1 for robustness).

        A small floor keeps the filter well conditioned when ``noise_scale = 0``.
        """
        k = sensors.noise_scale * inflation
        imu, mocap = sensors.imu, sensors.mocap
        return cls(
            gyro_noise=max(k * imu.gyro_noise, 1e-5),
            accel_noise=max(k * imu.accel_noise, 1e-4),
            gyro_bias_walk=max(k * imu.gyro_bias_walk, 1e-7),
            accel_bias_walk=max(k * imu.accel_bias_walk, 1e-6),
            position_noise=max(k * mocap.position_noise, 1e-5),
            attitude_noise=max(k * math.radians(mocap.attitude_noise_deg), 1e-5),
        )


@dataclass(frozen=True, slots=True)
class NavState:
    """Navigation state estimate (F_W unless named otherwise).

    Attributes
    ----------
    p_W, v_W : (3,) arrays
        Position [m] and velocity [m/s] of the centre of mass.
    q_WB : (4,) array
        Attitude quaternion (w, x, y, z).
    b_g, b_a : (3,) arrays
        Gyro [rad/s] and accelerometer [m/s^2] biases, F_B.
    """

    p_W: FloatArray
    v_W: FloatArray
    q_WB: FloatArray
    b_g: FloatArray
    b_a: FloatArray


class Ukf:
    """Error-state unscented Kalman filter for IMU + motion capture.

    Parameters
    ----------
    noise : UkfNoise
    x0 : NavState
        Initial estimate.
    P0 : (15, 15) array
        Initial error covariance.
    t0 : float
        Time of the initial estimate [s].
    history : float
        How far back delayed measurements are accepted [s].
    imu_rate_hz : float
        Nominal IMU rate, sizes the history buffer [Hz].
    alpha, beta, kappa : float
        Scaled unscented transform parameters. The defaults (1, 2, 0) spread the sigma
        points by sqrt(15) standard deviations with non-negative mean weights.
    """

    def __init__(
        self,
        noise: UkfNoise,
        x0: NavState,
        P0: ArrayLike,
        t0: float = 0.0,
        *,
        history: float = 0.1,
        imu_rate_hz: float = 1000.0,
        alpha: float = 1.0,
        beta: float = 2.0,
        kappa: float = 0.0,
    ) -> None:
        self.noise = noise
        n = N_ERR
        lam = alpha * alpha * (n + kappa) - n
        self._gamma = math.sqrt(n + lam)
        wm = np.full(2 * n + 1, 0.5 / (n + lam))
        wc = wm.copy()
        wm[0] = lam / (n + lam)
        wc[0] = lam / (n + lam) + (1.0 - alpha * alpha + beta)
        R_diag = np.array([noise.position_noise**2] * 3 + [noise.attitude_noise**2] * 3)
        process = np.array(
            [noise.accel_noise, noise.gyro_noise, noise.gyro_bias_walk, noise.accel_bias_walk,
             _NOISE_FLOOR]
        )  # fmt: skip
        P0 = np.array(P0, dtype=float)
        if P0.shape != (n, n):
            raise ValueError(f"P0 must be {n}x{n}, got {P0.shape}")
        # the whole state in one array (kernels.WS_*), the arrays below views of it
        rows = max(2, int(history * imu_rate_hz) + 2)
        self._ws = ws = np.zeros(kernels.workspace_size(rows))
        self._x, self._P = ws[kernels.WS_X], ws[kernels.WS_P].reshape(n, n)
        self._imu, self._wm, self._wc = ws[kernels.WS_CLOCK], ws[kernels.WS_WM], ws[kernels.WS_WC]
        self._par = ws[kernels.WS_PAR]
        # mean-only history for delayed measurements: ring of rows [t, p_W, q_WB]
        self._hist = ws[kernels.WS_HIST :].reshape(rows, kernels.HIST_WIDTH)
        self._ring = ws[kernels.WS_RING].view(np.int64)  # [head, count]
        self._wm[...], self._wc[...] = wm, wc
        self._par[...] = kernels.pack_params(self._gamma, process, R_diag)
        q0 = np.asarray(x0.q_WB, dtype=float)
        self._x[...] = np.concatenate((x0.p_W, x0.v_W, q0 / np.linalg.norm(q0), x0.b_g, x0.b_a))
        self._P[...] = P0
        # [t, f_B and omega_B of the last IMU sample, mean f_B of the last prediction]
        self._imu[...] = np.concatenate(([float(t0)], -_G_W, np.zeros(3), -_G_W))
        self._hist[0, 0] = t0
        self._hist[0, 1:4], self._hist[0, 4:8] = self._x[0:3], self._x[6:10]
        self._ring[1] = 1
        self.rejected_late = 0
        """Motion-capture samples older than the history (not fused)."""
        self._load_kernels()

    def _load_kernels(self) -> None:
        """Load the compiled prediction and update now (numba's cache, once per process)
        rather than inside the first control ticks: calls on scratch copies."""
        ws = self._ws.copy()
        t = float(ws[kernels.WS_CLOCK][0])
        row = np.zeros((1, 7))
        row[0, 0], row[0, 3] = t + 1e-3, 9.81
        kernels.predict_ws(ws, row, 1)
        x = ws[kernels.WS_X]
        kernels.update_pose_ws(ws, t + 1e-3, x[0:3].copy(), x[6:10].copy())

    # ---------------------------------------------------------------- accessors
    @property
    def t(self) -> float:
        """Time of the current estimate [s]."""
        return float(self._imu[0])

    @property
    def covariance(self) -> FloatArray:
        """Error covariance (15x15) in the order [p, v, theta_B, b_g, b_a] (a copy)."""
        return self._P.copy()

    @property
    def covariance_view(self) -> FloatArray:
        """The live error covariance (15x15) (updated in place by every step: read, never
        keep or write)."""
        return self._P

    @property
    def x(self) -> FloatArray:
        """The state vector [p_W, v_W, q_WB, b_g, b_a] (16,) (a copy)."""
        return self._x.copy()

    @property
    def workspace(self) -> FloatArray:
        """The live workspace: the filter's whole state in one array, laid out as
        ``ukf_kernels.WS_*`` (updated in place by every step: read, never keep or write;
        the compiled steps of :class:`~tetherland.estimation.UkfEstimator` take it)."""
        return self._ws

    @property
    def x_view(self) -> FloatArray:
        """The live state vector (updated in place by every step: read, never keep or write)."""
        return self._x

    @property
    def imu_view(self) -> FloatArray:
        """The live IMU record [t, f_B (3) and omega_B (3) of the last sample, mean f_B over
        the samples of the last prediction (3)] (measured, not bias-corrected) [s, m/s^2,
        rad/s]; updated in place by every prediction: read, never keep or write."""
        return self._imu

    @property
    def mean_specific_force_B(self) -> FloatArray:
        """Mean measured specific force over the samples of the last prediction [m/s^2]."""
        return self._imu[7:10].copy()

    @property
    def state(self) -> NavState:
        x = self._x
        return NavState(
            x[0:3].copy(), x[3:6].copy(), x[6:10].copy(), x[10:13].copy(), x[13:16].copy()
        )

    @property
    def omega_B(self) -> FloatArray:
        """Bias-corrected angular rate of the last IMU sample [rad/s]."""
        return self._imu[4:7] - self._x[10:13]

    @property
    def specific_force_B(self) -> FloatArray:
        """Bias-corrected specific force of the last IMU sample [m/s^2]."""
        return self._imu[1:4] - self._x[13:16]

    # ---------------------------------------------------------------- public steps
    def predict(self, t: float, f_B: ArrayLike, omega_B: ArrayLike) -> None:
        """Integrate one IMU sample (specific force [m/s^2], rate [rad/s], both F_B) up to ``t``.

        All 31 sigma points are propagated through the sample (unscented transform).
        """
        if not t > self.t:
            raise ValueError(f"IMU times must increase beyond t = {self.t}: got {t}")
        row = np.empty((1, 7))
        row[0, 0] = t
        row[0, 1:4] = f_B
        row[0, 4:7] = omega_B
        self.predict_rows(row, 1)

    def predict_many(self, ts: ArrayLike, f_B: ArrayLike, omega_B: ArrayLike) -> None:
        """Integrate several IMU samples in one unscented transform.

        Every sigma point is carried through every sample (rows of ``f_B``, ``omega_B``,
        times ``ts``), then mean and covariance are formed once; the process noise of each
        sample is added. Identical to :meth:`predict` for one sample.
        """
        ts = np.asarray(ts, dtype=float).reshape(-1)
        if ts[0] <= self.t or (ts.shape[0] > 1 and not np.all(ts[1:] > ts[:-1])):
            raise ValueError(f"IMU times must increase beyond t = {self.t}: got {ts}")
        imu = np.column_stack((ts, np.asarray(f_B, dtype=float), np.asarray(omega_B, float)))
        self.predict_rows(imu, ts.shape[0])

    def predict_rows(self, imu: FloatArray, n: int) -> None:
        """:meth:`predict_many` on packed rows ``imu[:n]`` = [t, f_B (3), omega_B (3)].

        The caller guarantees C-contiguous float rows with times increasing beyond
        :attr:`t` (:class:`~tetherland.estimation.UkfEstimator` does the same inside its
        compiled estimate, :func:`~tetherland.estimation.kernels.flush`).
        """
        kernels.predict_ws(self._ws, imu, n)

    def update_pose(self, t_meas: float, p_W: ArrayLike, q_WB: ArrayLike) -> float:
        """Fuse a motion-capture pose measured at ``t_meas`` (possibly in the past).

        The innovation is formed against the estimate stored at ``t_meas`` and applied now.

        Returns
        -------
        float
            The normalised innovation squared (chi-square with 6 dof when consistent);
            NaN if the measurement was older than the history and was not fused.
        """
        nis = kernels.update_pose_ws(
            self._ws, float(t_meas),
            np.ascontiguousarray(p_W, dtype=float), np.ascontiguousarray(q_WB, dtype=float),
        )  # fmt: skip
        if nis == kernels.REJECTED:
            self.rejected_late += 1
            return math.nan
        return nis

    def error(self, truth: NavState) -> FloatArray:
        """Error-state vector truth - estimate, in the filter's chart (for NEES)."""
        x = self._x
        dth = kernels.qlog(kernels.qmul(kernels.qconj(x[6:10]), np.asarray(truth.q_WB, float)))
        return np.concatenate(
            (
                truth.p_W - x[0:3],
                truth.v_W - x[3:6],
                dth,
                truth.b_g - x[10:13],
                truth.b_a - x[13:16],
            )
        )

    def nees(self, truth: NavState) -> float:
        """Normalised estimation error squared, chi-square with 15 dof when consistent."""
        e = self.error(truth)
        return float(e @ np.linalg.solve(self._P, e))


def initial_covariance(
    position: float = 0.01,
    velocity: float = 0.05,
    attitude: float = math.radians(2.0),
    gyro_bias: float = 0.01,
    accel_bias: float = 0.1,
) -> FloatArray:
    """Diagonal initial covariance from standard deviations [m, m/s, rad, rad/s, m/s^2]."""
    return np.diag(
        [position**2] * 3
        + [velocity**2] * 3
        + [attitude**2] * 3
        + [gyro_bias**2] * 3
        + [accel_bias**2] * 3
    )
