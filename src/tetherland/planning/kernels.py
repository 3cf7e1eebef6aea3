"""Compiled (numba) kernels of the planner, each beside its plain reference.

:func:`interval_ends` integrates the rotor-form model (6.20) over every shooting interval
from its node with the input held: the shooting gaps of the online re-plan's node check
(:func:`tetherland.planning.verify.verify_nodes`) in a few microseconds, where the same
integration through CasADi or numpy costs 0.1-0.2 ms of conversions and small-array
overhead. The plain reference is :func:`interval_ends_reference`: the model's own numpy
right-hand side (:meth:`ExtendedPlanarModel.rhs`) stepped by the project's one RK4
(:func:`tetherland.models.integrators.rk4`); a test checks that both agree.
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
    c = [m, l, J_y, g, torque_row (4), r_x, r_z]; tau = torque_row . f is the net torque."""
    f_R = x[4] + x[5] + x[6] + x[7]
    tau = c[4] * x[4] + c[5] * x[5] + c[6] * x[6] + c[7] * x[7]
    ct, st = math.cos(x[1]), math.sin(x[1])
    rx = ct * c[8] + st * c[9]
    rz = -st * c[8] + ct * c[9]
    cp, sp = math.cos(x[0]), math.sin(x[0])
    a = -sp * rz - cp * rx
    b = cp * rz - sp * rx
    ddtheta = tau / c[2]
    out[0] = x[2]
    out[1] = x[3]
    out[2] = (
        -c[3] / c[1] * cp
        + math.cos(x[0] + x[1]) * f_R / (c[0] * c[1])
        + (a * ddtheta - b * x[3] * x[3]) / c[1]
    )
    out[3] = ddtheta
    for i in range(4):
        out[4 + i] = x[8 + i]
        out[8 + i] = u[i]


@njit(cache=True)
def interval_ends(
    X: np.ndarray, U: np.ndarray, h: np.ndarray, steps: int, c: np.ndarray
) -> np.ndarray:
    """States (N, 12) at the end of every interval k, from X[k] with U[k] held for h[k]
    in ``steps`` RK4 steps (rotor form; c = ``PlanarParams.coefficients``)."""
    N = U.shape[0]
    ends = np.empty((N, 12))
    k1, k2, k3, k4 = np.empty(12), np.empty(12), np.empty(12), np.empty(12)
    z = np.empty(12)
    for k in range(N):
        x = X[k].copy()
        dt = h[k] / steps
        for _ in range(steps):
            _rotor_rhs(x, U[k], c, k1)
            z[:] = x + 0.5 * dt * k1
            _rotor_rhs(z, U[k], c, k2)
            z[:] = x + 0.5 * dt * k2
            _rotor_rhs(z, U[k], c, k3)
            z[:] = x + dt * k3
            _rotor_rhs(z, U[k], c, k4)
            x = x + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)
        ends[k] = x
    return ends


def interval_ends_reference(
    model: ExtendedPlanarModel, X: FloatArray, U: FloatArray, h: FloatArray, steps: int
) -> FloatArray:
    """:func:`interval_ends` with the numpy model and the generic RK4 (the reference)."""
    x = X[:-1].T
    for _ in range(steps):
        x = rk4(model.rhs, x, U.T, h / steps)
    return np.ascontiguousarray(x.T)
