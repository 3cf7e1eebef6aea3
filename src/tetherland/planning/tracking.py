"""A planned trajectory as a stream of controller references, precomputed on a time grid.

Sampling a :class:`~tetherland.planning.trajectory.Trajectory` and its flatness map costs
about 1 ms per call, too much at 500 Hz; :class:`TrajectoryTrack` evaluates everything once,
vectorised, on the control grid, so that :meth:`TrajectoryTrack.reference` is an index lookup
(the feed-forward records of the grid points are built once, on first use).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tetherland.geometry import FloatArray
from tetherland.interfaces import ControlMode, Feedforward, Reference
from tetherland.planning.trajectory import Trajectory


@dataclass(frozen=True)
class TrackSamples:
    """Precomputed references on a uniform grid t0 + k dt, k = 0..n-1."""

    t0: float
    dt: float
    outputs: FloatArray  # (n, 5, 4): rows y, y', ..., y'''' of [phi, delta, theta_A, psi]
    omega_B: FloatArray  # (n, 3)
    omega_dot_B: FloatArray  # (n, 3)
    f_R: FloatArray  # (n, 3): f_R, f_R', f_R''
    tension: FloatArray  # (n,)
    rotor_thrusts: FloatArray  # (n, 4)
    rotor_rates: FloatArray  # (n, 4): planned rotor thrust rates [N/s]


class TrajectoryTrack:
    """References of a tethered trajectory started at time ``t0`` (held after its end).

    Parameters
    ----------
    trajectory : Trajectory
        A planned landing or takeoff.
    t0 : float
        Mission time at which the trajectory starts [s].
    rate_hz : float
        Control rate: the grid spacing is 1/rate_hz [s].
    phase : int
        Phase code written into every reference.
    """

    def __init__(self, trajectory: Trajectory, t0: float, rate_hz: float, phase: int = 0):
        self.trajectory = trajectory
        self.t0 = float(t0)
        self.phase = phase
        dt = 1.0 / rate_hz
        n = int(np.ceil(trajectory.duration / dt)) + 2
        times = np.arange(n) * dt
        s = trajectory.sample(times)
        nominal = trajectory.flatness.evaluate_many(s.outputs())
        outputs = np.zeros((n, 5, 4))
        outputs[:, :, 0] = s.phi
        outputs[:, :3, 2] = s.theta_A[:, :3]  # theta_A: value and 2 derivatives (r = 2)
        outputs[:, 0, 3] = s.psi
        self.samples = TrackSamples(
            t0=self.t0,
            dt=dt,
            outputs=outputs,
            # C-contiguous rows: the compiled controllers take them as they are
            omega_B=np.ascontiguousarray(nominal["omega_B"], dtype=float),
            omega_dot_B=np.ascontiguousarray(nominal["omega_dot_B"], dtype=float),
            f_R=np.column_stack((nominal["f_R"], nominal["f_R_dot"], nominal["f_R_ddot"])),
            tension=nominal["tension"],
            rotor_thrusts=s.thrusts,
            rotor_rates=s.thrust_rates,
        )
        self._t_end = self.t0 + trajectory.duration
        self._last = n - 1
        self._ff: list[Feedforward | None] = [None] * n
        self._held: dict[int, tuple[FloatArray, Feedforward]] = {}

    @property
    def duration(self) -> float:
        return self.trajectory.duration

    @property
    def t_end(self) -> float:
        """Mission time at which the trajectory ends [s]."""
        return self.t0 + self.trajectory.duration

    def index(self, t: float) -> int:
        """Grid index of time ``t`` (clamped to the grid)."""
        k = round((t - self.t0) / self.samples.dt)
        return min(max(k, 0), self._last)

    def reference(self, t: float, mode: ControlMode = ControlMode.TETHERED) -> Reference:
        """The reference at mission time ``t`` (end values held after the end)."""
        k = round((t - self.t0) / self.samples.dt)
        k = min(max(k, 0), self._last)
        if t > self._t_end:
            out, ff = self._held.get(k) or self._hold(k)
        else:
            out = self.samples.outputs[k]
            ff = self._ff[k] or self._feedforward(k)
        return Reference(
            t=t, mode=mode, phase=self.phase, output=out, thrust_ff=ff.f_R, feedforward=ff
        )

    def _feedforward(self, k: int) -> Feedforward:
        s = self.samples
        f_R, f_R_dot, f_R_ddot = s.f_R[k].tolist()
        ff = Feedforward(
            omega_B=s.omega_B[k], omega_dot_B=s.omega_dot_B[k], f_R=f_R, f_R_dot=f_R_dot,
            f_R_ddot=f_R_ddot, tension=float(s.tension[k]),
        )  # fmt: skip
        self._ff[k] = ff
        return ff

    def _hold(self, k: int) -> tuple[FloatArray, Feedforward]:
        """Output and feed-forward held after the end: the values at k, no derivatives."""
        s = self.samples
        out = s.outputs[k].copy()
        out[1:] = 0.0
        ff = Feedforward(
            omega_B=np.zeros(3), omega_dot_B=np.zeros(3), f_R=float(s.f_R[k, 0]),
            tension=float(s.tension[k]),
        )  # fmt: skip
        self._held[k] = (out, ff)
        return out, ff
