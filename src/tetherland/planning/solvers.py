"""NLP solvers for transcribed optimal control problems: IPOPT and fatrop (bundled in CasADi).

:class:`OcpSolver` builds the CasADi ``nlpsol`` of a problem structure once and reuses it
for every later problem of the same structure (same symbolic statement, transcription and
solver settings): only numbers change between solves. A solve can be warm-started from
a previous :class:`OcpSolution` (primal values, and the multipliers for IPOPT).

fatrop evaluates the NLP through its interval functions compiled to C
(:mod:`.stagewise`, :attr:`SolverSettings.jit`); IPOPT, the fallback, through CasADi's
own functions of the flat NLP (the plain statement). Both are called on numpy arrays
(CasADi's buffer interface), without converting the numbers to CasADi matrices.
"""

from __future__ import annotations

import enum
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from tetherland.geometry import FloatArray
from tetherland.planning import stagewise
from tetherland.planning.ocp import OcpProblem
from tetherland.planning.transcription import MultipleShooting, Transcript

SolverName = Literal["fatrop", "ipopt"]
SOLVERS: tuple[str, ...] = ("fatrop", "ipopt")


class SolveStatus(enum.Enum):
    """Outcome of an NLP solve, from the solver's own return status."""

    SUCCESS = "success"
    INFEASIBLE = "infeasible"
    MAX_ITER = "max_iter"
    FAILED = "failed"


_UNIFIED = {
    "SOLVER_RET_SUCCESS": SolveStatus.SUCCESS,
    "SOLVER_RET_INFEASIBLE": SolveStatus.INFEASIBLE,
    "SOLVER_RET_LIMITED": SolveStatus.MAX_ITER,
}
_IPOPT = {
    "Solve_Succeeded": SolveStatus.SUCCESS,
    "Solved_To_Acceptable_Level": SolveStatus.SUCCESS,
    "Search_Direction_Becomes_Too_Small": SolveStatus.SUCCESS,
    "Infeasible_Problem_Detected": SolveStatus.INFEASIBLE,
    "Maximum_Iterations_Exceeded": SolveStatus.MAX_ITER,
    "Maximum_CpuTime_Exceeded": SolveStatus.MAX_ITER,
    "Maximum_WallTime_Exceeded": SolveStatus.MAX_ITER,
}


# fatrop::IpSolverReturnFlag (fatrop >= 1.0, bundled with CasADi 3.7+).
_FATROP_FLAGS = {
    0: "Success",
    1: "MaxIterExceeded",
    2: "StopAtTinyStep",
    3: "StopAtAcceptablePoint",
    4: "LocalInfeasibility",
    5: "FeasiblePointFound",
    6: "DivergingIterates",
    7: "ErrorInStepComputation",
    8: "InvalidOption",
    9: "InternalError",
    10: "Unknown",
}
# Acceptable-point and tiny-step exits count as candidate solutions: like every solution
# they must pass the planner's re-simulation check before they are used.
_FATROP = {
    0: SolveStatus.SUCCESS,
    1: SolveStatus.MAX_ITER,
    2: SolveStatus.SUCCESS,
    3: SolveStatus.SUCCESS,
    4: SolveStatus.INFEASIBLE,
}


