"""Differential flatness of the taut tethered quadrotor for y^b = [phi, delta, theta_A, psi].

From the output and its derivatives (4th order for phi and delta, 2nd for theta_A and
psi) :class:`FlatnessMap` computes the nominal state and input: link-end position,
velocity and acceleration, cable tension f_L, thrust f_R (with two derivatives, the
state of a dynamic extension on f_R), attitude R_WB, angular velocity and acceleration,
rotor torque and the rotor thrusts Gamma^-1 [f_R, tau_B] (6.19). These are the "nominal"
values of figure 6.5 and the feed-forward of the tethered controllers.

Model (docs/theory.md sections 4 and 7; the translational dynamics of the link end, taken at
the centre of mass as in the chapter):

  m l d'' = -m g z_W + f_R z_B - f_L d,   d = d_A(phi, delta)
  F := f_R z_B = u_x x_L + u_y y_L + u_z z_L   (F_L components, vectors in F_A)
  u_z = z_L . (m l d'' + m g z_W),  u_y = y_L . (m l d'' + m g z_W)
  u_x = u_z tan(phi + theta_A) / cos(delta)    (theta_A: tilt of the projection of z_B
                                                on span(x_L, z_L), docs/theory.md section 7)
  f_L = u_x - x_L . (m l d'' + m g z_W)

Attitude: R_AB = R_y(theta_e) R_x(roll) R_z(psi), with theta_e and roll the two angles of
z_B (theta_e = atan2(x_A.z_B, z_A.z_B) = theta_A when delta = 0; roll is the chapter's
varphi of figure 6.5) and psi the rotation about z_B. R_WB = R_WA R_AB.
Rotational dynamics: tau_B = J w' + w x J w - tau_L, where tau_L = r_att x (-f_L R_BA d)
is the cable torque about the centre of mass for an attachment offset r_att (6.6.5,
zero by default: the chapter's model).

Singular where u_z <= 0 (no thrust component across the link towards z_L), where
cos(phi + theta_A) = 0, where cos(delta) = 0, or where z_B is along y_A (roll = 90 deg);
:meth:`FlatnessMap.evaluate` raises :class:`SingularityError` there.
"""

from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import casadi as ca
import numpy as np
from numpy.typing import ArrayLike

from tetherland import GRAVITY, ccode
from tetherland.errors import SingularityError
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.models.quadrotor import RotorLayout
from tetherland.rotations import rotmat_to_quat

if TYPE_CHECKING:
    from tetherland.config import Scenario

SINGULAR_TOL = 1e-9
"""Thresholds of the singularity checks (u_z [N], |cos| [-])."""

_ORDERS = (5, 5, 3, 3)  # derivative counts kept for phi, delta, theta_A, psi
OUTPUT_SIZE = sum(_ORDERS)


@dataclass(frozen=True)
class OutputDerivatives:
    """The output y^b = [phi, delta, theta_A, psi] with its time derivatives.

    Attributes
    ----------
    phi, delta : (5,) arrays
        [x, x', x'', x''', x''''] of the link elevation and azimuth [rad, rad/s^k].
    theta_A, psi : (3,) arrays
        [x, x', x''] of the robot tilt and the rotation about z_B [rad, rad/s^k].
        Longer inputs are truncated (a planner may know more derivatives).
    """

    phi: FloatArray
    delta: FloatArray
    theta_A: FloatArray
    psi: FloatArray

    def __post_init__(self) -> None:
        for name, n in zip(("phi", "delta", "theta_A", "psi"), _ORDERS, strict=True):
            v = np.asarray(getattr(self, name), dtype=float).reshape(-1)
            if v.size < n:
                v = np.concatenate((v, np.zeros(n - v.size)))
            object.__setattr__(self, name, v[:n].copy())

    @classmethod
    def planar(cls, phi: ArrayLike, theta_A: ArrayLike, psi: float = 0.0) -> OutputDerivatives:
        """An output in the plane P_M: delta = 0 and a constant psi."""
        return cls(
            phi=np.asarray(phi, dtype=float),
            delta=np.zeros(5),
            theta_A=np.asarray(theta_A, dtype=float),
            psi=np.array([psi, 0.0, 0.0]),
        )

    def as_vector(self) -> FloatArray:
        """The 16 numbers [phi(5), delta(5), theta_A(3), psi(3)]."""
        return np.concatenate((self.phi, self.delta, self.theta_A, self.psi))

    @property
    def value(self) -> FloatArray:
        """y^b = [phi, delta, theta_A, psi] [rad]."""
        return np.array([self.phi[0], self.delta[0], self.theta_A[0], self.psi[0]])


