"""Sensor models: strapdown IMU and motion capture (docs/theory.md sections 8, 9; chapter 6.6.4).

IMU (1 kHz): specific force f_B = R_BW (a - g) (what an accelerometer measures: thrust,
cable and contact forces over the mass, never gravity) and angular rate omega_B, from
MuJoCo's accelerometer and gyro at the centre of mass, plus

    y_k = x_k + b_k + sigma n_k,    b_{k+1} = b_k + sigma_b sqrt(dt) xi_k,

with n_k, xi_k standard normal, b_0 ~ N(0, sigma_b0^2) per axis. Motion capture (120 Hz):
position + N(0, sigma_p^2) per axis, attitude q (x) exp(N(0, sigma_theta^2) per axis) (a
body-frame rotation-vector perturbation), delivered ``latency`` later, and invalid during
Poisson dropouts (rate lambda per second, each lasting ``dropout_duration``).

Every intensity is multiplied by ``scenario.sensors.noise_scale``. Randomness comes only
from the :class:`numpy.random.Generator` passed in; each sensor spawns independent child
streams, so that e.g. enabling dropouts leaves the noise sequence unchanged.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from tetherland.config import ImuConfig, MocapConfig
from tetherland.geometry import FloatArray
from tetherland.interfaces import ImuSample, MocapSample

NOISE_BLOCK = 1024
"""Samples whose noise is drawn at once (IMU and mocap each)."""
_NAN3 = np.full(3, np.nan)
_NAN3.setflags(write=False)
_NAN4 = np.full(4, np.nan)
_NAN4.setflags(write=False)


@njit(cache=True)
def _row_into(t: float, truth: FloatArray, noise: FloatArray, i: int, out: FloatArray) -> None:
    """out[:7] = [t, truth + noise[i]] (the IMU row; compiled: the runner's rate)."""
    out[0] = t
    for j in range(6):
        out[1 + j] = truth[j] + noise[i, j]


class Imu:
    """Noisy IMU with bias random walks.

    Parameters
    ----------
    config : ImuConfig
        Rates and intensities.
    rng : numpy.random.Generator
        Source of all randomness of this sensor.
    noise_scale : float
        Multiplier of every intensity (``sensors.noise_scale``) [-].
    """

    def __init__(
        self, config: ImuConfig, rng: np.random.Generator, noise_scale: float = 1.0
    ) -> None:
        self.config = config
        self.period = 1.0 / config.rate_hz
        s = float(noise_scale)
        self._white = np.array([config.accel_noise] * 3 + [config.gyro_noise] * 3) * s
        self._walk = (
            np.array([config.accel_bias_walk] * 3 + [config.gyro_bias_walk] * 3)
            * s
            * math.sqrt(self.period)
        )
        rng_init, self._rng = rng.spawn(2)
        b0 = np.array([config.accel_bias_initial] * 3 + [config.gyro_bias_initial] * 3) * s
        self._bias_next = b0 * rng_init.standard_normal(6)
        self._noise = np.empty((NOISE_BLOCK, 6))
        self._bias = np.empty((NOISE_BLOCK, 6))
        self._refill()

    def _refill(self) -> None:
        z = self._rng.standard_normal((NOISE_BLOCK, 12))
        # Bias of sample j: b_next + cumulative increments before j.
        increments = z[:, 6:] * self._walk
        np.cumsum(increments, axis=0, out=self._bias)
        self._bias -= increments
        self._bias += self._bias_next
        self._bias_next = self._bias[-1] + increments[-1]
        np.multiply(z[:, :6], self._white, out=self._noise)
        self._noise += self._bias
        self._i = 0

    def sample(self, t: float, truth: FloatArray) -> ImuSample:
        """Measure ``truth`` = [specific_force_B (3), omega_B (3)] taken at time ``t``.

        ``truth`` may be a view (e.g. into MuJoCo's ``sensordata``); it is not kept.
        """
        i = self._i
        if i == NOISE_BLOCK:
            self._refill()
            i = 0
        y = truth + self._noise[i]
        self._i = i + 1
        return ImuSample(t, y[0:3], y[3:6])

    def sample_into(self, t: float, truth: FloatArray, out: FloatArray) -> None:
        """:meth:`sample` written as the row [t, specific_force_B (3), omega_B (3)] into
        ``out[:7]`` (no allocation, no record; the same values)."""
        i = self._i
        if i == NOISE_BLOCK:
            self._refill()
            i = 0
        _row_into(t, truth, self._noise, i, out)
        self._i = i + 1

    @property
    def bias(self) -> FloatArray:
        """True biases [accel (3) m/s^2, gyro (3) rad/s] of the last sample (of the next one
        before any sample) (copy)."""
        return self._bias[max(self._i - 1, 0)].copy()

    def bias_into(self, out: FloatArray) -> None:
        """Write :attr:`bias` into ``out[:6]`` (no allocation)."""
        out[:6] = self._bias[max(self._i - 1, 0)]


class Mocap:
    """Motion capture of the body pose with noise, latency and Poisson dropouts.

    Parameters
    ----------
    config : MocapConfig
    rng : numpy.random.Generator
    noise_scale : float
        Multiplier of the noise intensities (not of latency or dropouts) [-].
    outage : (float, float), optional
        Fault: no pose is delivered for measurement times in [start, end) [s].
    """

    def __init__(
        self,
        config: MocapConfig,
        rng: np.random.Generator,
        noise_scale: float = 1.0,
        outage: tuple[float, float] | None = None,
    ) -> None:
        self.config = config
        self.period = 1.0 / config.rate_hz
        self.latency = config.latency
        self._sigma_p = config.position_noise * noise_scale
        self._sigma_theta = math.radians(config.attitude_noise_deg) * noise_scale
        self._rng, self._rng_drop = rng.spawn(2)
        self._drop_rate = config.dropout_rate
        self._drop_duration = config.dropout_duration
        self._drop_until = -math.inf
        self._outage = (math.inf, math.inf) if outage is None else (float(outage[0]),
                                                                      float(outage[1]))
        self._next_drop = self._draw_gap(0.0)
        self._z: list[list[float]] = []
        self._j = NOISE_BLOCK

    def _draw_gap(self, t: float) -> float:
        if self._drop_rate <= 0.0 or self._drop_duration <= 0.0:
            return math.inf
        return t + float(self._rng_drop.exponential(1.0 / self._drop_rate))

    def in_dropout(self, t: float) -> bool:
        """Advance the dropout process to ``t`` (non-decreasing) and tell if ``t`` is lost."""
        while self._next_drop <= t:
            self._drop_until = max(self._drop_until, self._next_drop + self._drop_duration)
            self._next_drop = self._draw_gap(self._next_drop)
        return t < self._drop_until

    def measure(
        self, t_measured: float, p_W: ArrayLike, q_WB: ArrayLike, t_delivered: float | None = None
    ) -> MocapSample:
        """Measure the true pose (p_W, q_WB) at ``t_measured``.

        Parameters
        ----------
        t_delivered
            Delivery time; default ``t_measured + latency`` (the runner passes the
            physics tick at which it delivers).
        """
        if self._j == NOISE_BLOCK:
            self._z = self._rng.standard_normal((NOISE_BLOCK, 6)).tolist()
            self._j = 0
        z = self._z[self._j]  # drawn even in a dropout: the noise stream stays aligned
        self._j += 1
        if t_delivered is None:
            t_delivered = t_measured + self.latency
        if self.in_dropout(t_measured) or self._outage[0] <= t_measured < self._outage[1]:
            return MocapSample(t_measured, t_delivered, _NAN3.copy(), _NAN4.copy(), False)
        sp, st = self._sigma_p, self._sigma_theta
        px, py, pz = np.asarray(p_W, dtype=float).tolist()
        w, x, y, zq = np.asarray(q_WB, dtype=float).tolist()
        # q (x) exp(dtheta), dtheta = sigma_theta z[3:6] (body-frame perturbation)
        ax, ay, az = st * z[3], st * z[4], st * z[5]
        angle = math.sqrt(ax * ax + ay * ay + az * az)
        if angle > 1e-12:
            c, k = math.cos(0.5 * angle), math.sin(0.5 * angle) / angle
        else:
            c, k = 1.0, 0.5
        bw, bx, by, bz = c, k * ax, k * ay, k * az
        qw = w * bw - x * bx - y * by - zq * bz
        qx = w * bx + x * bw + y * bz - zq * by
        qy = w * by - x * bz + y * bw + zq * bx
        qz = w * bz + x * by - y * bx + zq * bw
        n = math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
        if qw < 0.0:
            n = -n
        return MocapSample(
            t_measured,
            t_delivered,
            np.array([px + sp * z[0], py + sp * z[1], pz + sp * z[2]]),
            np.array([qw / n, qx / n, qy / n, qz / n]),
            True,
        )