@dataclass(frozen=True)
class SolverSettings:
    """Which NLP solver and how hard it tries.

    Attributes
    ----------
    name : {"fatrop", "ipopt"}
    tol : float
        Convergence tolerance (KKT error) [-].
    max_iter : int
        Iteration limit.
    mu_init : float or None
        Initial barrier parameter of the interior-point method (None: the solver's
        default, 0.1); smaller values suit a good initial guess.
    verbose : bool
        Print the solver's iteration log.
    warm_mu_init : float or None
        Initial barrier parameter of a warm start (None: 1e-4 for fatrop, 1e-5 for
        IPOPT); a start very near the solution (online re-planning) takes 1e-8.
    constr_viol_tol : float or None
        Constraint violation tolerance of the converged point (None: the solver's
        default, 1e-4) [constraint units].
    jit : bool
        fatrop: evaluate the NLP through its interval functions compiled to C
        (:mod:`.stagewise`; a few seconds once per structure and machine, then loaded
        from the disk cache; 5-10x faster evaluations than CasADi's virtual machine).
        Without the C compiler, or with IPOPT, the solver evaluates CasADi's own NLP
        functions (:attr:`~tetherland.planning.transcription.Transcript.nlp`).
    """

    name: SolverName = "fatrop"
    tol: float = 1e-6
    max_iter: int = 500
    mu_init: float | None = None
    verbose: bool = False
    warm_mu_init: float | None = None
    constr_viol_tol: float | None = None
    jit: bool = True

    def __post_init__(self) -> None:
        if self.name not in SOLVERS:
            raise ValueError(f"solver must be one of {', '.join(SOLVERS)}, got {self.name!r}")
        if not self.tol > 0 or self.max_iter < 1:
            raise ValueError("tol must be > 0 and max_iter >= 1")
        for name in ("mu_init", "warm_mu_init", "constr_viol_tol"):
            value = getattr(self, name)
            if value is not None and not value > 0:
                raise ValueError(f"{name} must be > 0 (or None), got {value}")

    def options(self, transcript: Transcript, warm: bool) -> dict[str, Any]:
        """CasADi ``nlpsol`` options (warm: tuned to start near a solution)."""
        common: dict[str, Any] = {
            "expand": True, "print_time": False, "error_on_fail": False,
        }  # fmt: skip
        if self.name == "ipopt":
            ipopt: dict[str, Any] = {
                "tol": self.tol,
                "max_iter": self.max_iter,
                "print_level": 5 if self.verbose else 0,
                "sb": "yes",
            }
            if self.mu_init is not None:
                ipopt["mu_init"] = self.mu_init
            if self.constr_viol_tol is not None:
                ipopt["constr_viol_tol"] = self.constr_viol_tol
            if warm:
                ipopt.update(
                    warm_start_init_point="yes",
                    mu_init=self.warm_mu_init or 1e-5,
                    warm_start_bound_push=1e-6,
                    warm_start_mult_bound_push=1e-6,
                )
            return {**common, "ipopt": ipopt}
        fatrop: dict[str, Any] = {
            "tol": self.tol,
            "max_iter": self.max_iter,
            "print_level": 10 if self.verbose else 0,
        }
        if self.mu_init is not None:
            fatrop["mu_init"] = self.mu_init
        if self.constr_viol_tol is not None:
            fatrop["constr_viol_tol"] = self.constr_viol_tol
        # fatrop's tolerance is absolute (IPOPT scales its own): accept a point whose KKT
        # error stays below a looser bound for some iterations, as IPOPT does by default.
        fatrop.update(tol_acceptable=max(1e-4, 100 * self.tol), acceptable_iter=15)
        if warm:
            fatrop.update(mu_init=self.warm_mu_init or 1e-4, bound_push=1e-6)
        return {
            **common,
            "structure_detection": "auto",
            "equality": list(transcript.equality),
            "fatrop": fatrop,
        }


@dataclass(frozen=True)
class OcpSolution:
    """What a solver returned for one problem (raw nodes; no verification).

    Attributes
    ----------
    status : SolveStatus
    return_status : str
        The solver's own status (e.g. ``Solve_Succeeded``, ``SOLVER_RET_SUCCESS``).
    solver : str
    times : (N+1,) array
        Node times [s].
    X : (N+1, nx) array
        Node states.
    U : (N, nu) array
        Inputs, constant on [t_k, t_{k+1}).
    cost : float
    iterations : int
    solve_time : float
        Wall time of the solver call [s].
    build_time : float
        Time spent building the solver for this call (0 when it was cached) [s].
    structure_key : str
    lam_x, lam_g : arrays
        Multipliers (for warm starts).
    """

    status: SolveStatus
    return_status: str
    solver: str
    times: FloatArray
    X: FloatArray
    U: FloatArray
    cost: float
    iterations: int
    solve_time: float
    build_time: float
    structure_key: str
    lam_x: FloatArray = field(repr=False)
    lam_g: FloatArray = field(repr=False)

    @property
    def success(self) -> bool:
        return self.status is SolveStatus.SUCCESS


@dataclass(frozen=True)
class InitialGuess:
    """Node states (N+1, nx) and inputs (N, nu) to start the solver from."""

    X: FloatArray
    U: FloatArray


_NLPSOL_DEFAULTS = {"lbx": -np.inf, "ubx": np.inf, "lbg": -np.inf, "ubg": np.inf}
"""Values of the nlpsol inputs that a call does not set (the others: 0)."""


