"""Motion under inputs held on intervals: node states, inputs and a dense RK4 table.

Both planned trajectory kinds are an OCP solution of this form: node times t_0 < ... < t_N,
node states X (N+1, nx) and inputs U (N, nu), u = U[k] on [t_k, t_{k+1}). Between the
nodes the model x' = f(x, u) is integrated in ``sub`` equal RK4 substeps per interval
(:func:`tetherland.models.integrators.rk4`), at most :data:`DENSE_STEP` long; the state
after every substep is kept in a table, and a sample at time t is one more RK4 step from
the table entry just before t. Every sample is therefore the model's own motion.

:class:`HeldInputSimulator` runs the substeps with a compiled CasADi step function
(``mapaccum`` chains, cached per length), either *through* all intervals from an initial
state (the planners' independent re-simulation: continuous node states) or *restarted*
at every node (a solution read back from a file).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Literal

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from tetherland.geometry import FloatArray
from tetherland.models.integrators import rk4

DENSE_STEP = 2e-3
"""Largest RK4 substep between the nodes [s]."""

NumpyRhs = Callable[[FloatArray, FloatArray], FloatArray]
"""f(x (nx, n), u (nu, n)) -> x' (nx, n), the model's numpy right-hand side."""


def substeps(interval: float, dense_step: float = DENSE_STEP) -> int:
    """Substeps of at most ``dense_step`` for the longest interval [s] (at least 1)."""
    return max(1, math.ceil(interval / dense_step - 1e-9))


class HeldInputSimulator:
    """Fixed-step RK4 through intervals with the input held, compiled once per length.

    Parameters
    ----------
    step : casadi.Function
        ``step(x[nx], u[nu], h, c[nc]) -> x(t + h)``: one RK4 step for model constants c.

    Keep one simulator for repeated use: the chains it compiles are cached in it.
    """

    def __init__(self, step: ca.Function) -> None:
        self.step = step
        self.nx = int(step.size1_in(0))
        self._chains: dict[tuple[str, int, int], ca.Function] = {}

    def _chain(self, kind: Literal["through", "restart"], n: int, m: int) -> ca.Function:
        key = (kind, n, m)
        if key not in self._chains:
            chain = self.step.mapaccum(n)
            self._chains[key] = chain.map(m) if kind == "restart" else chain
        return self._chains[key]

    def run(
        self, c: FloatArray, times: FloatArray, x0: FloatArray, U: FloatArray, sub: int
    ) -> FloatArray:
        """States after every substep, (N, sub, nx), integrating through all intervals."""
        N = len(times) - 1
        h = np.repeat(np.diff(times) / sub, sub)[None, :]
        ends = self._chain("through", N * sub, 1)(x0, np.repeat(U.T, sub, axis=1), h, c)
        return np.asarray(ends).T.reshape(N, sub, self.nx)

    def advance(
        self, c: FloatArray, rhs: NumpyRhs, x: FloatArray, u: FloatArray, h: FloatArray
    ) -> FloatArray:
        """One RK4 step of length h (n,) [s] from each state x (nx, n) under u (nu, n), with
        the model's numpy right-hand side ``rhs`` (a subclass may run its own kernel)."""
        return rk4(rhs, x, u, h)

    def restart(
        self, c: FloatArray, times: FloatArray, X: FloatArray, U: FloatArray, sub: int
    ) -> FloatArray:
        """States after every substep, (N, sub, nx), each interval started at its node X[k]."""
        N = len(times) - 1
        h = np.repeat(np.diff(times) / sub, sub)[None, :]
        ends = self._chain("restart", sub, N)(X[:-1].T, np.repeat(U.T, sub, axis=1), h, c)
        return np.asarray(ends).T.reshape(N, sub, self.nx)


