"""The dynamic-feedback-linearising tethered law Gamma_DFL^b (docs/theory.md section 7),
plain and compiled side by side.

:func:`dfl_reference` is the readable law: the Lie derivatives from the CasADi function
(:func:`tetherland.control.kernels.dfl_model.dfl_function`), u = A^-1 (v - b) with numpy,
the cable-offset torque (6.6.5) and the mixer. :func:`dfl_into` is the same law compiled,
one call per control tick, with the Lie derivatives from the kernel generated from that
function (:mod:`tetherland.control.kernels.dfl_terms`). Both read the gains and model
packed by :func:`pack_dfl` at the ``PAR_*`` fields, keep their memory at the ``STATE_*``
fields (:func:`dfl_state`) and write the ``OUT_*`` fields of ``out``. The controller is
:class:`tetherland.control.DflController`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.control.kernels import mixer, so3
from tetherland.control.kernels.dfl_model import (
    DFL_RELATIVE_DEGREES,
    MODEL_PARAMETERS,
    YAB_A,
    YAB_B,
    YAB_WIDTH,
    YAB_Y,
    dfl_function,
)
from tetherland.control.kernels.dfl_terms import dfl_terms_into
from tetherland.control.kernels.packing import Fields
from tetherland.geometry import FloatArray, link_frame
from tetherland.models.quadrotor import RotorLayout, RotorModel
from tetherland.rotations import quat_to_rotmat

DFL_OFFSETS = tuple(sum(DFL_RELATIVE_DEGREES[:j]) for j in range(len(DFL_RELATIVE_DEGREES)))
"""Start of each output's derivatives in y (12): the running sums of the relative degrees."""
HADAMARD_MIN = 1e-9
"""|det A| / prod(||row_i||) below which the decoupling matrix counts as singular (the ratio
is 1 for orthogonal rows and 0 for dependent ones; cheaper than a condition number)."""

# ------------------------------------------------------------------ par: gains and model
_par = Fields()
PAR_MASS = _par.scalar()
"""m [kg]."""
PAR_INTEGRAL = _par.scalar()
"""1: integral action on the output errors."""
PAR_INTEGRAL_MAX = _par.scalar()
"""Bound of each error integral [rad s]."""
PAR_PERIOD = _par.scalar()
"""Control period h [s]: the rotors hold each command that long."""
PAR_CABLE = _par.vector(so3.CABLE_WIDTH)
"""The cable's geometry (:func:`tetherland.control.kernels.so3.pack_cable`)."""
PAR_GAINS = _par.vector(sum(DFL_RELATIVE_DEGREES))
"""Gains k_0 .. k_{r-1} of each output, in the order of y (:data:`DFL_OFFSETS`)."""
PAR_INTEGRAL_GAINS = _par.vector(4)
"""Integral gain of each output."""
PAR_THRUST_SHARE = _par.vector(4)
"""dF_i/df_R: each rotor's share of the total thrust [-]."""
PAR_MODEL = _par.vector(len(MODEL_PARAMETERS))
"""The model's parameters p (:data:`tetherland.control.kernels.dfl_model.MODEL_PARAMETERS`)."""
PAR_WIDTH = _par.width

# ------------------------------------------------------------------ state: the memory
_state = Fields()
STATE_THRUST = _state.scalar()
"""Thrust extension f_R [N] (NaN: unset)."""
STATE_THRUST_RATE = _state.scalar()
"""Thrust extension f_R' [N/s]."""
STATE_T_LAST = _state.scalar()
"""Time of the last update [s] (NaN: none)."""
STATE_U = _state.vector(4)
"""Last input u = [f_R'' [N/s^2], tau_B [N m]] (the torque is held through singularities)."""
STATE_INTEGRAL = _state.vector(4)
"""Integrals of the output errors [rad s]."""
STATE_WIDTH = _state.width

