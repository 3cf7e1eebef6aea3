"""Planned references y^bd(t) with derivatives, nominal state and input, and CSV files.

A :class:`Trajectory` answers, at any time t (held at its end values outside [0, T]):
the output y^bd = [phi, delta = 0, theta_A, psi*] with derivatives up to the 4th order,
the planar extended state x = [phi, theta_A, phi', theta_A', f, f'] and input f'' of
(6.20), the tension, and through :class:`~tetherland.models.flatness.FlatnessMap` the
full nominal state and input of the quadrotor.

Two kinds share this interface:

* :class:`ShootingTrajectory` (``ocp``): the node states and piecewise-constant inputs
  f'' of an OCP solution. Between nodes the model (6.20) is integrated with the input
  held (fine RK4 steps, exact for the thrusts, which are C^1), so phi and theta_A and
  their derivatives are those of the model: phi is C^3, phi'''' jumps with f''.
* :class:`PolynomialTrajectory` (``spline``): 9th-order rest-to-rest polynomials for phi
  and theta_A; thrusts and tension from planar flatness.

CSV files (:mod:`tetherland.planning.codec`) have ``#`` header lines (format, kind,
scenario, maneuver, version and a JSON ``meta`` line with the model constants), then one
row per node (ocp) or sample (spline); :func:`load_trajectory` rebuilds the same
trajectory.
"""

from __future__ import annotations

import functools
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from tetherland import GRAVITY, __version__
from tetherland.errors import ConfigError
from tetherland.geometry import FloatArray
from tetherland.io import atomic_write_text
from tetherland.models.flatness import FlatnessMap, NominalState, OutputDerivatives
from tetherland.models.planar import (
    NUMPY,
    ExtendedPlanarModel,
    PlanarParams,
    parametric_rk4_step,
    planar_flat_inputs,
)
from tetherland.planning import codec, kernels
from tetherland.planning.shooting import (
    DENSE_STEP,
    HeldInputMotion,
    HeldInputSimulator,
    NumpyRhs,
)
from tetherland.planning.spline import rest_to_rest

FORMAT_VERSION = codec.FORMAT_VERSION
_COLUMNS = (
    "t", *(f"phi_d{k}" for k in range(5)), *(f"theta_A_d{k}" for k in range(5)),
    *(f"f{i}" for i in range(1, 5)), *(f"f{i}_dot" for i in range(1, 5)),
    *(f"f{i}_ddot" for i in range(1, 5)), "f_R", "tension",
)  # fmt: skip
OCP_SCHEMA = codec.CsvSchema("ocp", _COLUMNS)
"""CSV columns of a :class:`ShootingTrajectory` (one row per node)."""
SPLINE_SCHEMA = codec.CsvSchema("spline", _COLUMNS)
"""CSV columns of a :class:`PolynomialTrajectory` (rows on a uniform grid)."""


@dataclass(frozen=True)
class TrajectoryMeta:
    """Where a trajectory comes from and the model constants needed to evaluate it.

    Attributes
    ----------
    scenario : str
    maneuver : str
        ``landing`` or ``takeoff``.
    mass, length : float
        [kg], [m].
    inertia_B : (3,) or (3, 3) array
        [kg m^2].
    allocation : (4, 4) array
        Gamma (6.19).
    heading : float
        psi* [rad].
    R_WA : (3, 3) array
        Anchor frame.
    p_A : (3,) array
        Anchor point in F_W [m].
    gravity : float
    version : str
        tetherland version that made it.
    r_att_B : (3,) array
        Cable attachment offset in F_B the plan's model counts exactly [m] (zeros: the
        chapter's cable at the centre of mass; files without it load as zeros).
    """

    scenario: str
    maneuver: str
    mass: float
    length: float
    inertia_B: FloatArray
    allocation: FloatArray
    heading: float = 0.0
    R_WA: FloatArray = field(default_factory=lambda: np.eye(3))
    p_A: FloatArray = field(default_factory=lambda: np.zeros(3))
    gravity: float = GRAVITY
    version: str = __version__
    r_att_B: FloatArray = field(default_factory=lambda: np.zeros(3))

    @functools.cached_property
    def params(self) -> PlanarParams:
        """The planar model constants (computed once)."""
        return PlanarParams.from_matrices(
            self.mass, self.length, self.inertia_B, self.allocation, self.heading, self.gravity,
            r_att_B=self.r_att_B,
        )  # fmt: skip

    def to_json(self) -> dict[str, Any]:
        return codec.meta_to_json(self)

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> TrajectoryMeta:
        return codec.meta_from_json(cls, d)