class _BufferedCall:
    """Calls an ``nlpsol`` on numpy arrays it keeps (CasADi's buffer interface): no
    conversion of the inputs and outputs to CasADi matrices, which costs about 0.1 us per
    number and call (a tenth of a warm re-plan)."""

    def __init__(self, solver: ca.Function) -> None:
        self.buffer, self.trigger = solver.buffer()
        self.args = {
            name: np.zeros(solver.nnz_in(i)) for i, name in enumerate(solver.name_in())
        }
        self.res = {
            name: np.zeros(solver.nnz_out(i)) for i, name in enumerate(solver.name_out())
        }
        for i, name in enumerate(solver.name_in()):
            self.buffer.set_arg(i, memoryview(self.args[name]))
        for i, name in enumerate(solver.name_out()):
            self.buffer.set_res(i, memoryview(self.res[name]))

    def __call__(self, args: dict[str, ArrayLike]) -> tuple[dict[str, FloatArray], dict[str, Any]]:
        """Outputs (copies) and statistics of a call with ``args`` (the other inputs at
        their defaults)."""
        for name, value in self.args.items():
            value[:] = args[name] if name in args else _NLPSOL_DEFAULTS.get(name, 0.0)
        self.trigger()
        if self.buffer.ret():
            raise RuntimeError(f"solver returned code {self.buffer.ret()}")
        return {k: v.copy() for k, v in self.res.items()}, self.buffer.stats()


def _classify(solver: str, stats: dict[str, Any]) -> tuple[SolveStatus, str]:
    unified = str(stats.get("unified_return_status", ""))
    if solver == "ipopt":
        raw = str(stats.get("return_status", unified))
        status = _IPOPT.get(raw, _UNIFIED.get(unified, SolveStatus.FAILED))
        if status is SolveStatus.SUCCESS and not stats.get("success", True):
            status = SolveStatus.FAILED
    else:
        flag = int(stats.get("fatrop", {}).get("return_flag", -1))
        raw = f"{_FATROP_FLAGS.get(flag, 'Unknown')} (fatrop return flag {flag})"
        status = _FATROP.get(flag, SolveStatus.FAILED)
    return status, raw