@dataclass(frozen=True)
class NominalState:
    """State and input of the tethered quadrotor that realise an output (flatness).

    Vectors in F_W unless the name says otherwise.

    Attributes
    ----------
    output : OutputDerivatives
    p_W, v_W, a_W : (3,) arrays
        Link end (centre of mass in the model): position [m], velocity [m/s],
        acceleration [m/s^2].
    R_WB : (3, 3) array
        Attitude.
    roll : float
        Roll angle of R_AB = R_y(theta_e) R_x(roll) R_z(psi) [rad] (the chapter's varphi).
    omega_B, omega_dot_B : (3,) arrays
        Angular velocity [rad/s] and acceleration [rad/s^2] in F_B.
    f_R, f_R_dot, f_R_ddot : float
        Total thrust and its derivatives [N, N/s, N/s^2].
    tau_B : (3,) array
        Torque the rotors must produce, F_B [N m].
    rotor_thrusts : (4,) array
        Gamma^-1 [f_R, tau_B], not limited [N].
    tension, tension_dot : float
        Cable tension f_L and its rate [N, N/s].
    """

    output: OutputDerivatives
    p_W: FloatArray
    v_W: FloatArray
    a_W: FloatArray
    R_WB: FloatArray
    roll: float
    omega_B: FloatArray
    omega_dot_B: FloatArray
    f_R: float
    f_R_dot: float
    f_R_ddot: float
    tau_B: FloatArray
    rotor_thrusts: FloatArray
    tension: float
    tension_dot: float

    @property
    def q_WB(self) -> FloatArray:
        """Attitude quaternion (w, x, y, z)."""
        return rotmat_to_quat(self.R_WB)

    @property
    def z_B(self) -> FloatArray:
        """Thrust axis in F_W."""
        return self.R_WB[:, 2]


def _rot_x(a: ca.SX) -> ca.SX:
    c, s = ca.cos(a), ca.sin(a)
    return ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, c, -s), ca.horzcat(0, s, c))


def _rot_y(a: ca.SX) -> ca.SX:
    c, s = ca.cos(a), ca.sin(a)
    return ca.vertcat(ca.horzcat(c, 0, s), ca.horzcat(0, 1, 0), ca.horzcat(-s, 0, c))


def _rot_z(a: ca.SX) -> ca.SX:
    c, s = ca.cos(a), ca.sin(a)
    return ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))


_OUTPUT_NAMES = (
    "p_A", "v_A", "a_A", "R_AB", "roll", "omega_B", "omega_dot_B", "f_R", "f_R_dot",
    "f_R_ddot", "tau_B", "rotor_thrusts", "tension", "tension_dot", "u_z", "cos_s", "cos_delta",
)  # fmt: skip


def _build_function(
    mass: float,
    length: float,
    inertia: FloatArray,
    allocation: FloatArray,
    r_att_B: FloatArray,
    g: float,
) -> ca.Function:
    """The flatness map as a CasADi Function of the 16 output derivatives, the numbers
    built in (the plain form; :func:`_parametric` is the same map with them as inputs)."""
    Y = ca.SX.sym("y", OUTPUT_SIZE)
    r_att = np.asarray(r_att_B, dtype=float)
    outputs = _nominal(
        Y, mass, length, g, ca.DM(inertia), ca.DM(np.linalg.inv(allocation)),
        ca.DM(r_att) if np.any(r_att != 0) else None,
    )  # fmt: skip
    return ca.Function("flatness", [Y], outputs, ["y"], list(_OUTPUT_NAMES))