@dataclass(frozen=True)
class TrajectorySamples:
    """A trajectory sampled at times ``t`` (arrays with a leading sample axis n).

    Attributes
    ----------
    t : (n,) array [s]
    phi, theta_A : (n, 5) arrays
        Value and derivatives 1..4 [rad, rad/s^k].
    psi : float
        psi* [rad] (delta is 0).
    thrusts, thrust_rates, thrust_accels : (n, 4) arrays
        f, f', f'' [N, N/s, N/s^2].
    f_R, tension : (n,) arrays
        Total thrust and cable tension [N].
    """

    t: FloatArray
    phi: FloatArray
    theta_A: FloatArray
    psi: float
    thrusts: FloatArray
    thrust_rates: FloatArray
    thrust_accels: FloatArray
    f_R: FloatArray
    tension: FloatArray

    def outputs(self) -> FloatArray:
        """(n, 16) rows of :meth:`OutputDerivatives.as_vector` for the flatness map."""
        n = len(self.t)
        psi = np.tile([self.psi, 0.0, 0.0], (n, 1))
        return np.hstack((self.phi, np.zeros((n, 5)), self.theta_A[:, :3], psi))

    def states(self) -> FloatArray:
        """(n, 12) rotor-form extended states [phi, theta_A, phi', theta_A', f, f']."""
        return np.hstack(
            (self.phi[:, :1], self.theta_A[:, :1], self.phi[:, 1:2], self.theta_A[:, 1:2],
             self.thrusts, self.thrust_rates)
        )  # fmt: skip


@functools.cache
def _planar_step() -> ca.Function:
    """The CasADi RK4 step of (6.20) (built once per process)."""
    return parametric_rk4_step()


class PlanarSimulator(HeldInputSimulator):
    """Integrates (6.20) with f'' held on each interval, in fixed RK4 substeps.

    ``run``/``restart``/``advance`` take the model constants ``PlanarParams.coefficients``
    and run the compiled kernels :func:`~tetherland.planning.kernels.held_input` and
    :func:`~tetherland.planning.kernels.rk4_rows`; the CasADi chains of the base class on
    the same RK4 step, and the model's numpy right-hand side, are their references.
    """

    def __init__(self) -> None:
        super().__init__(_planar_step())

    def run(
        self, c: FloatArray, times: FloatArray, x0: FloatArray, U: FloatArray, sub: int
    ) -> FloatArray:
        return self._held(c, times, np.asarray(x0)[None, :], U, sub, through=True)

    def restart(
        self, c: FloatArray, times: FloatArray, X: FloatArray, U: FloatArray, sub: int
    ) -> FloatArray:
        return self._held(c, times, X, U, sub, through=False)

    @staticmethod
    def _held(
        c: FloatArray, times: FloatArray, X: FloatArray, U: FloatArray, sub: int, through: bool
    ) -> FloatArray:
        def arr(a: ArrayLike) -> FloatArray:
            return np.ascontiguousarray(a, dtype=float)

        return kernels.held_input(arr(X), arr(U), arr(np.diff(times)), sub, arr(c), through)

    def advance(
        self, c: FloatArray, rhs: NumpyRhs, x: FloatArray, u: FloatArray, h: FloatArray
    ) -> FloatArray:
        return kernels.rk4_rows(
            np.ascontiguousarray(x.T, dtype=float), np.ascontiguousarray(u.T, dtype=float),
            np.ascontiguousarray(h, dtype=float), np.ascontiguousarray(c, dtype=float),
        ).T  # fmt: skip