# ------------------------------------------------------------------ out: after the mixer's
_out = Fields(mixer.OUT_WIDTH)
OUT_ERRORS = _out.vector(4)
"""Errors e_phi, e_delta, e_theta_A, e_psi (desired - actual) [rad]."""
OUT_SINGULAR = _out.scalar()
"""1 when A is singular (f_R'' = 0 and the last torque are held)."""
OUT_RATIO = _out.scalar()
"""Hadamard ratio of A [-] (:data:`HADAMARD_MIN`)."""
OUT_WIDTH = _out.width


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
    """``par`` of :func:`dfl_into` (:data:`PAR_WIDTH`): mass [kg], integral action on or off,
    the integral bound [rad s], whether to cancel the cable torque, the control period [s],
    r_att in F_B [m], R_WA, ``gains`` k_0..k_{r-1} per output, the integral gains, each
    rotor's thrust share dF_i/df_R and the model parameters p
    (:func:`tetherland.control.kernels.dfl_model.model_parameters`)."""
    par = np.empty(PAR_WIDTH)
    par[PAR_MASS], par[PAR_INTEGRAL], par[PAR_INTEGRAL_MAX] = mass, float(integral), integral_max
    par[PAR_PERIOD] = control_dt
    par[PAR_CABLE] = so3.pack_cable(compensate, r_att_B, R_WA)
    par[PAR_GAINS] = np.concatenate(gains)
    par[PAR_INTEGRAL_GAINS] = integral_gains
    par[PAR_THRUST_SHARE] = thrust_share
    par[PAR_MODEL] = model
    return par


