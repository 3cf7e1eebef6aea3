"""The mixer (allocation (6.19) with priority saturation, then speed commands), plain and
compiled side by side.

:func:`mix_reference` is the readable law (:meth:`RotorLayout.allocate`,
:meth:`RotorModel.speed_command`); :func:`mix_into` is the same law compiled, on the packed
``mix`` of :func:`pack_mixer` (fields ``MIX_*``). Every compiled law ends with
:func:`mix_into` and so begins its ``out`` with the mixer's result (fields ``OUT_*``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.control.kernels.packing import Fields
from tetherland.geometry import FloatArray
from tetherland.models.quadrotor import RotorLayout, RotorModel, Saturation

_BOUND_TOL = 1e-12  # as models.quadrotor
_SATURATION_LEVEL = {s: float(i) for i, s in enumerate(Saturation)}  # 0 none ... 3 thrust

# ------------------------------------------------------------------ mix: the packed mixer
_mix = Fields()
MIX_G = _mix.vector(16)
"""Allocation Gamma: rotor thrusts [N] -> wrench (f_R [N], tau [N m]), row-major 4x4."""
MIX_GI = _mix.vector(16)
"""Its inverse, row-major 4x4."""
MIX_F_MIN = _mix.scalar()
"""Smallest rotor thrust [N]."""
MIX_F_MAX = _mix.scalar()
"""Largest rotor thrust [N]."""
MIX_C_F = _mix.scalar()
"""Thrust coefficient c_f, f = c_f w^2 [N s^2/rad^2]."""
MIX_TAU = _mix.scalar()
"""Rotor time constant tau_m [s]."""
MIX_W_MIN = _mix.scalar()
"""Smallest rotor speed command [rad/s]."""
MIX_W_MAX = _mix.scalar()
"""Largest rotor speed command [rad/s]."""
MIX_WIDTH = _mix.width

# ------------------------------------------------------------------ out: the mixer's result
_out = Fields()
OUT_SPEEDS = _out.vector(4)
"""Rotor speed commands [rad/s]."""
OUT_WRENCH = _out.vector(4)
"""Achieved wrench: thrust f_R [N], torque tau_B [N m]."""
OUT_SATURATION = _out.scalar()
"""Saturation level: 0 none, 1 yaw scaled, 2 roll/pitch scaled, 3 thrust clipped."""
OUT_WIDTH = _out.width


def pack_mixer(
    allocation: FloatArray,
    allocation_inverse: FloatArray,
    f_min: float,
    f_max: float,
    thrust_coefficient: float,
    time_constant: float,
    w_min: float,
    w_max: float,
) -> FloatArray:
    """``mix`` of :func:`mix_into` (:data:`MIX_WIDTH`): allocation Gamma (4x4) and its
    inverse, rotor thrust bounds [N], c_f [N s^2/rad^2], tau_m [s], speed bounds [rad/s]."""
    mix = np.empty(MIX_WIDTH)
    mix[MIX_G] = np.asarray(allocation, dtype=float).reshape(16)
    mix[MIX_GI] = np.asarray(allocation_inverse, dtype=float).reshape(16)
    mix[MIX_F_MIN], mix[MIX_F_MAX] = f_min, f_max
    mix[MIX_C_F], mix[MIX_TAU] = thrust_coefficient, time_constant
    mix[MIX_W_MIN], mix[MIX_W_MAX] = w_min, w_max
    return mix


def mix_reference(
    wrench: FloatArray, rates: FloatArray | None, layout: RotorLayout, rotors: RotorModel
) -> FloatArray:
    """Allocation with priority saturation then speed commands (:meth:`RotorLayout.allocate`,
    :meth:`RotorModel.speed_command`): the mixer's ``out`` (:data:`OUT_WIDTH`)."""
    alloc = layout.allocate(wrench)
    speeds = rotors.speed_command(alloc.thrusts, rates)
    out = np.empty(OUT_WIDTH)
    out[OUT_SPEEDS], out[OUT_WRENCH] = speeds, alloc.wrench
    out[OUT_SATURATION] = _SATURATION_LEVEL[alloc.saturation]
    return out


