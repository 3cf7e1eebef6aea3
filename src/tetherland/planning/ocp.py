"""A continuous-time optimal control problem, stated apart from its transcription and solver.

The statement (rockit style) is symbolic in CasADi, with every number that may change
from one solve to the next (initial state, parameters, bounds, duration) kept out of the
expressions. Problems of the same *structure* therefore share one transcription and one
compiled solver (see :mod:`tetherland.planning.solvers`):

  minimise    integral_0^T L(x, u, t, p) dt + E(x(T), p)
  subject to  x' = f(x, u, p)                     dynamics
              x(0) = x_0                          initial state
              g_lb <= g(x, u, t, p, h) <= g_ub    path constraints on (0, T)
              x_lb <= x <= x_ub                   state bounds on (0, T)
              u_lb <= u <= u_ub                   input bounds on [0, T)
              h(x(T), p) = 0                      terminal constraints

Path constraints and state bounds hold on the open interval: the boundary states are
fixed by the initial and terminal conditions and are checked by the problem's author.
A path constraint may use the symbol ``h``, the length of the transcription's interval
(T/N for multiple shooting), to bound a quantity between the nodes.
"""

from __future__ import annotations

import copy
import hashlib
from collections.abc import Iterable
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from tetherland.geometry import FloatArray


def _vec(values: ArrayLike, n: int, what: str) -> FloatArray:
    v = np.asarray(values, dtype=float).reshape(-1)
    if v.shape != (n,):
        raise ValueError(f"{what} must have {n} entries, got {v.shape[0]}")
    if np.any(np.isnan(v)):
        raise ValueError(f"{what} contains NaN")
    return v


@dataclass(frozen=True)
class OcpProblem:
    """Symbolic statement and numerical data of an optimal control problem.

    Attributes
    ----------
    x, u, p : casadi.SX
        Column symbols of the state (nx), input (nu) and parameters (np).
    t, T, h : casadi.SX
        Scalar symbols of the time, of the duration and of the transcription's interval.
    ode : casadi.SX
        f(x, u, p): the state derivative (nx).
    stage_cost : casadi.SX
        L(x, u, t, p, T), scalar.
    terminal_cost : casadi.SX
        E(x, p), scalar.
    path : casadi.SX
        g(x, u, t, p, T, h), column (may be empty).
    terminal : casadi.SX
        h(x, p), column, constrained to zero.
    duration : float
        T [s].
    x0 : (nx,) array
        Initial state.
    p_value : (np,) array
        Parameter values.
    path_lb, path_ub : arrays like ``path``
        Bounds of the path constraints (+-inf allowed).
    x_lb, x_ub, u_lb, u_ub : arrays
        Simple bounds (+-inf allowed).
    state_names, input_names : tuple of str
        For messages and tables.
    """

    x: ca.SX
    u: ca.SX
    p: ca.SX
    t: ca.SX
    T: ca.SX
    h: ca.SX
    ode: ca.SX
    stage_cost: ca.SX
    terminal_cost: ca.SX
    path: ca.SX
    terminal: ca.SX
    duration: float
    x0: FloatArray
    p_value: FloatArray
    path_lb: FloatArray
    path_ub: FloatArray
    x_lb: FloatArray
    x_ub: FloatArray
    u_lb: FloatArray
    u_ub: FloatArray
    state_names: tuple[str, ...] = ()
    input_names: tuple[str, ...] = ()
    _key: str = field(init=False, repr=False, compare=False)
    _sizes: dict[str, int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        sizes = {
            "x0": self.x.numel(), "p_value": self.p.numel(), "path_lb": self.path.numel(),
            "path_ub": self.path.numel(), "x_lb": self.x.numel(), "x_ub": self.x.numel(),
            "u_lb": self.u.numel(), "u_ub": self.u.numel(),
        }  # fmt: skip
        object.__setattr__(self, "_sizes", sizes)
        if self.ode.numel() != self.nx:
            raise ValueError(f"ode has {self.ode.numel()} entries for {self.nx} states")
        self._check_numbers(self._NUMBERS)
        f = ca.Function(
            "ocp_structure",
            [self.x, self.u, self.p, self.t, self.T, self.h],
            [self.ode, self.stage_cost, self.terminal_cost, self.path, self.terminal],
        )
        object.__setattr__(self, "_key", hashlib.sha1(f.serialize().encode()).hexdigest())

    def _check_numbers(self, names: Iterable[str]) -> None:
        """Validate (and store as float vectors) the numbers ``names``."""
        names = set(names)
        if "duration" in names and not (self.duration > 0 and np.isfinite(self.duration)):
            raise ValueError(f"duration must be a positive number, got {self.duration}")
        for name in names - {"duration"}:
            object.__setattr__(self, name, _vec(getattr(self, name), self._sizes[name], name))
        for name in names & {"x0", "p_value"}:
            if not np.all(np.isfinite(getattr(self, name))):
                raise ValueError("x0 and p_value must be finite")
        for lo, hi in (("path_lb", "path_ub"), ("x_lb", "x_ub"), ("u_lb", "u_ub")):
            if names & {lo, hi} and np.any(getattr(self, lo) > getattr(self, hi)):
                raise ValueError(f"{lo} > {hi} for some entry")

    _NUMBERS = ("duration", "x0", "p_value", "path_lb", "path_ub", "x_lb", "x_ub", "u_lb", "u_ub")

    def with_numbers(self, **numbers: object) -> OcpProblem:
        """The same statement (and structure key) with other numerical data.

        Accepts ``duration``, ``x0``, ``p_value``, the path bounds and the simple bounds;
        much cheaper than building the statement again.
        """
        unknown = set(numbers) - set(self._NUMBERS)
        if unknown:
            raise TypeError(f"with_numbers() got unexpected fields {sorted(unknown)}")
        new = copy.copy(self)
        for name, value in numbers.items():
            object.__setattr__(new, name, value)
        new._check_numbers(numbers)
        return new

    @property
    def nx(self) -> int:
        return int(self._sizes["x0"])

    @property
    def nu(self) -> int:
        return int(self._sizes["u_lb"])

    @property
    def structure_key(self) -> str:
        """Hash of the symbolic statement: equal keys share a transcription and a solver."""
        return self._key

    def functions(self) -> dict[str, ca.Function]:
        """The statement's expressions as CasADi Functions of (x, u, t, p, T, h)."""
        args = [self.x, self.u, self.t, self.p, self.T, self.h]
        names = ["x", "u", "t", "p", "T", "h"]
        return {
            "ode": ca.Function(
                "ode", [self.x, self.u, self.p], [self.ode], ["x", "u", "p"], ["xdot"]
            ),
            "stage_cost": ca.Function("stage_cost", args, [self.stage_cost], names, ["L"]),
            "terminal_cost": ca.Function(
                "terminal_cost", [self.x, self.p], [self.terminal_cost], ["x", "p"], ["E"]
            ),
            "path": ca.Function("path", args, [self.path], names, ["g"]),
            "terminal": ca.Function(
                "terminal", [self.x, self.p], [self.terminal], ["x", "p"], ["h"]
            ),
        }
