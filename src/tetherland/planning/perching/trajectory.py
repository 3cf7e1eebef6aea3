"""The planned perching maneuver as a free-flight trajectory, with CSV files.

A :class:`FreeFlightTrajectory` holds the node states X (N+1, 10) and the inputs
U (N, 2) = [f_R'', tau''] (held on each interval) of the planar model of :mod:`.model`.
Between nodes the model is integrated with the input held (RK4 steps of at most
:data:`DENSE_STEP`), so every sample is the model's own motion: p is C^3, its snap jumps
with f_R''. :meth:`FreeFlightTrajectory.simulate` builds one by integrating through all
intervals from the initial state: that re-simulation, not the solver's nodes, is what the
planner checks and hands out.

Samples (:class:`FreeFlightSamples`) give, in F_W, the flat outputs p(t) with derivatives
up to the snap and the yaw, and the nominal attitude R_WB, body rate and angular
acceleration, total thrust, body torque and rotor thrusts with their rates. Before 0 and
after T the end values are held with zero derivatives.

CSV (:mod:`tetherland.planning.codec`): ``#`` header lines (format, kind, scenario,
version, a JSON ``meta`` line with the model constants), then one row per node: t, the 10
states and the 2 inputs (the last row's inputs are zero).
:func:`load_free_flight_trajectory` rebuilds the same trajectory.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from tetherland import GRAVITY, __version__
from tetherland.errors import ConfigError
from tetherland.geometry import FloatArray
from tetherland.io import atomic_write_text
from tetherland.models.integrators import rk4
from tetherland.planning import codec
from tetherland.planning.perching import kernels
from tetherland.planning.perching.model import (
    CASADI,
    NU,
    NUMPY,
    NX,
    STATE_NAMES,
    PerchSpec,
    flat_derivatives,
    rhs,
)
from tetherland.planning.shooting import DENSE_STEP, HeldInputMotion, HeldInputSimulator

FORMAT_VERSION = codec.FORMAT_VERSION
KIND = "free-flight"
SCHEMA = codec.CsvSchema(KIND, ("t", *STATE_NAMES, "f_R_ddot", "tau_ddot"))
"""CSV columns of a :class:`FreeFlightTrajectory`: one row per node (the last row's
inputs are zero)."""
__all__ = [
    "DENSE_STEP",
    "SCHEMA",
    "FreeFlightMeta",
    "FreeFlightSamples",
    "FreeFlightTrajectory",
    "free_flight_rk4_step",
    "free_flight_trajectory_from_csv",
    "load_free_flight_trajectory",
]


@dataclass(frozen=True)
class FreeFlightMeta:
    """Model constants and frame of a free-flight trajectory.

    Attributes
    ----------
    scenario : str
    mass, inertia, gravity : float
        m [kg], J_y about y_B [kg m^2], g [m/s^2].
    G : (4, 2) array
        [f_R, tau] -> rotor thrusts.
    R_WA : (3, 3) array
        Plane frame (x_A horizontal downhill, y_A, z_W).
    p_L : (3,) array
        Landing point, origin of the plane coordinates, F_W [m].
    beta : float
        Slope angle [rad].
    h_R : float
        Centre of mass to landers plane [m].
    approach_speed : float
        Planned touchdown speed along -z_S [m/s].
    rotor_drag : float
        Rotor drag d_x of the model [N s/m] (0: drag-free; the key is then left out of
        the CSV header, as before the drag was modelled).
    version : str
    """

    scenario: str
    mass: float
    inertia: float
    G: FloatArray
    R_WA: FloatArray
    p_L: FloatArray
    beta: float
    h_R: float
    approach_speed: float = 0.0
    gravity: float = GRAVITY
    version: str = field(default=__version__)
    rotor_drag: float = 0.0

    @classmethod
    def from_spec(cls, spec: PerchSpec) -> FreeFlightMeta:
        return cls(
            scenario=spec.scenario_name, mass=spec.mass, inertia=spec.inertia, G=spec.G,
            R_WA=spec.R_WA, p_L=spec.p_L, beta=spec.beta, h_R=spec.h_R,
            approach_speed=spec.approach_speed, gravity=spec.gravity,
            rotor_drag=spec.rotor_drag,
        )  # fmt: skip

    @property
    def heading(self) -> float:
        """Yaw psi of x_A in F_W [rad]."""
        return math.atan2(float(self.R_WA[1, 0]), float(self.R_WA[0, 0]))

    @property
    def z_S(self) -> FloatArray:
        """Surface normal in F_W."""
        b = self.beta
        return self.R_WA[:, 0] * math.sin(b) + self.R_WA[:, 2] * math.cos(b)

    @property
    def p_landed(self) -> FloatArray:
        """Landed centre of mass p*_L + h_R z_S in F_W [m]."""
        return self.p_L + self.h_R * self.z_S

    @property
    def constants(self) -> list[float]:
        """The model constants c of the RK4 step: [m, J_y, g], and d_x with rotor drag."""
        c = [self.mass, self.inertia, self.gravity]
        return [*c, self.rotor_drag] if self.rotor_drag > 0.0 else c

    def to_json(self) -> dict[str, Any]:
        d = codec.meta_to_json(self)
        if self.rotor_drag == 0.0:
            del d["rotor_drag"]
        return d

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> FreeFlightMeta:
        return codec.meta_from_json(cls, d)


@dataclass(frozen=True)
class FreeFlightSamples:
    """A free-flight trajectory sampled at times ``t`` (leading axis n), F_W.

    Attributes
    ----------
    t : (n,) array [s]
    p_W : (n, 5, 3) array
        Centre of mass position and derivatives 1..4 (velocity, acceleration, jerk,
        snap) [m, m/s, m/s^2, m/s^3, m/s^4].
    reference_W : (n, 5, 3) array
        The rows the tracker flies: position and velocity as ``p_W``, then the thrust's
        acceleration f_R z_B / m - g z_W and its jerk and snap [m/s^2, m/s^3, m/s^4]:
        the planned motion with the model's rotor drag taken out, so that the flatness
        feed-forward of these rows is the planned attitude, body rate and angular
        acceleration. Without drag in the model, ``p_W`` bit for bit.
    yaw : (n,) array
        Reference heading psi [rad] (x_B in the fall-line plane).
    R_WB : (n, 3, 3) array
        Nominal attitude.
    omega_B, omega_dot_B : (n, 3) arrays
        Nominal body rate [rad/s] and angular acceleration [rad/s^2], F_B.
    thrust, thrust_rate : (n,) arrays
        f_R [N], f_R' [N/s].
    torque_B : (n, 3) array
        Nominal body torque [N m].
    rotor_thrusts, rotor_thrust_rates : (n, 4) arrays
        f_i [N], f_i' [N/s].
    states : (n, 10) array
        Planar extended states (plane coordinates relative to p*_L).
    """

    t: FloatArray
    p_W: FloatArray
    reference_W: FloatArray
    yaw: FloatArray
    R_WB: FloatArray
    omega_B: FloatArray
    omega_dot_B: FloatArray
    thrust: FloatArray
    thrust_rate: FloatArray
    torque_B: FloatArray
    rotor_thrusts: FloatArray
    rotor_thrust_rates: FloatArray
    states: FloatArray

    @property
    def z_B(self) -> FloatArray:
        """(n, 3) nominal thrust axes."""
        return self.R_WB[:, :, 2]


def free_flight_rk4_step(drag: bool = False) -> ca.Function:
    """``step(x[10], u[2], h, c[3]) -> x(t + h)``: one RK4 step of the free-flight model
    with the input held, for the constants c = [m, J_y, g] (``drag``: the model with rotor
    drag, c[4] = [m, J_y, g, d_x])."""
    n = 4 if drag else 3
    x, u, h, c = ca.SX.sym("x", NX), ca.SX.sym("u", NU), ca.SX.sym("h"), ca.SX.sym("c", n)

    def f(z: ca.SX, v: ca.SX) -> ca.SX:
        return rhs(z, v, c[0], c[1], c[2], CASADI, c[3] if drag else None)

    return ca.Function("perch_drag_rk4" if drag else "perch_rk4", [x, u, h, c], [rk4(f, x, u, h)])


_SIMULATOR: dict[bool, HeldInputSimulator] = {}


def _simulator(drag: bool = False) -> HeldInputSimulator:
    """The module's simulator of the drag-free model or the one with rotor drag (built on
    first use; its compiled chains are shared)."""
    if drag not in _SIMULATOR:
        _SIMULATOR[drag] = HeldInputSimulator(free_flight_rk4_step(drag))
    return _SIMULATOR[drag]


def _numpy_rhs(meta: FreeFlightMeta) -> Any:
    drag = meta.rotor_drag if meta.rotor_drag > 0.0 else None

    def f(x: FloatArray, u: FloatArray) -> FloatArray:
        return rhs(x, u, meta.mass, meta.inertia, meta.gravity, NUMPY, drag)  # type: ignore[no-any-return]

    return f


class FreeFlightTrajectory:
    """A planned free-flight (perching) maneuver on [0, T]; see the module docstring.

    Parameters
    ----------
    meta : FreeFlightMeta
    times : (N+1,) array
        Node times, increasing [s] (shifted to start at 0).
    X : (N+1, 10) array
        Node states.
    U : (N, 2) array
        Inputs held on each interval.
    substeps : int, optional
        RK4 steps per interval of the dense table (default: steps of <= DENSE_STEP).
    """

    kind = KIND

    def __init__(
        self,
        meta: FreeFlightMeta,
        times: ArrayLike,
        X: ArrayLike,
        U: ArrayLike,
        substeps: int | None = None,
        _motion: HeldInputMotion | None = None,
    ) -> None:
        N = len(np.atleast_1d(times)) - 1
        if N < 1 or np.shape(X) != (N + 1, NX) or np.shape(U) != (N, NU):
            raise ValueError(
                f"need X (N+1, {NX}) and U (N, {NU}) for {N + 1} times, "
                f"got {np.shape(X)}, {np.shape(U)}"
            )
        self.meta = meta
        self._motion = _motion or HeldInputMotion(
            _simulator(meta.rotor_drag > 0.0), meta.constants, _numpy_rhs(meta),
            times, X, U, substeps,
        )  # fmt: skip
        self.times, self.X, self.U = self._motion.times, self._motion.X, self._motion.U
        self.duration = self._motion.duration
        self._touchdown_rows: FloatArray | None = None  # flat outputs at T (continuation)
        self._reference_pack: tuple[FloatArray, ...] | None = None  # reference_at's arrays

    @classmethod
    def simulate(
        cls, meta: FreeFlightMeta, times: ArrayLike, x0: ArrayLike, U: ArrayLike
    ) -> FreeFlightTrajectory:
        """Integrate the model from ``x0`` with ``U`` held on each interval (RK4 steps of
        at most :data:`DENSE_STEP`) through all intervals; keep the continuous nodes."""
        motion = HeldInputMotion.simulate(
            _simulator(meta.rotor_drag > 0.0), meta.constants, _numpy_rhs(meta),
            times, x0, U,
        )  # fmt: skip
        return cls(meta, motion.times, motion.X, motion.U, _motion=motion)

    # -- evaluation --------------------------------------------------------------------
    def states(self, times: ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Planar states (n, 10) and inputs (n, 2) at ``times`` clipped to [0, T]."""
        x, u = self._motion.states(times)
        return x.T.copy(), u.T.copy()

    def _masked_states(
        self, times: ArrayLike
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Times (n,), states (n, 10), inputs (n, 2) and the mask of the times outside
        [0, T], whose rates and inputs are zero (at rest before and after)."""
        t = np.atleast_1d(np.asarray(times, dtype=float))
        x, u = self.states(t)
        outside = (t < 0.0) | (t > self.duration)
        x[outside, 3:6] = 0.0
        x[outside, 7:10] = 0.0
        u[outside] = 0.0
        return t, x, u, outside

    def _flat_rows(
        self, x: FloatArray, u: FloatArray, outside: FloatArray
    ) -> tuple[FloatArray, FloatArray, dict[str, FloatArray]]:
        """Flat-output rows (n, 5, 3) [p, v, a, jerk, snap] in F_W of :meth:`_masked_states`,
        the tracker's rows (n, 5, 3) (``FreeFlightSamples.reference_W``: p, v and the
        thrust's acceleration, jerk and snap) and the planar derivatives they came from."""
        meta = self.meta
        d = flat_derivatives(x.T, u.T, meta.mass, meta.inertia, meta.gravity, meta.rotor_drag)
        p_W = self._to_world(x, d, outside)
        if meta.rotor_drag == 0.0:
            return p_W, p_W, d
        return p_W, self._thrust_rows(x, u, outside), d

    def _thrust_rows(self, x: FloatArray, u: FloatArray, outside: FloatArray) -> FloatArray:
        """The tracker's rows (n, 5, 3) in F_W: p, v and the thrust's own acceleration
        f_R z_B / m - g z_W, jerk and snap, the drag-free closed forms of the same states
        (the planned motion less the model's drag and its derivatives; without drag in the
        model, the flat outputs' rows)."""
        meta = self.meta
        f = flat_derivatives(x.T, u.T, meta.mass, meta.inertia, meta.gravity)
        return self._to_world(x, f, outside)

    def _to_world(self, x: FloatArray, d: dict[str, FloatArray], outside: FloatArray) -> FloatArray:
        """(n, 5, 3) rows [p, v, d["acc"], d["jerk"], d["snap"]] in F_W (zero derivatives
        from the acceleration on outside [0, T])."""
        meta = self.meta
        plane = np.stack(
            (x[:, 0:2].T, x[:, 3:5].T, d["acc"], d["jerk"], d["snap"]), axis=1
        )  # (2, 5, n)
        plane[:, 2:, outside] = 0.0
        A = meta.R_WA[:, [0, 2]]
        p_W = np.einsum("ij,jkn->nki", A, plane)
        p_W[:, 0, :] += meta.p_L
        return p_W

    def reference_at(self, t: float) -> tuple[FloatArray, float]:
        """The tracker's (5, 3) rows in F_W and the collective thrust [N] at one time
        ``t`` [s]: ``sample([t]).reference_W[0]`` and ``sample([t]).thrust[0]``, the same
        numbers by the same operations, without the rest of the sample, in one compiled
        call (:func:`~tetherland.planning.perching.kernels.reference_into`; the perching
        reference asks this every control tick of the maneuver). With rotor drag in the
        model the rows from the acceleration on are the thrust's, not the flat outputs'
        (:class:`FreeFlightSamples`)."""
        pack = self._reference_pack
        if pack is None:
            motion, meta = self._motion, self.meta
            c = kernels.pack(meta.mass, meta.inertia, meta.gravity, meta.rotor_drag,
                             motion.sub, meta.R_WA, meta.p_L)  # fmt: skip
            arrays = (motion.times, motion.table, motion.U)
            pack = self._reference_pack = (*map(np.ascontiguousarray, arrays), c)
        rows = np.empty((5, 3))
        thrust = kernels.reference_into(float(t), *pack, rows)
        return rows, thrust

    def sample(self, times: ArrayLike) -> FreeFlightSamples:
        """Everything at ``times`` [s] (see :class:`FreeFlightSamples`)."""
        meta = self.meta
        t, x, u, outside = self._masked_states(times)
        n = len(t)
        p_W, reference_W, d = self._flat_rows(x, u, outside)
        th = x[:, 2]
        c, s = np.cos(th), np.sin(th)
        R_y = np.zeros((n, 3, 3))
        R_y[:, 0, 0], R_y[:, 0, 2], R_y[:, 1, 1] = c, s, 1.0
        R_y[:, 2, 0], R_y[:, 2, 2] = -s, c
        R_WB = meta.R_WA[None, :, :] @ R_y
        zeros = np.zeros(n)
        omega_dot = np.where(outside, 0.0, d["omega_dot"])
        wrench, wrench_dot = x[:, 6:8], x[:, 8:10]
        return FreeFlightSamples(
            t=t,
            p_W=p_W,
            reference_W=reference_W,
            yaw=np.full(n, meta.heading),
            R_WB=R_WB,
            omega_B=np.column_stack((zeros, x[:, 5], zeros)),
            omega_dot_B=np.column_stack((zeros, omega_dot, zeros)),
            thrust=x[:, 6].copy(),
            thrust_rate=x[:, 8].copy(),
            torque_B=np.column_stack((zeros, x[:, 7], zeros)),
            rotor_thrusts=wrench @ meta.G.T,
            rotor_thrust_rates=wrench_dot @ meta.G.T,
            states=x,
        )

    def flat_outputs(self, t: float) -> FloatArray:
        """(5, 3) rows [p, v, a, jerk, snap] of the planned motion at ``t`` in F_W
        (``sample([t]).p_W[0]``; the tracker's rows are :meth:`reference_at`'s)."""
        _, x, u, outside = self._masked_states([t])
        return self._flat_rows(x, u, outside)[0][0]

    def continuation(self, s: float) -> FloatArray:
        """(5, 3) flat-output rows ``s`` seconds after t_L with the touchdown thrust and
        attitude held (constant acceleration): the free flight that goes on towards the
        surface until contact when the vehicle is late [F_W]."""
        if self._touchdown_rows is None:
            self._touchdown_rows = self.flat_outputs(self.duration)
            self._touchdown_rows.setflags(write=False)
        end = self._touchdown_rows
        s = max(0.0, float(s))
        rows = np.zeros((5, 3))
        rows[0] = end[0] + end[1] * s + 0.5 * end[2] * s * s
        rows[1] = end[1] + end[2] * s
        rows[2] = end[2]
        return rows

    @property
    def start_state(self) -> FloatArray:
        return self.X[0].copy()

    @property
    def final_state(self) -> FloatArray:
        return self.states([self.duration])[0][0]

    # -- files -------------------------------------------------------------------------
    def to_csv(self) -> str:
        """CSV text (:mod:`tetherland.planning.codec`): header lines, column names, one
        row per node."""
        U = np.vstack((self.U, np.zeros((1, NU))))
        data = np.column_stack((self.times, self.X, U))
        meta = {**self.meta.to_json(), "duration": self.duration, "substeps": self._motion.sub}
        return codec.encode(
            SCHEMA, data, meta, scenario=self.meta.scenario, maneuver="perching",
            version=self.meta.version,
        )  # fmt: skip

    def save_csv(self, path: str | Path) -> Path:
        """Write :meth:`to_csv` to ``path`` atomically."""
        return atomic_write_text(path, self.to_csv())


def free_flight_trajectory_from_csv(text: str) -> FreeFlightTrajectory:
    """Rebuild a trajectory from :meth:`FreeFlightTrajectory.to_csv` text."""
    doc = codec.decode(text, (SCHEMA,))
    try:
        meta = FreeFlightMeta.from_json(doc.meta)
        substeps = int(doc.meta["substeps"])
    except KeyError as err:
        raise ConfigError(f"trajectory CSV: bad meta header (no {err})") from None
    data = doc.data
    return FreeFlightTrajectory(
        meta, data[:, 0], data[:, 1 : 1 + NX], data[:-1, 1 + NX :], substeps=substeps
    )


def load_free_flight_trajectory(path: str | Path) -> FreeFlightTrajectory:
    """Read a trajectory CSV written by :meth:`FreeFlightTrajectory.save_csv`."""
    return free_flight_trajectory_from_csv(codec.read_text(path))
