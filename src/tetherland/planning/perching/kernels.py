"""Compiled reference of a perching maneuver at one time: the tracker's rows of a tick.

The contact-free method asks its planned maneuver for the tracker's rows at every control
tick (:meth:`~tetherland.planning.perching.trajectory.FreeFlightTrajectory.reference_at`).
The plain path, :meth:`~tetherland.planning.perching.trajectory.FreeFlightTrajectory.sample`,
does it with numpy on one-sample arrays: the table entry before ``t``
(:meth:`~tetherland.planning.shooting.HeldInputMotion.states`), one partial RK4 step of
the planar model (:func:`~tetherland.planning.perching.model.rhs`, with the rotor drag the
plan modelled), the drag-free closed forms of the acceleration, jerk and snap
(:func:`~tetherland.planning.perching.model.flat_derivatives`) and the rotation into F_W.
:func:`reference_into` is the same arithmetic, operation for operation in the same order,
in one compiled call (a test checks the bits against ``sample``); it took a quarter of
the CPU of a contact-free campaign run in numpy's per-call overhead.

Packed constants ``c`` (:data:`C_WIDTH` floats, :func:`pack`): [m, J_y, g, d_x (0: the
drag-free model), sub, A (3x2, row-major: the columns x_A and z_W of R_WA), p_L (3)].
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.geometry import FloatArray

NX = 10
"""Planar states [p_x, p_z, theta, v_x, v_z, omega, f_R, tau, f_R', tau'] (model.py)."""
C_MASS, C_INERTIA, C_GRAVITY, C_DRAG, C_SUB, C_A, C_P_L = 0, 1, 2, 3, 4, 5, 11
C_WIDTH = 14
"""Floats in the packed constants (module doc)."""


def pack(
    mass: float, inertia: float, gravity: float, drag: float, sub: int, R_WA: FloatArray,
    p_L: FloatArray,
) -> FloatArray:  # fmt: skip
    """The packed constants ``c`` of :func:`reference_into` (module doc)."""
    c = np.empty(C_WIDTH)
    c[C_MASS], c[C_INERTIA], c[C_GRAVITY], c[C_DRAG] = mass, inertia, gravity, drag
    c[C_SUB] = sub
    c[C_A : C_A + 6] = np.asarray(R_WA, dtype=float)[:, [0, 2]].reshape(6)
    c[C_P_L : C_P_L + 3] = p_L
    return c


@njit(cache=True)
def _rhs_into(x: np.ndarray, u0: float, u1: float, c: np.ndarray, out: np.ndarray) -> None:
    """x' of the planar model (:func:`~tetherland.planning.perching.model.rhs` with, for
    d_x > 0, :func:`~tetherland.planning.perching.model.drag_terms`), the same operations."""
    mass, inertia, gravity, drag = c[C_MASS], c[C_INERTIA], c[C_GRAVITY], c[C_DRAG]
    th, F = x[2], x[6]
    s_th, c_th = math.sin(th), math.cos(th)
    out[0], out[1], out[2] = x[3], x[4], x[5]
    if drag > 0.0:
        scale = math.sqrt(F / (mass * gravity))
        k = -drag * scale * (x[3] * c_th - x[4] * s_th) / mass
        out[3] = F * s_th / mass + k * c_th
        out[4] = F * c_th / mass - gravity + -k * s_th
    else:
        out[3] = F * s_th / mass
        out[4] = F * c_th / mass - gravity
    out[5] = x[7] / inertia
    out[6], out[7], out[8], out[9] = x[8], x[9], u0, u1


@njit(cache=True)
def reference_into(
    t: float, times: np.ndarray, table: np.ndarray, U: np.ndarray, c: np.ndarray,
    out: np.ndarray,
) -> float:  # fmt: skip
    """The tracker's rows at ``t`` [s] into ``out`` (5, 3) [p, v, a, jerk, snap] in F_W;
    returns the collective thrust f_R [N].

    ``times`` (N+1,), ``table`` (N, sub, 10) and ``U`` (N, 2) are the motion's
    (:class:`~tetherland.planning.shooting.HeldInputMotion`), ``c`` :func:`pack`'s.
    Outside [0, T] the end state is held with zero rates, inputs and derivatives.
    """
    N = len(times) - 1
    T = times[N]
    outside = t < 0.0 or t > T
    tc = min(max(t, 0.0), T)
    k = np.searchsorted(times, tc, side="right") - 1
    k = min(max(k, 0), N - 1)
    sub = int(c[C_SUB])
    h_sub = (times[k + 1] - times[k]) / sub
    j = math.floor((tc - times[k]) / h_sub)
    j = min(max(j, 0), sub - 1)
    x = table[k, j].copy()
    u0, u1 = U[k, 0], U[k, 1]
    h = tc - (times[k] + j * h_sub)
    if h > 0.0:  # (on a substep the table entry itself)
        k1, k2, k3, k4 = np.empty(NX), np.empty(NX), np.empty(NX), np.empty(NX)
        y = np.empty(NX)
        half = 0.5 * h
        _rhs_into(x, u0, u1, c, k1)
        for i in range(NX):
            y[i] = x[i] + half * k1[i]
        _rhs_into(y, u0, u1, c, k2)
        for i in range(NX):
            y[i] = x[i] + half * k2[i]
        _rhs_into(y, u0, u1, c, k3)
        for i in range(NX):
            y[i] = x[i] + h * k3[i]
        _rhs_into(y, u0, u1, c, k4)
        sixth = h / 6.0
        for i in range(NX):
            x[i] = x[i] + sixth * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    if outside:
        x[3] = x[4] = x[5] = 0.0
        x[7] = x[8] = x[9] = 0.0
        u0 = 0.0
    # the drag-free closed forms (flat_derivatives without drag), plane (x_A, z_W) rows
    mass, gravity = c[C_MASS], c[C_GRAVITY]
    th, om, F, dF = x[2], x[5], x[6], x[8]
    om_dot = x[7] / c[C_INERTIA]
    zx, zz = math.sin(th), math.cos(th)
    xx, xz = math.cos(th), -math.sin(th)
    plane = np.empty((5, 2))
    plane[0, 0], plane[0, 1] = x[0], x[1]
    plane[1, 0], plane[1, 1] = x[3], x[4]
    a = F / mass
    plane[2, 0], plane[2, 1] = a * zx, a * zz - gravity
    a, b = dF / mass, F * om / mass
    plane[3, 0], plane[3, 1] = a * zx + b * xx, a * zz + b * xz
    a, b = (u0 - F * om * om) / mass, (2.0 * dF * om + F * om_dot) / mass
    plane[4, 0], plane[4, 1] = a * zx + b * xx, a * zz + b * xz
    if outside:
        for r in range(2, 5):
            plane[r, 0] = plane[r, 1] = 0.0
    for r in range(5):
        for i in range(3):
            out[r, i] = c[C_A + 2 * i] * plane[r, 0] + c[C_A + 2 * i + 1] * plane[r, 1]
    for i in range(3):
        out[0, i] += c[C_P_L + i]
    return F
