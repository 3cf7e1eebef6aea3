"""Compiled DFL law Gamma_DFL^b (docs/theory.md section 7) beside its plain reference.

:func:`dfl_into` is one controller update: the thrust extension integrated, the Lie
derivatives of :func:`tetherland.control.dfl.dfl_expression` from the generated kernel
(:mod:`tetherland.control.dfl_terms`), u = A^-1 (v - b), the cable-offset torque
(6.6.5) and the mixer (:func:`tetherland.control.kernels.mix_into`).
:func:`dfl_reference` does the same with the CasADi function and numpy; a property test
checks both to 1e-9.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.control.common import cable_torque
from tetherland.control.dfl_model import DFL_RELATIVE_DEGREES, dfl_function
from tetherland.control.dfl_terms import dfl_terms_into
from tetherland.control.kernels import (
    cancel_cable_torque,
    mix_into,
    mix_reference,
    quat_rotmat3,
    remainder,
    tmul3,
)
from tetherland.geometry import FloatArray, link_frame
from tetherland.models.quadrotor import RotorLayout, RotorModel
from tetherland.rotations import quat_to_rotmat

DFL_OFFSETS = (0, 4, 8, 10)  # start of each output's derivatives in y (12)
DFL_WIDTH = 43
"""mass, integral (0/1), integral max, compensate, control period h, r_att (3), R_WA (9),
gains k (12, in the order of y), integral gains (4), thrust share dF_i/df_R (4), model p (6)."""
DFL_STATE_WIDTH = 11  # f_R, f_R', t_last (NaN: none), last u (4), error integrals (4)
DFL_OUT_WIDTH = 15  # mixer (9), e_phi, e_delta, e_theta_A, e_psi, singular, decoupling ratio
DFL_ERRORS, DFL_SINGULAR, DFL_RATIO = slice(9, 13), 13, 14
HADAMARD_MIN = 1e-9
"""|det A| / prod(||row_i||) below which the decoupling matrix counts as singular (the ratio
is 1 for orthogonal rows and 0 for dependent ones; cheaper than a condition number)."""


def dfl_state() -> FloatArray:
    """A reset DFL ``state``: thrust extension unset (NaN), no integral."""
    s = np.zeros(DFL_STATE_WIDTH)
    s[0] = s[2] = math.nan
    return s


def _dfl_attitude(R_AB: FloatArray) -> tuple[float, float, float]:
    """(theta_e, roll, psi) of R_AB = R_y(theta_e) R_x(roll) R_z(psi)."""
    zx, zy, zz = R_AB[0, 2], R_AB[1, 2], R_AB[2, 2]
    ax, ay, az = R_AB[0, 0], R_AB[1, 0], R_AB[2, 0]
    theta_e = math.atan2(zx, zz)
    roll = math.atan2(-zy, math.hypot(zx, zz))
    c_t, s_t, c_r, s_r = math.cos(theta_e), math.sin(theta_e), math.cos(roll), math.sin(roll)
    # psi from R_AB = M R_z(psi), M = R_y(theta_e) R_x(roll): columns 0, 1 of M dotted with
    # the first column of R_AB
    psi = math.atan2(s_t * s_r * ax + c_r * ay + c_t * s_r * az, c_t * ax - s_t * az)
    return theta_e, roll, psi


_dfl_attitude_compiled = njit(cache=True)(_dfl_attitude)


def dfl_reference(
    t: float,
    link: FloatArray,
    q_WB: FloatArray,
    omega_B: FloatArray,
    Y: FloatArray,
    tension: float,
    state: FloatArray,
    par: FloatArray,
    layout: RotorLayout,
    rotors: RotorModel,
) -> FloatArray:
    """Gamma_DFL^b (docs/theory.md section 7), plain, with the CasADi terms; see
    :mod:`tetherland.control.dfl` for the equations. ``Y`` rows y_d .. y_d'''' (5, 4),
    ``state`` updated in place (its thrust extension must be set). Returns ``out``
    (:data:`DFL_OUT_WIDTH`)."""
    integral, lim, compensate, h = par[1], par[2], par[3], par[4]
    r_att, R_WA = par[5:8], par[8:17].reshape(3, 3)
    K, k_int, share, p = par[17:29], par[29:33], par[33:37], par[37:43]
    f, fd = state[0], state[1]
    dt = 0.0
    if not math.isnan(state[2]):  # integrate the extension with the last f_R''
        dt = t - state[2]
        u0 = state[3]
        f, fd = f + fd * dt + 0.5 * u0 * dt * dt, fd + u0 * dt
    state[0], state[1], state[2] = f, fd, t
    R = quat_to_rotmat(q_WB)
    theta_e, roll, psi = _dfl_attitude(R_WA.T @ R)
    x = np.array([*link, theta_e, roll, psi, *omega_B, f, fd])
    packed = np.asarray(dfl_function()(x, p)).ravel()
    y_all, A, b = packed[:12], packed[12:28].reshape(4, 4), packed[28:32]
    v, e0 = np.empty(4), np.empty(4)
    for j, (i, r) in enumerate(zip(DFL_OFFSETS, DFL_RELATIVE_DEGREES, strict=True)):
        e = Y[:r, j] - y_all[i : i + r]
        if j == 3:
            e[0] = math.remainder(e[0], 2 * math.pi)
        v[j] = Y[r, j] + K[i : i + r] @ e
        e0[j] = e[0]
    if integral:
        state[7:11] = np.clip(state[7:11] + e0 * dt, -lim, lim)
        v += k_int * state[7:11]
    ratio = abs(np.linalg.det(A)) / float(np.prod(np.sqrt((A * A).sum(axis=1))))
    singular = not ratio >= HADAMARD_MIN
    u = np.array([0.0, *state[4:7]]) if singular else np.linalg.solve(A, v - b)
    state[3:7] = u
    tau = u[1:4].copy()
    if compensate and tension > 0.0:
        d_B = R.T @ (R_WA @ link_frame(link[0], link[1])[:, 0])
        tau = tau - cable_torque(r_att, tension, d_B)
    # the rotors hold the command for one period: the mean of the thrust polynomial over
    # it, f + f' h/2 + f'' h^2/6; the motor lag is led along f_R'
    thrust = f + 0.5 * fd * h + u[0] * h * h / 6.0
    rates = share * (fd + 0.5 * u[0] * h)
    out = np.zeros(DFL_OUT_WIDTH)
    out[0:9] = mix_reference(np.concatenate(([max(thrust, 0.0)], tau)), rates, layout, rotors)
    out[DFL_ERRORS], out[DFL_SINGULAR], out[DFL_RATIO] = e0, float(singular), ratio
    return out


@njit(cache=True)
def _lu4_solve(A: FloatArray, b: FloatArray) -> tuple[float, FloatArray]:
    """det(A) and A^-1 b by Gaussian elimination with partial pivoting (as LAPACK getrf)."""
    M = A.copy()
    x = b.copy()
    n = 4
    det = 1.0
    for c in range(n):
        piv = c
        for r in range(c + 1, n):
            if abs(M[r, c]) > abs(M[piv, c]):
                piv = r
        if piv != c:
            det = -det
            for k in range(n):
                M[c, k], M[piv, k] = M[piv, k], M[c, k]
            x[c], x[piv] = x[piv], x[c]
        d = M[c, c]
        det *= d
        if d == 0.0:
            return 0.0, x
        for r in range(c + 1, n):
            m = M[r, c] / d
            for k in range(c + 1, n):
                M[r, k] -= m * M[c, k]
            x[r] -= m * x[c]
    for r in range(n - 1, -1, -1):
        acc = x[r]
        for k in range(r + 1, n):
            acc -= M[r, k] * x[k]
        x[r] = acc / M[r, r]
    return det, x


@njit(cache=True)
def dfl_into(
    t: float,
    link: FloatArray,
    q_WB: FloatArray,
    omega_B: FloatArray,
    Y: FloatArray,
    tension: float,
    state: FloatArray,
    par: FloatArray,
    mix: FloatArray,
    out: FloatArray,
) -> None:
    """Compiled :func:`dfl_reference`, with the generated terms
    (:func:`tetherland.control.dfl_terms.dfl_terms_into`)."""
    f, fd = state[0], state[1]
    dt = 0.0
    if state[2] == state[2]:
        dt = t - state[2]
        u0 = state[3]
        f, fd = f + fd * dt + 0.5 * u0 * dt * dt, fd + u0 * dt
    state[0], state[1], state[2] = f, fd, t
    R = quat_rotmat3(q_WB)
    R_WA = par[8:17].reshape(3, 3)
    theta_e, roll, psi = _dfl_attitude_compiled(tmul3(R_WA, R))
    x = np.empty(12)
    x[0], x[1], x[2], x[3] = link[0], link[1], link[2], link[3]
    x[4], x[5], x[6] = theta_e, roll, psi
    x[7], x[8], x[9] = omega_B[0], omega_B[1], omega_B[2]
    x[10], x[11] = f, fd
    terms = np.empty(32)
    dfl_terms_into(x, par[37:43], terms)
    v = np.empty(4)
    for j in range(4):
        i, r = DFL_OFFSETS[j], DFL_RELATIVE_DEGREES[j]
        acc = 0.0
        for d in range(r):
            e = Y[d, j] - terms[i + d]
            if d == 0:
                if j == 3:
                    e = remainder(e, 2.0 * math.pi)
                out[9 + j] = e
            acc += par[17 + i + d] * e
        v[j] = Y[r, j] + acc
    if par[1] != 0.0:
        lim = par[2]
        for j in range(4):
            state[7 + j] = min(max(state[7 + j] + out[9 + j] * dt, -lim), lim)
            v[j] += par[29 + j] * state[7 + j]
    A = terms[12:28].reshape(4, 4)
    rows = 1.0
    for i in range(4):
        rows *= math.sqrt(A[i, 0] ** 2 + A[i, 1] ** 2 + A[i, 2] ** 2 + A[i, 3] ** 2)
    for j in range(4):
        v[j] -= terms[28 + j]  # v - b
    det, u = _lu4_solve(A, v)
    ratio = abs(det) / rows
    singular = not ratio >= HADAMARD_MIN
    if singular:  # hold f_R'' = 0 and the last torque
        u[0] = 0.0
        for i in range(1, 4):
            u[i] = state[3 + i]
    for i in range(4):
        state[3 + i] = u[i]
    t0, t1, t2 = u[1], u[2], u[3]
    if par[3] != 0.0 and tension > 0.0:
        phi, delta = link[0], link[1]
        cd = math.cos(delta)
        t0, t1, t2 = cancel_cable_torque(
            t0, t1, t2, R, R_WA, cd * math.cos(phi), -math.sin(delta), cd * math.sin(phi),
            tension, par[5], par[6], par[7],
        )  # fmt: skip
    h = par[4]
    thrust = f + 0.5 * fd * h + u[0] * h * h / 6.0
    lead = fd + 0.5 * u[0] * h
    rates = np.empty(4)
    for i in range(4):
        rates[i] = par[33 + i] * lead
    mix_into(max(thrust, 0.0), t0, t1, t2, rates, True, mix, out)
    out[DFL_SINGULAR] = 1.0 if singular else 0.0
    out[DFL_RATIO] = ratio


def pack_dfl(
    mass: float,
    integral: bool,
    integral_max: float,
    compensate: bool,
    control_dt: float,
    r_att_B: FloatArray,
    R_WA: FloatArray,
    gains: list[FloatArray],
    integral_gains: list[float],
    thrust_share: FloatArray,
    model: FloatArray,
) -> FloatArray:
    """``par`` of :func:`dfl_into` (see :data:`DFL_WIDTH`); ``gains`` k_0..k_{r-1} per output."""
    head = [mass, float(integral), integral_max, float(compensate), control_dt]
    R = np.asarray(R_WA, dtype=float).reshape(9)
    k = np.concatenate(gains)
    return np.concatenate((head, r_att_B, R, k, integral_gains, thrust_share, model)).astype(float)
