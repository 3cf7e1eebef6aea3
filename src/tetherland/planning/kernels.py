"""Compiled (numba) kernels of the planner, each beside its plain reference.

The rotor-form model (6.20) with the attachment offset (docs/theory.md (4.20)) integrated
with the input held, in the project's one RK4 (:func:`tetherland.models.integrators.rk4`):

* :func:`interval_ends`: every shooting interval from its node, the shooting gaps of the
  online re-plan's node check (:func:`tetherland.planning.verify.verify_nodes`);
* :func:`held_input`: the state after every substep of every interval, integrated
  through all intervals from the initial state (the planner's independent
  re-simulation) or restarted at every node (a solution read from a file);
* :func:`rk4_rows`: one RK4 step from each of many states (the partial step of a dense
  sample).

Each costs microseconds where the same integration through CasADi or numpy costs
milliseconds of conversions and small-array overhead. The plain references are the
model's numpy right-hand side (:meth:`ExtendedPlanarModel.rhs`) stepped by the generic
RK4 (:func:`interval_ends_reference`) and the CasADi chains of
:class:`~tetherland.planning.shooting.HeldInputSimulator` on
:func:`~tetherland.models.planar.parametric_rk4_step`; tests check that they agree.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.geometry import FloatArray
from tetherland.models.integrators import rk4
from tetherland.models.planar import ExtendedPlanarModel


@njit(cache=True)
def _rotor_rhs(x: np.ndarray, u: np.ndarray, c: np.ndarray, out: np.ndarray) -> None:
    """(6.18), (6.20) in rotor form with the attachment offset (docs/theory.md (4.20)),
    c = [m, l, J_y, g, torque_row (4), r_x, r_z]; tau = torque_row . f is the net torque;
    the arms (4.13) a = -(r_x cos s + r_z sin s), b = r_z cos s - r_x sin s."""
    f_R = x[4] + x[5] + x[6] + x[7]
    tau = c[4] * x[4] + c[5] * x[5] + c[6] * x[6] + c[7] * x[7]
    cs, ss = math.cos(x[0] + x[1]), math.sin(x[0] + x[1])
    a = -(c[8] * cs + c[9] * ss)
    b = c[9] * cs - c[8] * ss
    ddtheta = tau / c[2]
    out[0] = x[2]
    out[1] = x[3]
    out[2] = (
        -c[3] / c[1] * math.cos(x[0])
        + cs * f_R / (c[0] * c[1])
        + (a * ddtheta - b * x[3] * x[3]) / c[1]
    )
    out[3] = ddtheta
    for i in range(4):
        out[4 + i] = x[8 + i]
        out[8 + i] = u[i]


@njit(cache=True)
def _rk4_into(x: np.ndarray, u: np.ndarray, h: float, c: np.ndarray, work: np.ndarray) -> None:
    """One RK4 step of :func:`_rotor_rhs` from ``x`` in place (``work`` (5, 12) scratch),
    in the arithmetic of :func:`tetherland.models.integrators.rk4`."""
    k1, k2, k3, k4, z = work[0], work[1], work[2], work[3], work[4]
    _rotor_rhs(x, u, c, k1)
    for i in range(12):
        z[i] = x[i] + 0.5 * h * k1[i]
    _rotor_rhs(z, u, c, k2)
    for i in range(12):
        z[i] = x[i] + 0.5 * h * k2[i]
    _rotor_rhs(z, u, c, k3)
    for i in range(12):
        z[i] = x[i] + h * k3[i]
    _rotor_rhs(z, u, c, k4)
    for i in range(12):
        x[i] = x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@njit(cache=True)
def held_input(
    X: np.ndarray, U: np.ndarray, h: np.ndarray, sub: int, c: np.ndarray, through: bool
) -> np.ndarray:
    """States (N, sub, 12) after every one of ``sub`` equal RK4 substeps of every interval
    k with U[k] held for h[k] [s] (c = ``PlanarParams.coefficients``): each interval
    started at its node X[k], or ``through`` all intervals from X[0] (each starting where
    the previous one ended)."""
    N = U.shape[0]
    ends = np.empty((N, sub, 12))
    work = np.empty((5, 12))
    x = X[0].copy()
    for k in range(N):
        if not through:
            x[:] = X[k]
        dt = h[k] / sub
        for j in range(sub):
            _rk4_into(x, U[k], dt, c, work)
            ends[k, j] = x
    return ends


@njit(cache=True)
def interval_ends(
    X: np.ndarray, U: np.ndarray, h: np.ndarray, steps: int, c: np.ndarray
) -> np.ndarray:
    """States (N, 12) at the end of every interval k, from X[k] with U[k] held for h[k]
    in ``steps`` RK4 steps (rotor form; c = ``PlanarParams.coefficients``)."""
    return held_input(X, U, h, steps, c, False)[:, steps - 1].copy()


@njit(cache=True)
def rk4_rows(x: np.ndarray, u: np.ndarray, h: np.ndarray, c: np.ndarray) -> np.ndarray:
    """One RK4 step of length h[i] [s] from every state x[i] (n, 12) under u[i] (n, 4)."""
    out = x.copy()
    work = np.empty((5, 12))
    for i in range(x.shape[0]):
        _rk4_into(out[i], u[i], h[i], c, work)
    return out


def interval_ends_reference(
    model: ExtendedPlanarModel, X: FloatArray, U: FloatArray, h: FloatArray, steps: int
) -> FloatArray:
    """:func:`interval_ends` with the numpy model and the generic RK4 (the reference)."""
    x = X[:-1].T
    for _ in range(steps):
        x = rk4(model.rhs, x, U.T, h / steps)
    return np.ascontiguousarray(x.T)
