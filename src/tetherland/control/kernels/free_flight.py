"""The free-flight law (geometric position + SO(3) attitude, Lee et al. 2010), plain and
compiled side by side.

:func:`free_flight_reference` is the readable law (the equations of
:class:`~tetherland.control.position.PositionController`,
:func:`~tetherland.control.attitude.attitude_torque` and the mixer); :func:`free_flight_into`
is the same law compiled, one call per control tick. Both read the gains packed by
:func:`pack_free_flight` at the ``PAR_*`` fields and write the ``OUT_*`` fields of ``out``.
The controller is :class:`tetherland.control.FreeFlightController`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.control.attitude import attitude_torque
from tetherland.control.kernels import mixer, so3
from tetherland.control.kernels.packing import Fields
from tetherland.errors import SingularityError
from tetherland.geometry import FloatArray
from tetherland.models.quadrotor import RotorLayout, RotorModel
from tetherland.rotations import quat_to_rotmat, rotation_from_z_and_yaw

YAW_SINGULAR_NORM = 1e-9
"""|z_B,d x x_C| below which the heading is undefined (as rotation_from_z_and_yaw)."""

# ------------------------------------------------------------------ par: gains and model
_par = Fields()
PAR_MASS = _par.scalar()
"""m [kg]."""
PAR_G = _par.scalar()
"""g [m/s^2]."""
PAR_K_X = _par.scalar()
"""Position gain k_x [1/s^2]."""
PAR_K_V = _par.scalar()
"""Velocity gain k_v [1/s]."""
PAR_K_I = _par.scalar()
"""Integral gain k_i [1/s^3]."""
PAR_INTEGRAL_BOUND = _par.scalar()
"""Bound of each component of the position-error integral [m s]."""
PAR_TAN_MAX_TILT = _par.scalar()
"""tan of the largest commanded tilt [-]."""
PAR_MIN_VERTICAL = _par.scalar()
"""Smallest vertical component of F_d [N]."""
PAR_ATTITUDE = _par.vector(so3.ATT_WIDTH)
"""The attitude law's gains (:func:`tetherland.control.kernels.so3.pack_attitude`)."""
PAR_WIDTH = _par.width

# ------------------------------------------------------------------ out: after the mixer's
_out = Fields(mixer.OUT_WIDTH)
OUT_LIMITED = _out.scalar()
"""1 when the tilt or vertical-thrust limit acted."""
OUT_SINGULAR = _out.scalar()
"""1 when the heading is undefined (thrust axis along it): no command."""
OUT_E_X = _out.vector(3)
"""Position error p - p_d, F_W [m]."""
OUT_WIDTH = _out.width


def pack_free_flight(
    mass: float,
    g: float,
    k_x: float,
    k_v: float,
    k_i: float,
    integral_max: float,
    tan_max_tilt: float,
    min_vertical: float,
    inertia: FloatArray,
    k_R: FloatArray,
    k_w: FloatArray,
) -> FloatArray:
    """``par`` of :func:`free_flight_into` (:data:`PAR_WIDTH`): mass [kg], g [m/s^2], gains
    k_x [1/s^2], k_v [1/s], k_i [1/s^3], the integral force bound per axis [N], tan of the
    largest tilt, smallest vertical thrust [N], inertia [kg m^2] and attitude gains
    k_R [1/s^2], k_w [1/s] per axis."""
    par = np.empty(PAR_WIDTH)
    par[PAR_MASS], par[PAR_G] = mass, g
    par[PAR_K_X], par[PAR_K_V], par[PAR_K_I] = k_x, k_v, k_i
    par[PAR_INTEGRAL_BOUND] = integral_max / (mass * k_i) if k_i > 0 else 0.0
    par[PAR_TAN_MAX_TILT], par[PAR_MIN_VERTICAL] = tan_max_tilt, min_vertical
    par[PAR_ATTITUDE] = so3.pack_attitude(inertia, k_R, k_w)
    return par


def free_flight_reference(
    p_W: FloatArray,
    v_W: FloatArray,
    q_WB: FloatArray,
    omega_B: FloatArray,
    ref: FloatArray,
    yaw: float,
    dt: float,
    integral: FloatArray,
    par: FloatArray,
    layout: RotorLayout,
    rotors: RotorModel,
) -> FloatArray:
    """Free-flight position + attitude control and mixer (Lee et al. 2010), plain.

    F_d = m (a_d - k_x e_x - k_v e_v) - m k_i int(e_x) + m g z_W, limited in tilt and
    vertical thrust; f_R = F_d . z_B; R_d from (F_d, psi_d); tau from the SO(3) law.
    ``ref`` rows (p, v, a), the first k given; ``dt`` NaN: no integration. ``integral``
    (int e_x [m s]) is updated in place. Returns ``out`` (:data:`OUT_WIDTH`).
    """
    m, g = par[PAR_MASS], par[PAR_G]
    k_x, k_v, k_i = par[PAR_K_X], par[PAR_K_V], par[PAR_K_I]
    bound = par[PAR_INTEGRAL_BOUND]
    tan_max, min_vertical = par[PAR_TAN_MAX_TILT], par[PAR_MIN_VERTICAL]
    att = par[PAR_ATTITUDE]
    zero = np.zeros(3)
    p_d, v_d, a_d = (ref[i] if ref.shape[0] > i else zero for i in range(3))
    e_x, e_v = p_W - p_d, v_W - v_d
    F = m * (a_d - k_x * e_x - k_v * e_v) - m * k_i * integral
    F[2] += m * g
    limited = False
    if F[2] < min_vertical:
        F[2] = min_vertical
        limited = True
    horiz, max_horiz = math.hypot(F[0], F[1]), F[2] * tan_max
    if horiz > max_horiz:
        F[0:2] *= max_horiz / horiz
        limited = True
    if not math.isnan(dt) and k_i > 0.0 and not limited:
        np.clip(integral + e_x * dt, -bound, bound, out=integral)
    out = np.zeros(OUT_WIDTH)
    out[OUT_LIMITED], out[OUT_E_X] = float(limited), e_x
    R = quat_to_rotmat(q_WB)
    try:
        R_d = rotation_from_z_and_yaw(F, yaw)
    except SingularityError:
        out[OUT_SINGULAR] = 1.0
        return out
    tau = attitude_torque(att[so3.ATT_J], att[so3.ATT_J_K_R], att[so3.ATT_J_K_W], R, omega_B, R_d)
    wrench = np.concatenate(([F @ R[:, 2]], tau))
    out[: mixer.OUT_WIDTH] = mixer.mix_reference(wrench, None, layout, rotors)
    return out


