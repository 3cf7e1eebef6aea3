"""Free-flight reference paths: chains of rest-to-rest straight segments.

Each segment moves from p0 to p1 along a straight line with the 9th-order smoothstep of
:func:`tetherland.planning.spline.smoothstep9` (zero velocity, acceleration, jerk and snap
at both ends), so every chain is C^4 and starts and ends at rest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import ArrayLike

from tetherland.geometry import FloatArray
from tetherland.planning.spline import smoothstep9, smoothstep9_scalar

_tau = np.linspace(0.0, 1.0, 2001)
_ds = smoothstep9(_tau, 2)
PEAK_SPEED_FACTOR = float(np.max(np.abs(_ds[1])))
"""max s'(tau): the peak speed of a segment is this times distance/duration."""
PEAK_ACCEL_FACTOR = float(np.max(np.abs(_ds[2])))
"""max s''(tau): the peak acceleration is this times distance/duration^2."""


def segment_duration(distance: float, speed: float, accel: float, minimum: float = 0.5) -> float:
    """Shortest duration [s] of a segment of ``distance`` [m] within peak speed and accel."""
    return max(
        minimum,
        PEAK_SPEED_FACTOR * distance / speed,
        math.sqrt(PEAK_ACCEL_FACTOR * distance / accel),
    )


@dataclass(frozen=True)
class Segment:
    """A straight rest-to-rest move from ``p0`` to ``p1``, from ``t0`` for ``duration``."""

    t0: float
    duration: float
    p0: FloatArray
    p1: FloatArray

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
    """

    def __init__(self, t0: float, start: ArrayLike, speed: float, accel: float,
                 min_duration: float = 0.5):  # fmt: skip
        self.t0 = float(t0)
        self.min_duration = float(min_duration)
        self.start = np.asarray(start, dtype=float).copy()
        self.speed = speed
        self.accel = accel
        self.segments: list[Segment] = []
        # per segment, for sample(): p1 - p0, and the held rows of a pause (read-only)
        self._delta: list[FloatArray] = []
        self._rest: list[FloatArray | None] = []
        self._cursor = 0
        self._start_rows = _rest_rows(self.start)

    @property
    def end(self) -> FloatArray:
        return self.segments[-1].p1 if self.segments else self.start

    @property
    def t_end(self) -> float:
        return self.segments[-1].t_end if self.segments else self.t0

    def to(self, p: ArrayLike, speed: float | None = None, pause: float = 0.0) -> Path:
        """Append a move to ``p`` (optionally slower), then an optional pause; returns self."""
        p = np.asarray(p, dtype=float)
        d = float(np.linalg.norm(p - self.end))
        T = segment_duration(d, speed or self.speed, self.accel, self.min_duration)
        self._append(Segment(self.t_end, T, self.end.copy(), p.copy()))
        if pause > 0.0:
            self._append(Segment(self.t_end, pause, p.copy(), p.copy()))
        return self

    def delay(self, dt: float) -> None:
        """Hold the path for ``dt`` [s]: every segment starts that much later."""
        self.t0 += dt
        self.segments = [replace(seg, t0=seg.t0 + dt) for seg in self.segments]

    def _append(self, seg: Segment) -> None:
        self.segments.append(seg)
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
        T = seg.duration
        s0, s1, s2 = smoothstep9_scalar((t - seg.t0) / T, 2)
        delta = self._delta[i]
        rows = np.empty((3, 3))
        rows[0] = seg.p0 + s0 * delta
        rows[1] = (s1 / T) * delta
        rows[2] = (s2 / (T * T)) * delta
        return rows


def _rest_rows(p: FloatArray) -> FloatArray:
    """Rows (p, 0, 0), read-only: shared by every tick that holds ``p``."""
    rows = np.zeros((3, 3))
    rows[0] = p
    rows.setflags(write=False)
    return rows
