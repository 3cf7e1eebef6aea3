"""Free-flight reference paths: chains of rest-to-rest straight segments.

Each segment moves from p0 to p1 along a straight line with the 9th-order smoothstep of
:func:`tetherland.planning.spline.smoothstep9` (zero velocity, acceleration, jerk and snap
at both ends), so every chain is C^4 and starts and ends at rest.

A path may carry a :class:`ZVShaper` (a load swinging under the vehicle with a known
period, the bar mechanism's hook): every move is then the smoothstep convolved with the
shaper's impulses, still straight from p0 to p1 and rest to rest, longer by half the
period, and leaves an undamped pendulum of that period without residual swing.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from tetherland.geometry import FloatArray
from tetherland.planning.spline import smoothstep9, smoothstep9_scalar

_tau = np.linspace(0.0, 1.0, 2001)
_ds = smoothstep9(_tau, 2)
PEAK_SPEED_FACTOR = float(np.max(np.abs(_ds[1])))
"""max s'(tau): the peak speed of a segment is this times distance/duration."""
PEAK_ACCEL_FACTOR = float(np.max(np.abs(_ds[2])))
"""max s''(tau): the peak acceleration is this times distance/duration^2."""


_GAUSS_TAU, _GAUSS_W = np.polynomial.legendre.leggauss(64)
_GAUSS_TAU, _GAUSS_W = 0.5 * (_GAUSS_TAU + 1.0), 0.5 * _GAUSS_W  # on [0, 1]


def smoothstep_residual(cycles: float) -> float:
    """Residual swing of an undamped pendulum at rest under the pivot, after a
    rest-to-rest smoothstep move of the pivot lasting ``cycles`` of its periods, over the
    move's length (along it) [-]: the magnitude of the velocity profile's spectrum,
    |int_0^1 s'(tau) exp(-i 2 pi cycles tau) dtau|. (The hook's swing relative to the
    pivot, x'' + w^2 x = -a(t), keeps |int a(t) exp(-i w t) dt| / w, and for
    a = D s''(t/T)/T^2 that is D times the above; 1 for a step, 11 % at 2 cycles, first
    zero at 2.60 cycles.) By 64-point Gauss-Legendre quadrature."""
    om = 2.0 * math.pi * cycles
    ds = smoothstep9(_GAUSS_TAU, 1)[1]
    return abs(complex(np.sum(_GAUSS_W * ds * np.exp(-1j * om * _GAUSS_TAU))))


def segment_duration(distance: float, speed: float, accel: float, minimum: float = 0.5) -> float:
    """Shortest duration [s] of a segment of ``distance`` [m] within peak speed and accel."""
    return max(
        minimum,
        PEAK_SPEED_FACTOR * distance / speed,
        math.sqrt(PEAK_ACCEL_FACTOR * distance / accel),
    )


@dataclass(frozen=True)
class ZVShaper:
    """Zero-vibration input shaper of an undamped pendulum of period ``period`` [s].

    Two impulses of 1/2 at 0 and period/2: a move convolved with them excites the
    pendulum twice, half a period apart, and the two swings cancel. If the true period
    is P_true, the residual swing is :meth:`residual_ratio` times the unshaped move's.
    """

    period: float

    @property
    def times(self) -> tuple[float, float]:
        """Impulse times [s]."""
        return (0.0, 0.5 * self.period)

    amplitudes: tuple[float, float] = (0.5, 0.5)
    """Impulse amplitudes [-] (sum 1: the move still ends at p1)."""

    @property
    def span(self) -> float:
        """How much longer a shaped move lasts [s]."""
        return 0.5 * self.period

    def residual_ratio(self, true_period: float) -> float:
        """Residual swing of a shaped move over the unshaped move's, for an undamped
        pendulum of period ``true_period`` [s]: |1/2 + 1/2 exp(-i w T/2)| =
        |cos(pi period / (2 true_period))| [-] (0 at the design period)."""
        return abs(math.cos(0.5 * math.pi * self.period / true_period))


@dataclass(frozen=True)
class Segment:
    """A straight rest-to-rest move from ``p0`` to ``p1``, from ``t0`` for ``duration``;
    ``base`` is the unshaped move's duration (``duration`` less the shaper's span) [s]."""

    t0: float
    duration: float
    p0: FloatArray
    p1: FloatArray
    base: float = 0.0

    @property
    def t_end(self) -> float:
        return self.t0 + self.duration