Structure = tuple[tuple[tuple[int, int], ...], tuple[tuple[int, int], ...], tuple[int, ...]]
"""Where the numbers of a map are not zero: J and Gamma^-1 (row, column) and r_att (row),
each in CasADi's column-major order (:func:`_structure`)."""


def _nonzeros(matrix: FloatArray) -> tuple[tuple[int, int], ...]:
    """(row, column) of the nonzero entries of ``matrix``, column by column."""
    cols, rows = np.nonzero(np.asarray(matrix, dtype=float).T)
    return tuple(zip(rows.tolist(), cols.tolist(), strict=True))


def _structure(
    inertia: FloatArray, allocation_inverse: FloatArray, r_att_B: FloatArray
) -> Structure:
    """The :data:`Structure` of J, Gamma^-1 and r_att."""
    return (
        _nonzeros(inertia),
        _nonzeros(allocation_inverse),
        tuple(int(i) for i in np.flatnonzero(r_att_B)),
    )


def _symbols(name: str, shape: tuple[int, int], where: tuple[tuple[int, int], ...]) -> ca.SX:
    """A symbolic matrix with entries only at ``where`` (structural zeros elsewhere)."""
    rows, cols = [w[0] for w in where], [w[1] for w in where]
    return ca.SX.sym(name, ca.Sparsity.triplet(shape[0], shape[1], rows, cols))


@functools.cache
def _parametric(structure: Structure) -> ca.Function:
    """The map as a Function ``(y (16), p) -> nominal values`` of the numbers
    p = [m, l, g, J, Gamma^-1, r_att] (the nonzeros of each, column by column; see
    :meth:`FlatnessMap.parameters`), built once per :data:`Structure`. Symbols stand only
    where the numbers are not zero, so that its operations are those of
    :func:`_build_function` with the numbers built in (CasADi drops the products with a
    built-in zero; the two give the same bits, tests/test_models_flatness.py)."""
    J_at, G_at, r_at = structure
    Y = ca.SX.sym("y", OUTPUT_SIZE)
    m, length, g = ca.SX.sym("m"), ca.SX.sym("l"), ca.SX.sym("g")
    J, G_inv = _symbols("J", (3, 3), J_at), _symbols("G_inv", (4, 4), G_at)
    r_att = _symbols("r_att", (3, 1), tuple((i, 0) for i in r_at)) if r_at else None
    outputs = _nominal(Y, m, length, g, J, G_inv, r_att)
    p = ca.vertcat(m, length, g, *J.nonzeros(), *G_inv.nonzeros(),
                   *(r_att.nonzeros() if r_att is not None else []))  # fmt: skip
    return ca.Function("flatness_p", [Y, p], outputs, ["y", "p"], list(_OUTPUT_NAMES))


@functools.cache
def _compiled(structure: Structure) -> ca.Function | None:
    """:func:`_parametric` compiled to C (:func:`tetherland.ccode.library`, once per
    structure and machine), or None without a C compiler (the virtual machine then)."""
    if not ccode.available():
        return None
    try:
        path = ccode.library([_parametric(structure)], "flatness", "flatness functions")
        return ca.external("flatness_p", str(path))
    except (OSError, RuntimeError) as err:  # (CasADi raises RuntimeError when loading fails)
        warnings.warn(f"compiled flatness map unavailable ({err}); using CasADi's", stacklevel=3)
        return None