@njit(cache=True)
def desired_force(
    p_W: FloatArray,
    v_W: FloatArray,
    ref: FloatArray,
    dt: float,
    integral: FloatArray,
    par: FloatArray,
    e_x: FloatArray,
    F: FloatArray,
) -> bool:
    """Compiled F_d of :func:`free_flight_reference` into ``F`` [N] (the position error
    into ``e_x`` [m], ``integral`` updated in place); True when a limit acted."""
    m, g, k_x, k_v, k_i = par[PAR_MASS], par[PAR_G], par[PAR_K_X], par[PAR_K_V], par[PAR_K_I]
    k = ref.shape[0]
    for i in range(3):
        e = p_W[i] - ref[0, i]
        e_x[i] = e
        ev = v_W[i] - (ref[1, i] if k > 1 else 0.0)
        a = ref[2, i] if k > 2 else 0.0
        F[i] = m * (a - k_x * e - k_v * ev) - m * k_i * integral[i]
    F[2] += m * g
    limited = False
    if F[2] < par[PAR_MIN_VERTICAL]:
        F[2] = par[PAR_MIN_VERTICAL]
        limited = True
    horiz, max_horiz = math.hypot(F[0], F[1]), F[2] * par[PAR_TAN_MAX_TILT]
    if horiz > max_horiz:
        F[0] *= max_horiz / horiz
        F[1] *= max_horiz / horiz
        limited = True
    if dt == dt and k_i > 0.0 and not limited:
        bound = par[PAR_INTEGRAL_BOUND]
        for i in range(3):
            integral[i] = min(max(integral[i] + e_x[i] * dt, -bound), bound)
    return limited


@njit(cache=True)
def desired_rotation(F: FloatArray, yaw: float, R_d: FloatArray) -> bool:
    """Compiled :func:`~tetherland.rotations.rotation_from_z_and_yaw` of z_B,d = F/||F||
    and psi [rad] into ``R_d``; False when the heading is undefined."""
    # y = z x x_C / ||.||, x = y x z
    n = math.sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2])
    zx, zy, zz = F[0] / n, F[1] / n, F[2] / n
    cx, cy = math.cos(yaw), math.sin(yaw)
    yx, yy, yz = -zz * cy, zz * cx, zx * cy - zy * cx
    n = math.sqrt(yx * yx + yy * yy + yz * yz)
    if n < YAW_SINGULAR_NORM:
        return False
    yx, yy, yz = yx / n, yy / n, yz / n
    R_d[0, 0], R_d[1, 0], R_d[2, 0] = yy * zz - yz * zy, yz * zx - yx * zz, yx * zy - yy * zx
    R_d[0, 1], R_d[1, 1], R_d[2, 1] = yx, yy, yz
    R_d[0, 2], R_d[1, 2], R_d[2, 2] = zx, zy, zz
    return True


@njit(cache=True)
def free_flight_into(
    p_W: FloatArray,
    v_W: FloatArray,
    q_WB: FloatArray,
    omega_B: FloatArray,
    ref: FloatArray,
    yaw: float,
    dt: float,
    integral: FloatArray,
    par: FloatArray,
    mix: FloatArray,
    out: FloatArray,
) -> None:
    """Compiled :func:`free_flight_reference` (``integral`` in place, result in ``out``)."""
    F = np.empty(3)
    limited = desired_force(p_W, v_W, ref, dt, integral, par, out[OUT_E_X], F)
    out[OUT_LIMITED] = 1.0 if limited else 0.0
    R_d = np.empty((3, 3))
    if not desired_rotation(F, yaw, R_d):
        out[OUT_SINGULAR] = 1.0
        return
    out[OUT_SINGULAR] = 0.0
    R = so3.quat_rotmat3(q_WB)
    thrust = F[0] * R[0, 2] + F[1] * R[1, 2] + F[2] * R[2, 2]
    t0, t1, t2 = so3.attitude_torque(R, omega_B, R_d, omega_B, omega_B, False, par[PAR_ATTITUDE])
    mixer.mix_into(thrust, t0, t1, t2, F, False, mix, out)