class OcpSolver:
    """Transcribes and solves OCPs, caching one transcription and NLP solver per structure.

    Parameters
    ----------
    transcription : MultipleShooting
    settings : SolverSettings

    The cache lives in the instance: keep one :class:`OcpSolver` (or one
    :class:`~tetherland.planning.planner.Planner`) for repeated solves.
    """

    def __init__(
        self, transcription: MultipleShooting | None = None, settings: SolverSettings | None = None
    ) -> None:
        self.transcription = transcription or MultipleShooting()
        self.settings = settings or SolverSettings()
        self._transcripts: dict[str, Transcript] = {}
        self._solvers: dict[tuple[str, bool], ca.Function] = {}
        self._bounds: dict[tuple[str, bytes], dict[str, FloatArray]] = {}
        self._calls: dict[tuple[str, bool], _BufferedCall] = {}
        self._libraries: dict[str, Path | None] = {}

    def transcript(self, problem: OcpProblem) -> Transcript:
        """The (cached) transcript of ``problem``'s structure."""
        key = problem.structure_key
        if key not in self._transcripts:
            self._transcripts[key] = self.transcription.transcribe(problem)
        return self._transcripts[key]

    @property
    def compiled(self) -> bool:
        """Whether this solver evaluates the NLP through the compiled interval functions."""
        return self.settings.jit and self.settings.name == "fatrop" and stagewise.available()

    def _nlpsol(self, transcript: Transcript, warm: bool) -> tuple[ca.Function, float]:
        key = (transcript.structure_key, warm)
        if key in self._solvers:
            return self._solvers[key], 0.0
        t0 = time.perf_counter()
        opts = self.settings.options(transcript, warm)
        name = f"ocp_{self.settings.name}"
        library = self._library(transcript) if self.compiled else None
        if library is not None:
            del opts["expand"]  # a library holds no expressions
            solver = ca.nlpsol(name, self.settings.name, str(library), opts)
        else:
            solver = ca.nlpsol(name, self.settings.name, transcript.nlp, opts)
        self._solvers[key] = solver
        self._calls[key] = _BufferedCall(solver)
        return solver, time.perf_counter() - t0

    def _library(self, transcript: Transcript) -> Path | None:
        """The compiled NLP of the transcript, or None (with a warning) when it cannot be
        built: the solver then evaluates CasADi's own functions."""
        key = transcript.structure_key
        if key not in self._libraries:
            try:
                self._libraries[key] = stagewise.library(transcript)
            except (OSError, RuntimeError) as err:
                warnings.warn(
                    f"compiled NLP functions unavailable ({err}); using CasADi's", stacklevel=3
                )
                self._libraries[key] = None
        return self._libraries[key]

    def prepare(self, problem: OcpProblem, warm: bool = False) -> float:
        """Build (or find) the solver for ``problem``'s structure; returns the build time [s]."""
        return self._nlpsol(self.transcript(problem), warm)[1]

    def solve(
        self,
        problem: OcpProblem,
        guess: InitialGuess | OcpSolution | None = None,
        warm: bool | None = None,
    ) -> OcpSolution:
        """Solve ``problem`` from ``guess`` (a warm start when it is a previous solution).

        Without a guess the solver starts from the initial state held constant and zero
        inputs. ``warm`` forces the warm-start options on or off (default: on when
        ``guess`` is an :class:`OcpSolution`, whose multipliers also start IPOPT).
        Solver exceptions are caught and reported as :attr:`SolveStatus.FAILED`.
        """
        tr = self.transcript(problem)
        N = tr.nodes
        if warm is None:
            warm = isinstance(guess, OcpSolution)
        build_time = self._nlpsol(tr, warm)[1]
        if guess is None:
            X0 = np.tile(problem.x0, (N + 1, 1))
            U0 = np.zeros((N, problem.nu))
        else:
            X0, U0 = np.asarray(guess.X, dtype=float), np.asarray(guess.U, dtype=float)
            if X0.shape != (N + 1, problem.nx) or U0.shape != (N, problem.nu):
                raise ValueError(
                    f"guess shapes {X0.shape}, {U0.shape} do not match the transcription "
                    f"({N + 1}, {problem.nx}), ({N}, {problem.nu})"
                )
        call = self._calls[(tr.structure_key, warm)]
        args = {"x0": tr.pack(X0, U0), "p": tr.parameters(problem), **self._bound_args(tr, problem)}
        if (
            warm
            and isinstance(guess, OcpSolution)
            and self.settings.name == "ipopt"
            and guess.structure_key == problem.structure_key
        ):
            args.update(lam_x0=guess.lam_x, lam_g0=guess.lam_g)
        t0 = time.perf_counter()
        try:
            res, stats = call(args)
        except RuntimeError as err:  # evaluation errors (NaN, ...) inside the solver
            elapsed = time.perf_counter() - t0
            nan_x = np.full_like(X0, np.nan)
            return OcpSolution(
                status=SolveStatus.FAILED,
                return_status=f"exception: {str(err).splitlines()[-1][:200]}",
                solver=self.settings.name,
                times=tr.times(problem.duration),
                X=nan_x,
                U=np.full_like(U0, np.nan),
                cost=float("nan"),
                iterations=0,
                solve_time=elapsed,
                build_time=build_time,
                structure_key=problem.structure_key,
                lam_x=np.zeros(tr.n_w),
                lam_g=np.zeros(len(tr.equality)),
            )
        elapsed = time.perf_counter() - t0
        status, raw = _classify(self.settings.name, stats)
        X, U = tr.unpack(res["x"])
        return OcpSolution(
            status=status,
            return_status=raw,
            solver=self.settings.name,
            times=tr.times(problem.duration),
            X=X,
            U=U,
            cost=float(res["f"][0]),
            iterations=int(stats.get("iter_count", 0)),
            solve_time=elapsed,
            build_time=build_time,
            structure_key=problem.structure_key,
            lam_x=res["lam_x"],
            lam_g=res["lam_g"],
        )

    def _bound_args(self, tr: Transcript, problem: OcpProblem) -> dict[str, FloatArray]:
        """``lbx``, ``ubx``, ``lbg``, ``ubg``, cached per bound values (re-plans change only
        the initial state, the duration and the parameters)."""
        key = (tr.structure_key, b"".join(
            np.ascontiguousarray(getattr(problem, name)).tobytes()
            for name in ("x_lb", "x_ub", "u_lb", "u_ub", "path_lb", "path_ub")
        ))  # fmt: skip
        if key not in self._bounds:
            if len(self._bounds) >= 16:
                self._bounds.clear()
            numbers = tr.numbers(problem)
            self._bounds[key] = {k: numbers[k] for k in ("lbx", "ubx", "lbg", "ubg")}
        return self._bounds[key]