@njit(cache=True)
def _feasible(a: FloatArray, b: FloatArray, lo: float, hi: float) -> tuple[bool, float, float]:
    """(exists, s_min, s_max) of {s: lo <= a + s b <= hi} (as models.quadrotor)."""
    s_min, s_max = -math.inf, math.inf
    for i in range(4):
        ai, bi = a[i], b[i]
        if abs(bi) < 1e-15:
            if ai < lo - _BOUND_TOL or ai > hi + _BOUND_TOL:
                return False, s_min, s_max
            continue
        s1, s2 = (lo - ai) / bi, (hi - ai) / bi
        s_min, s_max = max(s_min, min(s1, s2)), min(s_max, max(s1, s2))
    return not s_min > s_max + _BOUND_TOL, s_min, s_max


@njit(cache=True)
def mix_into(
    f_R: float,
    tx: float,
    ty: float,
    tz: float,
    rates: FloatArray,
    use_rates: bool,
    mix: FloatArray,
    out: FloatArray,
) -> None:
    """Compiled :func:`mix_reference` of the wrench (f_R, tau) into ``out[:OUT_WIDTH]``; the
    thrust rates [N/s] enter only when ``use_rates``."""
    Gi = mix[MIX_GI].reshape(4, 4)
    G = mix[MIX_G].reshape(4, 4)
    lo, hi = mix[MIX_F_MIN], mix[MIX_F_MAX]
    wrench = out[OUT_WRENCH]
    w = np.array([f_R, tx, ty, tz])
    f = np.empty(4)
    f_lo, f_hi = math.inf, -math.inf
    for i in range(4):
        f[i] = Gi[i, 0] * w[0] + Gi[i, 1] * w[1] + Gi[i, 2] * w[2] + Gi[i, 3] * w[3]
        f_lo, f_hi = min(f_lo, f[i]), max(f_hi, f[i])
    if f_lo >= lo - _BOUND_TOL and f_hi <= hi + _BOUND_TOL:  # the common case
        level = 0.0
        for i in range(4):
            wrench[i] = w[i]
    else:
        base = np.empty(4)
        d = np.empty(4)
        for i in range(4):  # 1. keep f_R, tau_x, tau_y; scale tau_z by s in [0, 1]
            base[i] = Gi[i, 0] * w[0] + Gi[i, 1] * w[1] + Gi[i, 2] * w[2]
            d[i] = Gi[i, 3] * w[3]
        ok, s0, s1 = _feasible(base, d, lo, hi)
        if ok and s0 <= 1.0 and s1 >= 0.0:
            level = 1.0
        else:  # 2. keep f_R; scale (tau_x, tau_y) by s in [0, 1], no yaw
            for i in range(4):
                base[i] = Gi[i, 0] * w[0]
                d[i] = Gi[i, 1] * w[1] + Gi[i, 2] * w[2]
            ok, s0, s1 = _feasible(base, d, lo, hi)
            if ok and s0 <= 1.0 and s1 >= 0.0:
                level = 2.0
            elif w[0] < 4.0 * lo:  # 3. below the floor: the roll/pitch torque first, on
                # rotors raised above f_min by its differential (as RotorLayout.allocate)
                level = 3.0
                d_lo, d_hi = math.inf, -math.inf
                for i in range(4):
                    d_lo, d_hi = min(d_lo, d[i]), max(d_hi, d[i])
                s1 = 1.0 if d_hi - d_lo <= hi - lo else (hi - lo) / (d_hi - d_lo)
                for i in range(4):
                    base[i] = lo - s1 * d_lo
            else:  # 3. above the ceiling: clip the total thrust, no torque
                level = 3.0
                f_c = min(max(w[0], 4.0 * lo), 4.0 * hi)
                for i in range(4):
                    base[i] = Gi[i, 0] * f_c
                    d[i] = 0.0
                s1 = 0.0
        s = min(1.0, s1)
        for i in range(4):
            f[i] = base[i] + s * d[i]
        for i in range(4):
            f[i] = min(max(f[i], lo), hi)
        for r in range(4):
            wrench[r] = G[r, 0] * f[0] + G[r, 1] * f[1] + G[r, 2] * f[2] + G[r, 3] * f[3]
    out[OUT_SATURATION] = level
    c_f, tau = mix[MIX_C_F], mix[MIX_TAU]
    w_min, w_max = mix[MIX_W_MIN], mix[MIX_W_MAX]
    speeds = out[OUT_SPEEDS]
    lead = use_rates and tau > 0.0
    for i in range(4):
        fi = min(max(f[i], lo), hi)
        wi = math.sqrt(fi / c_f)
        if lead:  # w_cmd = w + tau_m f'/(2 c_f w), limited
            wi = min(max(wi + tau * rates[i] / (2.0 * c_f * wi), w_min), w_max)
        speeds[i] = wi