def _nominal(
    Y: ca.SX,
    mass: float | ca.SX,
    length: float | ca.SX,
    g: float | ca.SX,
    J: ca.DM | ca.SX,
    G_inv: ca.DM | ca.SX,
    r_att: ca.DM | ca.SX | None,
) -> list[ca.SX]:
    """The nominal values of the outputs ``Y`` (the map's equations): the numbers m, l, g
    [kg, m, m/s^2], J (3x3), Gamma^-1 (4x4) and r_att (3, or None for no offset), as
    floats and DM matrices or as symbols."""
    phi, delta, th, psi = Y[0:5], Y[5:10], Y[10:13], Y[13:16]
    top = ca.vertcat(phi[4], delta[4], th[2], psi[2])
    Ydot = ca.vertcat(phi[1:5], 0, delta[1:5], 0, th[1:3], 0, psi[1:3], 0)

    def D(e: ca.SX) -> ca.SX:
        # d/dt of an expression of the outputs; the highest derivatives have no derivative.
        if ca.depends_on(e, top):  # pragma: no cover - guards the construction below
            raise AssertionError("flatness: differentiating past the available order")
        return ca.jtimes(e, Y, Ydot)

    cp, sp, cd, sd = ca.cos(phi[0]), ca.sin(phi[0]), ca.cos(delta[0]), ca.sin(delta[0])
    d = ca.vertcat(cd * cp, -sd, cd * sp)
    x_L, y_L, z_L = d, ca.vertcat(cp * sd, cd, sp * sd), ca.vertcat(-sp, 0, cp)
    d1 = D(d)
    d2 = D(d1)
    Q = mass * length * d2 + mass * g * ca.vertcat(0, 0, 1)
    u_z, u_y = ca.dot(z_L, Q), ca.dot(y_L, Q)
    s = phi[0] + th[0]
    u_x = u_z * ca.tan(s) / cd
    tension = u_x - ca.dot(x_L, Q)
    F = u_x * x_L + u_y * y_L + u_z * z_L
    f_R = ca.norm_2(F)
    f_R1 = D(f_R)
    f_R2 = D(f_R1)
    z_B = F / f_R
    theta_e = ca.atan2(z_B[0], z_B[2])
    roll = ca.atan2(-z_B[1], ca.sqrt(z_B[0] ** 2 + z_B[2] ** 2))
    Rz, Rx = _rot_z(psi[0]), _rot_x(roll)
    R_AB = _rot_y(theta_e) @ Rx @ Rz
    omega = (
        Rz.T @ Rx.T @ ca.vertcat(0, 1, 0) * D(theta_e)
        + Rz.T @ ca.vertcat(1, 0, 0) * D(roll)
        + ca.vertcat(0, 0, 1) * psi[1]
    )
    omega_dot = D(omega)
    tau = J @ omega_dot + ca.cross(omega, J @ omega)
    if r_att is not None:
        tau_L = ca.cross(r_att, -tension * (R_AB.T @ d))
        tau = tau - tau_L
    rotors = G_inv @ ca.vertcat(f_R, tau)
    return [
        length * d, length * d1, length * d2, R_AB, roll, omega, omega_dot, f_R, f_R1, f_R2,
        tau, rotors, tension, D(tension), u_z, ca.cos(s), cd,
    ]  # fmt: skip