class Trajectory(ABC):
    """A planned landing or takeoff reference on [0, T]; see the module docstring."""

    kind: ClassVar[str]

    def __init__(self, meta: TrajectoryMeta, duration: float) -> None:
        if not duration > 0:
            raise ValueError(f"duration must be > 0, got {duration}")
        self.meta = meta
        self.duration = float(duration)
        self.params = meta.params
        self.model = ExtendedPlanarModel(self.params)
        self._flatness: FlatnessMap | None = None

    # -- the one method a kind must provide ----------------------------------------
    @abstractmethod
    def _evaluate(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """phi (n,5), theta_A (n,5), x (n,12), u (n,4) for times in [0, T]."""

    @abstractmethod
    def _rows(self) -> FloatArray:
        """Times of the CSV rows."""

    @abstractmethod
    def _extra_meta(self) -> dict[str, Any]:
        """Kind-specific JSON needed to rebuild the trajectory from its CSV."""

    # -- interface -------------------------------------------------------------------
    def sample(self, times: ArrayLike) -> TrajectorySamples:
        """Everything at ``times`` [s]; before 0 and after T the end values are held
        (derivatives, thrust rates and f'' zero)."""
        t = np.atleast_1d(np.asarray(times, dtype=float))
        tc = np.clip(t, 0.0, self.duration)
        phi, theta, x, u = self._evaluate(tc)
        outside = (t < 0.0) | (t > self.duration)
        if np.any(outside):
            phi[outside, 1:] = 0.0
            theta[outside, 1:] = 0.0
            x[outside, 2:4] = 0.0
            x[outside, 8:12] = 0.0
            u[outside] = 0.0
        return TrajectorySamples(
            t=t,
            phi=phi,
            theta_A=theta,
            psi=self.params.heading,
            thrusts=x[:, 4:8],
            thrust_rates=x[:, 8:12],
            thrust_accels=u,
            f_R=x[:, 4:8].sum(axis=1),
            tension=np.asarray(self.model.tension(x.T)),
        )

    def states_at(self, times: ArrayLike) -> FloatArray:
        """Rotor-form extended states (n, 12) at ``times`` [s], held outside [0, T] (rates
        zero): the states of :meth:`sample` without the output's higher derivatives (what
        the checks need)."""
        t = np.atleast_1d(np.asarray(times, dtype=float))
        x = self._states(np.clip(t, 0.0, self.duration))
        outside = (t < 0.0) | (t > self.duration)
        if np.any(outside):
            x[outside, 2:4] = 0.0
            x[outside, 8:12] = 0.0
        return x

    def _states(self, t: FloatArray) -> FloatArray:
        """States (n, 12) for times in [0, T] (a kind may do this cheaper than
        :meth:`_evaluate`)."""
        return self._evaluate(t)[2]

    def output(self, t: float) -> OutputDerivatives:
        """y^bd(t) = [phi, 0, theta_A, psi*] with derivatives (4th order for phi, delta)."""
        s = self.sample([t])
        return OutputDerivatives.planar(s.phi[0], s.theta_A[0], s.psi)

    def state(self, t: float) -> FloatArray:
        """Planar extended state (12,) of (6.20) at ``t``."""
        return self.sample([t]).states()[0]

    @property
    def flatness(self) -> FlatnessMap:
        """The flatness map of this trajectory's vehicle (built on first use)."""
        if self._flatness is None:
            m = self.meta
            self._flatness = FlatnessMap(
                mass=m.mass, length=m.length, inertia=m.inertia_B, allocation=m.allocation,
                R_WA=m.R_WA, p_A=m.p_A, gravity=m.gravity,
            )  # fmt: skip
        return self._flatness

    def nominal(self, t: float) -> NominalState:
        """Nominal state and input of the quadrotor at ``t`` (flatness, figure 6.5 "n").

        Uses the chapter's model (cable at the centre of mass). For the rotor thrusts
        that also cancel the cable torque of the attachment offset (6.6.5), evaluate
        ``FlatnessMap.from_scenario(scenario, with_cable_offset=True)`` on
        :meth:`output`.
        """
        return self.flatness.evaluate(self.output(t))

    def nominal_many(self, times: ArrayLike) -> dict[str, FloatArray]:
        """:meth:`FlatnessMap.evaluate_many` at ``times``."""
        return self.flatness.evaluate_many(self.sample(times).outputs())

    @property
    def initial_output(self) -> FloatArray:
        return self.output(0.0).value

    @property
    def final_output(self) -> FloatArray:
        return self.output(self.duration).value

    # -- files -----------------------------------------------------------------------
    def to_csv(self) -> str:
        """The CSV text (:mod:`tetherland.planning.codec`: header lines, column names, rows)."""
        s = self.sample(self._rows())
        data = np.column_stack(
            (s.t, s.phi, s.theta_A, s.thrusts, s.thrust_rates, s.thrust_accels, s.f_R, s.tension)
        )
        meta = {**self.meta.to_json(), "duration": self.duration, **self._extra_meta()}
        schema = OCP_SCHEMA if self.kind == OCP_SCHEMA.kind else SPLINE_SCHEMA
        return codec.encode(
            schema, data, meta, scenario=self.meta.scenario, maneuver=self.meta.maneuver,
            version=self.meta.version,
        )  # fmt: skip

    def save_csv(self, path: str | Path) -> Path:
        """Write :meth:`to_csv` to ``path`` atomically."""
        return atomic_write_text(path, self.to_csv())


class ShootingTrajectory(Trajectory):
    """An OCP solution: node states X (N+1, 12) and inputs U (N, 4) held on each interval.

    Use :meth:`simulate` to build one from an initial state and inputs: it integrates
    the model through all intervals so that the node states are continuous.
    """

    kind = "ocp"

    def __init__(
        self,
        meta: TrajectoryMeta,
        times: ArrayLike,
        X: ArrayLike,
        U: ArrayLike,
        substeps: int | None = None,
        simulator: PlanarSimulator | None = None,
        _motion: HeldInputMotion | None = None,
    ) -> None:
        times = np.asarray(times, dtype=float)
        super().__init__(meta, float(times[-1] - times[0]))
        N = len(times) - 1
        if np.shape(X) != (N + 1, 12) or np.shape(U) != (N, 4):
            raise ValueError(
                f"need X (N+1, 12) and U (N, 4) for {N + 1} times, got {np.shape(X)}, {np.shape(U)}"
            )
        # Dense table: the state at every substep of every interval (substeps no longer
        # than DENSE_STEP), integrated from the node states with the input held.
        self._motion = _motion or HeldInputMotion(
            simulator or PlanarSimulator(), self.params.coefficients, self.model.rhs,
            times, X, U, substeps,
        )  # fmt: skip
        self.times, self.X, self.U = self._motion.times, self._motion.X, self._motion.U

    @classmethod
    def simulate(
        cls,
        meta: TrajectoryMeta,
        times: ArrayLike,
        x0: ArrayLike,
        U: ArrayLike,
        simulator: PlanarSimulator | None = None,
    ) -> ShootingTrajectory:
        """Integrate (6.20) from ``x0`` with the inputs ``U`` held on each interval (RK4
        steps of at most :data:`DENSE_STEP`) and keep the continuous node states."""
        params = meta.params
        motion = HeldInputMotion.simulate(
            simulator or PlanarSimulator(), params.coefficients,
            ExtendedPlanarModel(params).rhs, times, x0, U,
        )  # fmt: skip
        return cls(meta, motion.times, motion.X, motion.U, _motion=motion)

    def _evaluate(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        x, u = self._motion.states(t)
        d = self.model.derivatives(x, u)
        phi = np.stack((x[0], x[2], d["phi_ddot"], d["phi_dddot"], d["phi_ddddot"]), axis=1)
        theta = np.stack((x[1], x[3], d["theta_ddot"], d["theta_dddot"], d["theta_ddddot"]), axis=1)
        return phi, theta, x.T.copy(), u.T.copy()

    def _states(self, t: FloatArray) -> FloatArray:
        return self._motion.states(t)[0].T.copy()

    def _rows(self) -> FloatArray:
        return self.times

    def _extra_meta(self) -> dict[str, Any]:
        return {"substeps": self._motion.sub}


class PolynomialTrajectory(Trajectory):
    """Rest-to-rest 9th-order polynomials for phi and theta_A (:mod:`.spline`)."""

    kind = "spline"
    ROWS = 101

    def __init__(
        self,
        meta: TrajectoryMeta,
        duration: float,
        phi: tuple[float, float],
        theta_A: tuple[float, float],
    ) -> None:
        super().__init__(meta, duration)
        self.phi_ends = (float(phi[0]), float(phi[1]))
        self.theta_ends = (float(theta_A[0]), float(theta_A[1]))

    def _evaluate(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        phi = rest_to_rest(*self.phi_ends, self.duration, t)
        theta = rest_to_rest(*self.theta_ends, self.duration, t)
        w = planar_flat_inputs(phi, theta, self.params, NUMPY)
        G = self.params.G
        f = G @ np.vstack((w["f_R"], w["tau"]))
        f1 = G @ np.vstack((w["f_R_dot"], w["tau_dot"]))
        f2 = G @ np.vstack((w["f_R_ddot"], w["tau_ddot"]))
        x = np.vstack((phi[0], theta[0], phi[1], theta[1], f, f1))
        return phi.T.copy(), theta.T.copy(), x.T.copy(), f2.T.copy()

    def _rows(self) -> FloatArray:
        return np.linspace(0.0, self.duration, self.ROWS)

    def _extra_meta(self) -> dict[str, Any]:
        return {"phi_ends": list(self.phi_ends), "theta_A_ends": list(self.theta_ends)}


def trajectory_from_csv(text: str) -> Trajectory:
    """Rebuild a trajectory from :meth:`Trajectory.to_csv` text."""
    doc = codec.decode(text, (OCP_SCHEMA, SPLINE_SCHEMA))
    try:
        meta = TrajectoryMeta.from_json(doc.meta)
        if doc.kind == ShootingTrajectory.kind:
            data = doc.data
            X = np.column_stack((data[:, 1], data[:, 6], data[:, 2], data[:, 7], data[:, 11:19]))
            return ShootingTrajectory(
                meta, data[:, 0], X, data[:-1, 19:23], substeps=int(doc.meta["substeps"])
            )
        return PolynomialTrajectory(
            meta,
            doc.meta["duration"],
            tuple(doc.meta["phi_ends"]),
            tuple(doc.meta["theta_A_ends"]),
        )
    except KeyError as err:
        raise ConfigError(f"trajectory CSV: bad meta header (no {err})") from None


def load_trajectory(path: str | Path) -> Trajectory:
    """Read a trajectory CSV written by :meth:`Trajectory.save_csv`."""
    return trajectory_from_csv(codec.read_text(path))


__all__ = [
    "DENSE_STEP",
    "OCP_SCHEMA",
    "SPLINE_SCHEMA",
    "PlanarSimulator",
    "PolynomialTrajectory",
    "ShootingTrajectory",
    "Trajectory",
    "TrajectoryMeta",
    "TrajectorySamples",
    "load_trajectory",
    "trajectory_from_csv",
]