class Path:
    """A chain of segments, each starting where and when the previous one ends.

    Parameters
    ----------
    t0 : float
        Start time [s].
    start : (3,) array
        Start position [m].
    speed, accel : float
        Peak speed [m/s] and acceleration [m/s^2] used to size the segments.
    min_duration : float
        Shortest move [s] (a hanging hook's legs last a few of its swing periods).
    shaper : ZVShaper, optional
        Shape every move (not the pauses) for a load swinging with the shaper's period.
    """

    def __init__(self, t0: float, start: ArrayLike, speed: float, accel: float,
                 min_duration: float = 0.5, shaper: ZVShaper | None = None):  # fmt: skip
        self.t0 = float(t0)
        self.shaper = shaper
        self.min_duration = float(min_duration)
        self.start = np.asarray(start, dtype=float).copy()
        self.speed = speed
        self.accel = accel
        self.segments: list[Segment] = []
        # per segment, for sample(): p1 - p0, and the held rows of a pause (read-only)
        self._delta: list[FloatArray] = []
        self._rest: list[FloatArray | None] = []
        # the shaper's impulses as arrays (the compiled path_rows)
        self._shaper_times = np.array(shaper.times if shaper is not None else (), dtype=float)
        self._shaper_amplitudes = np.array(
            shaper.amplitudes if shaper is not None else (), dtype=float
        )
        self._cursor = 0
        self._start_rows = _rest_rows(self.start)
        self._t_end = self.t0

    @property
    def end(self) -> FloatArray:
        return self.segments[-1].p1 if self.segments else self.start

    @property
    def t_end(self) -> float:
        """End of the last segment [s] (kept as segments are added or delayed: the
        supervisor reads it at every tick)."""
        return self._t_end

    def to(self, p: ArrayLike, speed: float | None = None, pause: float = 0.0) -> Path:
        """Append a move to ``p`` (optionally slower), then an optional pause; returns self."""
        p = np.asarray(p, dtype=float)
        d = float(np.linalg.norm(p - self.end))
        T = segment_duration(d, speed or self.speed, self.accel, self.min_duration)
        span = self.shaper.span if self.shaper is not None and d > 0.0 else 0.0
        self._append(Segment(self.t_end, T + span, self.end.copy(), p.copy(), base=T))
        if pause > 0.0:
            self._append(Segment(self.t_end, pause, p.copy(), p.copy()))
        return self

    def delay(self, dt: float) -> None:
        """Hold the path for ``dt`` [s]: every segment starts that much later."""
        self.t0 += dt
        self.segments = [replace(seg, t0=seg.t0 + dt) for seg in self.segments]
        self._t_end = self.segments[-1].t_end if self.segments else self.t0

    def _append(self, seg: Segment) -> None:
        self.segments.append(seg)
        self._t_end = seg.t_end
        delta = seg.p1 - seg.p0
        self._delta.append(delta)
        self._rest.append(_rest_rows(seg.p1) if not delta.any() else None)

    def sample(self, t: float) -> FloatArray:
        """Rows (p, v, a) at time ``t`` [m, m/s, m/s^2]; held at the ends.

        Called every control tick with increasing ``t``: the segment search resumes where
        the last call found its segment; a pause returns its (read-only) held rows.
        """
        segs = self.segments
        if not segs or t <= self.t0:
            return self._start_rows
        i = self._cursor if t >= segs[self._cursor].t0 else 0
        last = len(segs) - 1
        while i < last and t >= segs[i].t_end:
            i += 1
        self._cursor = i
        rest = self._rest[i]
        if rest is not None:
            return rest
        seg = segs[i]
        if t >= seg.t_end:  # past the end of the path: held at its end
            return _rest_rows(seg.p1)
        T = seg.base if seg.base > 0.0 else seg.duration
        shaped = self.shaper is not None and seg.duration != T
        rows = _empty((3, 3))  # path_rows, inlined
        path_rows_into(t, seg.t0, T, self._shaper_times if shaped else _UNSHAPED,
                       self._shaper_amplitudes if shaped else _UNSHAPED, seg.p0,
                       self._delta[i], rows)  # fmt: skip
        return rows


_UNSHAPED = np.empty(0)
"""No shaper impulses: :func:`path_rows` takes the plain smoothstep."""


