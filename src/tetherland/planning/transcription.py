"""Direct multiple shooting of an :class:`~tetherland.planning.ocp.OcpProblem`.

Decision variables are ordered stage-wise, w = [x_0, u_0, x_1, u_1, ..., x_{N-1}, u_{N-1}, x_N],
and the constraints stage-wise too,

  [gap_0, x_0 - x_init, gap_1, g(x_1, u_1), ..., gap_{N-1}, g(x_{N-1}, u_{N-1}), h(x_N)]

with the gap-closing constraints written gap_k = x_{k+1} - F(x_k, u_k): this is the form
fatrop's structure detection needs (identity block on x_{k+1}); IPOPT does not mind.
F integrates the dynamics over one interval of T/N with ``steps`` fixed steps of the
chosen integrator, the input held constant. The stage cost is integrated by the
rectangle rule, L(x_k, u_k, t_k) T/N, so that it stays separable by stage.

The numbers (parameters, duration, initial state) enter as NLP parameters
P = [p, T, x_init], so one transcription serves every problem of the same structure.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from tetherland.geometry import FloatArray
from tetherland.models import integrators
from tetherland.planning.ocp import OcpProblem

Integrator = integrators.Method


@dataclass(frozen=True)
class MultipleShooting:
    """Multiple-shooting transcription settings.

    Attributes
    ----------
    nodes : int
        Number of shooting intervals N.
    integrator : {"rk4", "euler"}
        Fixed-step integrator inside each interval.
    steps : int
        Integrator steps per interval.
    """

    nodes: int = 50
    integrator: Integrator = "rk4"
    steps: int = 2

    def __post_init__(self) -> None:
        if self.nodes < 2:
            raise ValueError(f"nodes must be >= 2, got {self.nodes}")
        if self.steps < 1:
            raise ValueError(f"steps must be >= 1, got {self.steps}")
        if self.integrator not in integrators.METHODS:
            raise ValueError(f"integrator must be 'rk4' or 'euler', got {self.integrator!r}")

    def transcribe(self, problem: OcpProblem) -> Transcript:
        """Build the NLP of ``problem`` (symbolic; numbers enter via :meth:`Transcript.numbers`)."""
        N, nx, nu = self.nodes, problem.nx, problem.nu
        fn = problem.functions()
        p, T = problem.p, problem.T
        x_init = ca.SX.sym("x_init", nx)
        stage, terminal = self._stage_functions(problem, fn)
        X = [ca.SX.sym(f"x_{k}", nx) for k in range(N + 1)]
        U = [ca.SX.sym(f"u_{k}", nu) for k in range(N)]
        w, g, equality, layout = [], [], [], []
        cost = 0
        dt = T / N
        n_path = problem.path.numel()
        for k in range(N):
            w += [X[k], U[k]]
            x_end, stage_cost, path = stage(X[k], U[k], k * dt, p, T)
            g.append(X[k + 1] - x_end)
            equality += [True] * nx
            layout.append(("gap", nx))
            if k == 0:
                g.append(X[0] - x_init)
                equality += [True] * nx
                layout.append(("init", nx))
            elif n_path:
                g.append(path)
                equality += [False] * n_path
                layout.append(("path", n_path))
            cost += stage_cost
        w.append(X[N])
        terminal_cost, terminal_g = terminal(X[N], p)
        n_term = problem.terminal.numel()
        if n_term:
            g.append(terminal_g)
            equality += [True] * n_term
            layout.append(("terminal", n_term))
        cost += terminal_cost
        nlp = {"x": ca.vertcat(*w), "f": cost, "g": ca.vertcat(*g), "p": ca.vertcat(p, T, x_init)}
        x_s, u_s = ca.SX.sym("xs", nx), ca.SX.sym("us", nu)
        return Transcript(
            method=self,
            structure_key=problem.structure_key,
            nlp=nlp,
            equality=tuple(equality),
            layout=tuple(layout),
            nx=nx,
            nu=nu,
            interval_map=ca.Function("F", [x_s, u_s, p, T], [stage(x_s, u_s, 0, p, T)[0]]),
            stage=stage,
            terminal=terminal,
        )

    def _stage_functions(
        self, problem: OcpProblem, fn: dict[str, ca.Function]
    ) -> tuple[ca.Function, ca.Function]:
        """``stage(x, u, t, p, T) -> (F(x, u), L(x, u, t) T/N, g(x, u, t))`` of one interval
        (its expressions share their common subexpressions: the integrator's first stage
        is the model at the node, as in the cost and the path constraints) and
        ``terminal(x, p) -> (E(x), h(x))``."""
        N, nx, nu = self.nodes, problem.nx, problem.nu
        p, T = problem.p, problem.T
        x, u, t = ca.SX.sym("x", nx), ca.SX.sym("u", nu), ca.SX.sym("t")
        h = T / (N * self.steps)
        x_end = x
        for _ in range(self.steps):
            x_end = integrators.step(self.integrator, lambda z, v: fn["ode"](z, v, p), x_end, u, h)
        dt = T / N
        outputs = ca.cse(
            [x_end, fn["stage_cost"](x, u, t, p, T, dt) * dt, fn["path"](x, u, t, p, T, dt)]
        )
        stage = ca.Function(
            "stage", [x, u, t, p, T], outputs, ["x", "u", "t", "p", "T"], ["x_end", "cost", "path"]
        )
        terminal = ca.Function(
            "terminal", [x, p], ca.cse([fn["terminal_cost"](x, p), fn["terminal"](x, p)]),
            ["x", "p"], ["cost", "h"],
        )  # fmt: skip
        return stage, terminal


@dataclass(frozen=True)
class Transcript:
    """The NLP of a transcribed problem, with the maps between its vectors and trajectories.

    Attributes
    ----------
    method : MultipleShooting
    structure_key : str
        :attr:`OcpProblem.structure_key` of the problems it serves.
    nlp : dict
        CasADi NLP ``{"x", "f", "g", "p"}``.
    equality : tuple of bool
        Per constraint row, whether it is an equality (fatrop's structure detection).
    layout : tuple of (kind, size)
        The constraint blocks in order: ``gap``, ``init``, ``path``, ``terminal``.
    nx, nu : int
    interval_map : casadi.Function
        F(x, u, p, T): the state at the end of one interval.
    stage : casadi.Function
        ``(x, u, t, p, T) -> (x_end, cost, path)``: one interval's end state F(x, u), its
        stage cost L T/N and its path constraints g (the NLP is made of these).
    terminal : casadi.Function
        ``(x, p) -> (cost, h)``: the terminal cost E and constraints h.
    """

    method: MultipleShooting
    structure_key: str
    nlp: dict[str, ca.SX]
    equality: tuple[bool, ...]
    layout: tuple[tuple[str, int], ...]
    nx: int
    nu: int
    interval_map: ca.Function = field(repr=False)
    stage: ca.Function = field(repr=False)
    terminal: ca.Function = field(repr=False)
    _path_index: np.ndarray | None = field(default=None, repr=False, compare=False)

    @property
    def nodes(self) -> int:
        return self.method.nodes

    @property
    def n_w(self) -> int:
        return (self.nodes + 1) * self.nx + self.nodes * self.nu

    def times(self, duration: float) -> FloatArray:
        """Node times t_k = k T / N [s]."""
        return np.linspace(0.0, duration, self.nodes + 1)

    def pack(self, X: ArrayLike, U: ArrayLike) -> FloatArray:
        """w from node states (N+1, nx) and inputs (N, nu)."""
        X = np.asarray(X, dtype=float).reshape(self.nodes + 1, self.nx)
        U = np.asarray(U, dtype=float).reshape(self.nodes, self.nu)
        return np.concatenate((np.hstack((X[:-1], U)).reshape(-1), X[-1]))

    def unpack(self, w: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Node states (N+1, nx) and inputs (N, nu) from w."""
        w = np.asarray(w, dtype=float).reshape(-1)
        stride = self.nx + self.nu
        body = w[: self.nodes * stride].reshape(self.nodes, stride)
        X = np.vstack((body[:, : self.nx], w[self.nodes * stride :][None, :]))
        return X, body[:, self.nx :].copy()

    def numbers(self, problem: OcpProblem) -> dict[str, FloatArray]:
        """``lbx``, ``ubx``, ``lbg``, ``ubg`` and ``p`` for one problem of this structure.

        State bounds apply at the interior nodes 1..N-1 only (the boundary states are
        fixed by the initial and terminal conditions).
        """
        if problem.structure_key != self.structure_key:
            raise ValueError("problem structure differs from the transcribed one")
        N = self.nodes
        lbX, ubX = np.tile(problem.x_lb, (N + 1, 1)), np.tile(problem.x_ub, (N + 1, 1))
        lbX[[0, N]], ubX[[0, N]] = -np.inf, np.inf
        lbx = self.pack(lbX, np.tile(problem.u_lb, (N, 1)))
        ubx = self.pack(ubX, np.tile(problem.u_ub, (N, 1)))
        rows = self.path_index
        path = rows >= 0
        lbg, ubg = np.zeros(len(rows)), np.zeros(len(rows))
        lbg[path], ubg[path] = problem.path_lb[rows[path]], problem.path_ub[rows[path]]
        return {
            "lbx": lbx,
            "ubx": ubx,
            "lbg": lbg,
            "ubg": ubg,
            "p": self.parameters(problem),
        }

    def parameters(self, problem: OcpProblem) -> FloatArray:
        """The NLP parameters P = [p, T, x_init] of one problem of this structure."""
        return np.concatenate((problem.p_value, [problem.duration], problem.x0))

    @property
    def path_index(self) -> np.ndarray:
        """Per constraint row: its index in the path constraints g, or -1 (equalities)."""
        if self._path_index is None:
            blocks = [np.arange(n) if kind == "path" else np.full(n, -1) for kind, n in self.layout]
            object.__setattr__(self, "_path_index", np.concatenate(blocks))
        return self._path_index  # type: ignore[return-value]