class HeldInputMotion:
    """Node times, states and held inputs with their dense RK4 table (built on first use).

    Parameters
    ----------
    simulator : HeldInputSimulator
    coefficients : (nc,) array
        Model constants c of the simulator's step function.
    rhs : callable
        The same model in numpy, f(x (nx, n), u (nu, n)), for the last partial step.
    times : (N+1,) array
        Increasing node times [s]; shifted to start at 0.
    X : (N+1, nx) array
    U : (N, nu) array
    sub : int, optional
        Substeps per interval (default: :func:`substeps` of the longest interval).
    """

    def __init__(
        self,
        simulator: HeldInputSimulator,
        coefficients: ArrayLike,
        rhs: NumpyRhs,
        times: ArrayLike,
        X: ArrayLike,
        U: ArrayLike,
        sub: int | None = None,
        _table: FloatArray | None = None,
    ) -> None:
        times = np.asarray(times, dtype=float)
        self.times = times - times[0]
        self.X = np.asarray(X, dtype=float)
        self.U = np.asarray(U, dtype=float)
        N = len(self.times) - 1
        nx = simulator.nx
        if N < 1 or self.X.shape != (N + 1, nx) or self.U.ndim != 2 or len(self.U) != N:
            raise ValueError(
                f"need X (N+1, {nx}) and U (N, nu) for {N + 1} times, "
                f"got {self.X.shape}, {self.U.shape}"
            )
        if np.any(np.diff(self.times) <= 0):
            raise ValueError("node times must increase")
        self.simulator = simulator
        self.coefficients = np.asarray(coefficients, dtype=float)
        self.rhs = rhs
        self.sub = sub or substeps(float(np.max(np.diff(self.times))))
        self._table = _table

    @classmethod
    def simulate(
        cls,
        simulator: HeldInputSimulator,
        coefficients: ArrayLike,
        rhs: NumpyRhs,
        times: ArrayLike,
        x0: ArrayLike,
        U: ArrayLike,
    ) -> HeldInputMotion:
        """Integrate from ``x0`` through all intervals (substeps of at most
        :data:`DENSE_STEP`); the node states are the continuous motion's."""
        times = np.asarray(times, dtype=float)
        U = np.asarray(U, dtype=float)
        x0 = np.asarray(x0, dtype=float)
        c = np.asarray(coefficients, dtype=float)
        sub = substeps(float(np.max(np.diff(times))))
        ends = simulator.run(c, times, x0, U, sub)
        X = np.vstack((x0[None, :], ends[:, -1, :]))
        table = np.concatenate((X[:-1, None, :], ends[:, :-1, :]), axis=1)
        return cls(simulator, c, rhs, times, X, U, sub, _table=table)

    @property
    def duration(self) -> float:
        return float(self.times[-1])

    @property
    def table(self) -> FloatArray:
        """(N, sub, nx): the state at the start of every substep of every interval."""
        if self._table is None:
            ends = self.simulator.restart(self.coefficients, self.times, self.X, self.U, self.sub)
            self._table = np.concatenate((self.X[:-1, None, :], ends[:, :-1, :]), axis=1)
        return self._table

    def states(self, t: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """States (nx, n) and held inputs (nu, n) at times ``t`` (clipped to [0, T])."""
        t = np.clip(np.atleast_1d(np.asarray(t, dtype=float)), 0.0, self.duration)
        N = len(self.times) - 1
        k = np.clip(np.searchsorted(self.times, t, side="right") - 1, 0, N - 1)
        h_sub = (self.times[k + 1] - self.times[k]) / self.sub
        j = np.clip(np.floor((t - self.times[k]) / h_sub).astype(int), 0, self.sub - 1)
        u = self.U[k].T
        x = self.table[k, j].T
        dt = t - (self.times[k] + j * h_sub)
        inside = dt > 0.0  # samples on a substep are table entries: no partial step
        if np.any(inside):
            x = x.copy()
            x[:, inside] = self.simulator.advance(
                self.coefficients, self.rhs, x[:, inside], u[:, inside], dt[inside]
            )
        return x, u