def path_rows_reference(
    t: float, t0: float, T: float, times: FloatArray, amplitudes: FloatArray,
    p0: FloatArray, delta: FloatArray,
) -> FloatArray:  # fmt: skip
    """Rows (p, v, a) at ``t`` [s] of a move from ``p0`` by ``delta`` [m] started at
    ``t0`` [s], the smoothstep of duration ``T`` [s] convolved with the impulses
    (``times`` [s], ``amplitudes`` [-]) of a shaper, none (empty arrays): the plain
    smoothstep. Plain Python floats, the reference of :func:`path_rows`."""
    if times.shape[0] == 0:
        s0, s1, s2 = smoothstep9_scalar((t - t0) / T, 2)
    else:  # the smoothstep convolved with the shaper's impulses
        s0 = s1 = s2 = 0.0
        for ti, ai in zip(times.tolist(), amplitudes.tolist(), strict=True):
            r0, r1, r2 = smoothstep9_scalar((t - t0 - ti) / T, 2)
            s0, s1, s2 = s0 + ai * r0, s1 + ai * r1, s2 + ai * r2
    x0, y0, z0 = p0.tolist()
    dx, dy, dz = delta.tolist()
    a, b = s1 / T, s2 / (T * T)
    # element-wise as p0 + s0 delta, a delta, b delta with numpy: the same bits
    return np.array([[x0 + s0 * dx, y0 + s0 * dy, z0 + s0 * dz],
                     [a * dx, a * dy, a * dz], [b * dx, b * dy, b * dz]])  # fmt: skip


@njit(cache=True)
def _smoothstep2(tau: float) -> tuple[float, float, float]:  # pragma: no cover (compiled)
    """:func:`~tetherland.planning.spline.smoothstep9_scalar` to order 2, compiled with
    the same operations (``u ** 5.0``: the C library's pow, as Python's)."""
    if tau <= 0.0 or tau >= 1.0:
        return (0.0 if tau <= 0.0 else 1.0), 0.0, 0.0
    u = tau
    v = 1.0 - u
    w = 1.0 - 2.0 * u
    uv = u * v
    u2v2 = uv * uv
    s = u**5.0 * (126.0 + u * (-420.0 + u * (540.0 + u * (-315.0 + 70.0 * u))))
    return s, 630.0 * u2v2 * u2v2, 2520.0 * u2v2 * uv * w


def path_rows(
    t: float, t0: float, T: float, times: FloatArray, amplitudes: FloatArray,
    p0: FloatArray, delta: FloatArray,
) -> FloatArray:  # fmt: skip
    """:func:`path_rows_reference` compiled (:func:`path_rows_into`, the same operations in
    the same order: the same bits; a test checks it): called at every control tick of
    free flight. Float64 vectors (contiguous, writable) only."""
    rows = _empty((3, 3))
    path_rows_into(t, t0, T, times, amplitudes, p0, delta, rows)
    return rows


_empty = np.empty


@njit(
    "void(float64, float64, float64, float64[::1], float64[::1], float64[::1], float64[::1], "
    "float64[:, ::1])",
    cache=True,
)
def path_rows_into(
    t: float, t0: float, T: float, times: FloatArray, amplitudes: FloatArray,
    p0: FloatArray, delta: FloatArray, rows: FloatArray,
) -> None:  # fmt: skip  # pragma: no cover (compiled)
    """:func:`path_rows` written into ``rows`` (3, 3)."""
    if (
        p0.shape[0] != 3 or delta.shape[0] != 3 or rows.shape[0] != 3 or rows.shape[1] != 3
        or amplitudes.shape[0] != times.shape[0]
    ):  # fmt: skip
        raise ValueError("p0 (3,), delta (3,), rows (3, 3), one amplitude per impulse time")
    if times.shape[0] == 0:
        s0, s1, s2 = _smoothstep2((t - t0) / T)
    else:
        s0 = s1 = s2 = 0.0
        for k in range(times.shape[0]):
            ai = amplitudes[k]
            r0, r1, r2 = _smoothstep2((t - t0 - times[k]) / T)
            s0, s1, s2 = s0 + ai * r0, s1 + ai * r1, s2 + ai * r2
    a, b = s1 / T, s2 / (T * T)
    for j in range(3):
        d = delta[j]
        rows[0, j] = p0[j] + s0 * d
        rows[1, j] = a * d
        rows[2, j] = b * d


def _rest_rows(p: FloatArray) -> FloatArray:
    """Rows (p, 0, 0), read-only: shared by every tick that holds ``p``."""
    rows = np.zeros((3, 3))
    rows[0] = p
    rows.setflags(write=False)
    return rows