@dataclass(frozen=True)
class FlatnessMap:
    """Output y^b and derivatives -> nominal state and input of the taut tethered quadrotor.

    :meth:`evaluate_many` is vectorised: the map with the numbers below as its inputs,
    compiled to C once per machine (:func:`_compiled`, CasADi's virtual machine without a
    compiler; the same bits as :attr:`function`, which has them built in): about 5 us per
    sample over a track's 2000; :meth:`evaluate`, one sample, costs about 0.2 ms (CasADi's
    call and the conversions).

    Attributes
    ----------
    mass : float
        m [kg].
    length : float
        Cable length l [m].
    inertia : (3, 3) array
        J in F_B [kg m^2].
    allocation : (4, 4) array
        Gamma (6.19).
    R_WA : (3, 3) array
        Anchor frame.
    p_A : (3,) array
        Anchor point in F_W [m].
    r_att_B : (3,) array
        Cable attachment offset from the centre of mass in F_B [m]; its cable torque is
        compensated in tau_B. Zero (the chapter's model) by default.
    gravity : float
        g [m/s^2].
    """

    mass: float
    length: float
    inertia: FloatArray
    allocation: FloatArray
    R_WA: FloatArray = field(default_factory=lambda: np.eye(3))
    p_A: FloatArray = field(default_factory=lambda: np.zeros(3))
    r_att_B: FloatArray = field(default_factory=lambda: np.zeros(3))
    gravity: float = GRAVITY
    _structure: Structure = field(init=False, repr=False, compare=False)
    _parameters: FloatArray = field(init=False, repr=False, compare=False)
    _function: ca.Function | None = field(init=False, repr=False, compare=False, default=None)

    def __post_init__(self) -> None:
        J = np.asarray(self.inertia, dtype=float)
        object.__setattr__(self, "inertia", np.diag(J) if J.shape == (3,) else J)
        for name in ("allocation", "R_WA", "p_A", "r_att_B"):
            object.__setattr__(self, name, np.asarray(getattr(self, name), dtype=float))
        G_inv = np.linalg.inv(self.allocation)
        structure = _structure(self.inertia, G_inv, self.r_att_B)
        J_at, G_at, r_at = structure
        p = [float(self.mass), float(self.length), float(self.gravity)]
        p += [float(self.inertia[i, j]) for i, j in J_at]
        p += [float(G_inv[i, j]) for i, j in G_at]
        p += [float(self.r_att_B[i]) for i in r_at]
        object.__setattr__(self, "_structure", structure)
        object.__setattr__(self, "_parameters", np.array(p))

    @classmethod
    def from_scenario(
        cls,
        scenario: Scenario,
        *,
        with_cable_offset: bool = False,
        geometry: LandingGeometry | None = None,
    ) -> FlatnessMap:
        """The map for a scenario's vehicle, cable and anchor.

        ``with_cable_offset`` adds the compensation of the cable torque of the attachment
        offset ``vehicle.cable_attachment`` (6.6.5) to tau_B and the rotor thrusts.
        """
        v = scenario.vehicle
        geo = geometry or LandingGeometry.from_scenario(scenario)
        return cls(
            mass=v.mass,
            length=geo.link_length,
            inertia=np.diag(v.inertia),
            allocation=RotorLayout.from_config(v).allocation,
            R_WA=geo.R_WA,
            p_A=geo.p_A,
            r_att_B=np.asarray(v.cable_attachment if with_cable_offset else (0.0, 0.0, 0.0)),
        )

    @property
    def function(self) -> ca.Function:
        """The CasADi Function ``y(16) -> nominal values in F_A``, the map's numbers built in
        (for symbolic reuse; built on first use). :meth:`evaluate_many` evaluates the same
        map with the numbers as inputs (:attr:`parameters`), compiled to C when a compiler
        is there, with the same bits."""
        if self._function is None:
            fn = _build_function(
                self.mass, self.length, self.inertia, self.allocation, self.r_att_B,
                self.gravity,
            )  # fmt: skip
            object.__setattr__(self, "_function", fn)
        assert self._function is not None
        return self._function

    @property
    def parameters(self) -> FloatArray:
        """The numbers of the map as its parametric form takes them: m [kg], l [m],
        g [m/s^2], then the nonzeros of J [kg m^2], Gamma^-1 and r_att [m], each column by
        column (copy)."""
        return self._parameters.copy()

    def evaluate_many(self, outputs: ArrayLike, check: bool = True) -> dict[str, FloatArray]:
        """Vectorised map for an (n, 16) array of :meth:`OutputDerivatives.as_vector` rows.

        Returns arrays with a leading sample axis: ``p_W``, ``v_W``, ``a_W`` (n, 3),
        ``R_WB`` (n, 3, 3), ``roll``, ``f_R``, ``f_R_dot``, ``f_R_ddot``, ``tension``,
        ``tension_dot`` (n,), ``omega_B``, ``omega_dot_B``, ``tau_B`` (n, 3),
        ``rotor_thrusts`` (n, 4).
        """
        Y = np.atleast_2d(np.asarray(outputs, dtype=float))
        if Y.shape[1] != OUTPUT_SIZE:
            raise ValueError(f"outputs must have {OUTPUT_SIZE} columns, got shape {Y.shape}")
        n = Y.shape[0]
        fn = _compiled(self._structure) or _parametric(self._structure)
        if n > 1:  # the samples mapped, the numbers shared
            fn = fn.map("flatness_map", "serial", n, [1], [])
        raw = fn(Y.T, self._parameters)
        vals = {name: np.asarray(r) for name, r in zip(_OUTPUT_NAMES, raw, strict=True)}
        if check:
            self._check(vals, Y)
        R_AB = vals["R_AB"].reshape(3, n, 3).transpose(1, 0, 2)  # [R_0 R_1 ...] -> (n, 3, 3)
        out: dict[str, FloatArray] = {
            "p_W": self.p_A + (self.R_WA @ vals["p_A"]).T,
            "v_W": (self.R_WA @ vals["v_A"]).T,
            "a_W": (self.R_WA @ vals["a_A"]).T,
            "R_WB": np.einsum("ij,njk->nik", self.R_WA, R_AB),
        }
        for name in ("omega_B", "omega_dot_B", "tau_B", "rotor_thrusts"):
            out[name] = vals[name].T
        for name in ("roll", "f_R", "f_R_dot", "f_R_ddot", "tension", "tension_dot"):
            out[name] = vals[name].reshape(n)
        return out

    def evaluate(self, output: OutputDerivatives, check: bool = True) -> NominalState:
        """Nominal state and input for one output sample.

        Raises
        ------
        SingularityError
            At a singular output (see the module docstring), unless ``check`` is False.
        """
        v = self.evaluate_many(output.as_vector()[None, :], check=check)
        return NominalState(
            output=output,
            p_W=v["p_W"][0],
            v_W=v["v_W"][0],
            a_W=v["a_W"][0],
            R_WB=v["R_WB"][0],
            roll=float(v["roll"][0]),
            omega_B=v["omega_B"][0],
            omega_dot_B=v["omega_dot_B"][0],
            f_R=float(v["f_R"][0]),
            f_R_dot=float(v["f_R_dot"][0]),
            f_R_ddot=float(v["f_R_ddot"][0]),
            tau_B=v["tau_B"][0],
            rotor_thrusts=v["rotor_thrusts"][0],
            tension=float(v["tension"][0]),
            tension_dot=float(v["tension_dot"][0]),
        )

    @staticmethod
    def _check(vals: dict[str, FloatArray], Y: FloatArray) -> None:
        u_z, cos_s, cos_d = (vals[k].reshape(-1) for k in ("u_z", "cos_s", "cos_delta"))
        bad = (
            (u_z <= SINGULAR_TOL)
            | (np.abs(cos_s) <= SINGULAR_TOL)
            | (np.abs(cos_d) <= SINGULAR_TOL)
        )
        bad |= ~np.isfinite(vals["rotor_thrusts"]).all(axis=0)
        if np.any(bad):
            i = int(np.argmax(bad))
            raise SingularityError(
                f"flatness map singular at output sample {i} (phi = {np.degrees(Y[i, 0]):.2f} deg, "
                f"theta_A = {np.degrees(Y[i, 10]):.2f} deg): u_z = {u_z[i]:.3g} N, "
                f"cos(phi + theta_A) = {cos_s[i]:.3g}, cos(delta) = {cos_d[i]:.3g}"
            )