def dfl_state() -> FloatArray:
    """A reset ``state`` of :func:`dfl_into`: thrust extension unset (NaN), no integral."""
    s = np.zeros(STATE_WIDTH)
    s[STATE_THRUST] = s[STATE_T_LAST] = math.nan
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
    (:data:`OUT_WIDTH`)."""
    lim, h = par[PAR_INTEGRAL_MAX], par[PAR_PERIOD]
    cable = par[PAR_CABLE]
    R_WA = cable[so3.CABLE_R_WA].reshape(3, 3)
    K, k_int = par[PAR_GAINS], par[PAR_INTEGRAL_GAINS]
    share, p = par[PAR_THRUST_SHARE], par[PAR_MODEL]
    f, fd = state[STATE_THRUST], state[STATE_THRUST_RATE]
    dt = 0.0
    if not math.isnan(state[STATE_T_LAST]):  # integrate the extension with the last f_R''
        dt = t - state[STATE_T_LAST]
        u0 = state[STATE_U][0]
        f, fd = f + fd * dt + 0.5 * u0 * dt * dt, fd + u0 * dt
    state[STATE_THRUST], state[STATE_THRUST_RATE], state[STATE_T_LAST] = f, fd, t
    R = quat_to_rotmat(q_WB)
    theta_e, roll, psi = _dfl_attitude(R_WA.T @ R)
    x = np.array([*link, theta_e, roll, psi, *omega_B, f, fd])
    packed = np.asarray(dfl_function()(x, p)).ravel()
    y_all, A, b = packed[YAB_Y], packed[YAB_A].reshape(4, 4), packed[YAB_B]
    v, e0 = np.empty(4), np.empty(4)
    for j, (i, r) in enumerate(zip(DFL_OFFSETS, DFL_RELATIVE_DEGREES, strict=True)):
        e = Y[:r, j] - y_all[i : i + r]
        if j == 3:
            e[0] = math.remainder(e[0], 2 * math.pi)
        v[j] = Y[r, j] + K[i : i + r] @ e
        e0[j] = e[0]
    if par[PAR_INTEGRAL]:
        state[STATE_INTEGRAL] = np.clip(state[STATE_INTEGRAL] + e0 * dt, -lim, lim)
        v += k_int * state[STATE_INTEGRAL]
    ratio = abs(np.linalg.det(A)) / float(np.prod(np.sqrt((A * A).sum(axis=1))))
    singular = not ratio >= HADAMARD_MIN
    u = np.array([0.0, *state[STATE_U][1:]]) if singular else np.linalg.solve(A, v - b)
    state[STATE_U] = u
    x_L_A = link_frame(link[0], link[1])[:, 0]
    tau = so3.cancel_cable_torque_reference(u[1:4].copy(), R, x_L_A, tension, cable)
    # the rotors hold the command for one period: the mean of the thrust polynomial over
    # it, f + f' h/2 + f'' h^2/6; the motor lag is led along f_R'
    thrust = f + 0.5 * fd * h + u[0] * h * h / 6.0
    rates = share * (fd + 0.5 * u[0] * h)
    out = np.zeros(OUT_WIDTH)
    wrench = np.concatenate(([max(thrust, 0.0)], tau))
    out[: mixer.OUT_WIDTH] = mixer.mix_reference(wrench, rates, layout, rotors)
    out[OUT_ERRORS], out[OUT_SINGULAR], out[OUT_RATIO] = e0, float(singular), ratio
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
    (:func:`tetherland.control.kernels.dfl_terms.dfl_terms_into`)."""
    last_u, integral = state[STATE_U], state[STATE_INTEGRAL]
    errors = out[OUT_ERRORS]
    gains, k_int = par[PAR_GAINS], par[PAR_INTEGRAL_GAINS]
    f, fd = state[STATE_THRUST], state[STATE_THRUST_RATE]
    dt = 0.0
    t_last = state[STATE_T_LAST]
    if t_last == t_last:
        dt = t - t_last
        u0 = last_u[0]
        f, fd = f + fd * dt + 0.5 * u0 * dt * dt, fd + u0 * dt
    state[STATE_THRUST], state[STATE_THRUST_RATE], state[STATE_T_LAST] = f, fd, t
    R = so3.quat_rotmat3(q_WB)
    cable = par[PAR_CABLE]
    R_WA = cable[so3.CABLE_R_WA].reshape(3, 3)
    theta_e, roll, psi = _dfl_attitude_compiled(so3.tmul3(R_WA, R))
    x = np.empty(12)
    x[0], x[1], x[2], x[3] = link[0], link[1], link[2], link[3]
    x[4], x[5], x[6] = theta_e, roll, psi
    x[7], x[8], x[9] = omega_B[0], omega_B[1], omega_B[2]
    x[10], x[11] = f, fd
    terms = np.empty(YAB_WIDTH)
    dfl_terms_into(x, par[PAR_MODEL], terms)
    y_all, b = terms[YAB_Y], terms[YAB_B]
    v = np.empty(4)
    for j in range(4):
        i, r = DFL_OFFSETS[j], DFL_RELATIVE_DEGREES[j]
        acc = 0.0
        for d in range(r):
            e = Y[d, j] - y_all[i + d]
            if d == 0:
                if j == 3:
                    e = so3.remainder(e, 2.0 * math.pi)
                errors[j] = e
            acc += gains[i + d] * e
        v[j] = Y[r, j] + acc
    if par[PAR_INTEGRAL] != 0.0:
        lim = par[PAR_INTEGRAL_MAX]
        for j in range(4):
            integral[j] = min(max(integral[j] + errors[j] * dt, -lim), lim)
            v[j] += k_int[j] * integral[j]
    A = terms[YAB_A].reshape(4, 4)
    rows = 1.0
    for i in range(4):
        rows *= math.sqrt(A[i, 0] ** 2 + A[i, 1] ** 2 + A[i, 2] ** 2 + A[i, 3] ** 2)
    for j in range(4):
        v[j] -= b[j]  # v - b
    det, u = _lu4_solve(A, v)
    ratio = abs(det) / rows
    singular = not ratio >= HADAMARD_MIN
    if singular:  # hold f_R'' = 0 and the last torque
        u[0] = 0.0
        for i in range(1, 4):
            u[i] = last_u[i]
    for i in range(4):
        last_u[i] = u[i]
    phi, delta = link[0], link[1]
    cd = math.cos(delta)
    t0, t1, t2 = so3.cancel_cable_torque(
        u[1], u[2], u[3], R, cd * math.cos(phi), -math.sin(delta), cd * math.sin(phi),
        tension, cable,
    )  # fmt: skip
    h = par[PAR_PERIOD]
    thrust = f + 0.5 * fd * h + u[0] * h * h / 6.0
    lead = fd + 0.5 * u[0] * h
    share = par[PAR_THRUST_SHARE]
    rates = np.empty(4)
    for i in range(4):
        rates[i] = share[i] * lead
    mixer.mix_into(max(thrust, 0.0), t0, t1, t2, rates, True, mix, out)
    out[OUT_SINGULAR] = 1.0 if singular else 0.0
    out[OUT_RATIO] = ratio
