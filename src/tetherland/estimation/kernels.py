"""Compiled per-tick outputs of :class:`~tetherland.estimation.UkfEstimator`.

After the UKF has integrated the tick's IMU samples (:mod:`~tetherland.estimation.ukf_kernels`),
one call of :func:`estimate_into` writes everything the estimate record needs into one
flat array: the body state with the bias-corrected rate, the biases, the link state of
the attachment point around the believed anchor (docs/theory.md section 3) and the
instantaneous cable tension (docs/theory.md section 8)

    f_L = d_B . (f_R e3 - m (f_B - b_a))   (projection on the link; the norm when d_B = 0).

:func:`estimate_reference` is the same with the readable pieces
(:func:`tetherland.state.link_state_reference`,
:func:`tetherland.estimation.tension.tension_from_forces`); a property test checks both.

Layout of ``out`` (:data:`WIDTH` floats): p_W, v_W, q_WB, omega_B, accel bias b_a, gyro
bias b_g (the log's estimate columns in order), link [phi, delta, phi', delta'], d_B, the
raw tension and the external force m (f_B - b_a) - f_R e3 in F_B (everything but the
rotors: cable, contact, wind). ``geo`` = [r_att_B (3), p_A (3), R_WA (3x3, row-major)].
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.estimation.tension import tension_from_forces
from tetherland.geometry import FloatArray
from tetherland.state import link_into, link_state_reference

P_W, V_W, Q_WB, OMEGA_B = slice(0, 3), slice(3, 6), slice(6, 10), slice(10, 13)
ACCEL_BIAS, GYRO_BIAS, LINK, D_B = slice(13, 16), slice(16, 19), slice(19, 23), slice(23, 26)
TENSION = 26
EXTERNAL = slice(27, 30)
WIDTH = 30


def pack_geometry(r_att_B: FloatArray, p_A: FloatArray, R_WA: FloatArray) -> FloatArray:
    """``geo`` of :func:`estimate_into`."""
    return np.concatenate((r_att_B, p_A, np.asarray(R_WA, dtype=float).reshape(9))).astype(float)


def estimate_reference(
    x: FloatArray,
    imu: FloatArray,
    thrust: float,
    mass: float,
    geo: FloatArray,
) -> FloatArray:
    """Plain version of :func:`estimate_into` (returns ``out``).

    Parameters
    ----------
    x : (16,) array
        UKF state [p_W, v_W, q_WB, b_g, b_a].
    imu : (10,) array
        The UKF's IMU record [t, f_B, omega_B of the last sample, mean f_B of the last
        prediction] (measured) [s, m/s^2, rad/s, m/s^2].
    thrust : float
        Actual total rotor thrust (motor lag) [N].
    mass : float
        [kg]
    geo : (15,) array
        See the module docstring.
    """
    p_W, v_W, q_WB, b_g, b_a = x[0:3], x[3:6], x[6:10], x[10:13], x[13:16]
    omega_B, f_mean_B = imu[4:7] - b_g, imu[7:10]
    r_att, p_A, R_WA = geo[0:3], geo[3:6], geo[6:15].reshape(3, 3)
    link, d_B = link_state_reference(np.concatenate((p_W, q_WB, v_W, omega_B)), r_att, p_A, R_WA)
    tension = tension_from_forces(thrust, f_mean_B - b_a, mass, d_B if d_B.any() else None)
    external_B = mass * (f_mean_B - b_a) - thrust * np.array([0.0, 0.0, 1.0])
    return np.concatenate((p_W, v_W, q_WB, omega_B, b_a, b_g, link, d_B, [tension], external_B))


@njit(cache=True)
def estimate_into(
    x: FloatArray,
    imu: FloatArray,
    thrust: float,
    mass: float,
    geo: FloatArray,
    out: FloatArray,
) -> None:
    """Compiled :func:`estimate_reference`, written into ``out`` (:data:`WIDTH`,)."""
    for i in range(6):
        out[i] = x[i]  # p_W, v_W
    for i in range(4):
        out[6 + i] = x[6 + i]  # q_WB
    for i in range(3):
        out[10 + i] = imu[4 + i] - x[10 + i]  # omega_B = omega_m - b_g
        out[13 + i] = x[13 + i]  # b_a
        out[16 + i] = x[10 + i]  # b_g
    R_WA = geo[6:15].reshape(3, 3)
    link_into(out[0:3], out[6:10], out[3:6], out[10:13], geo[0:3], geo[3:6], R_WA,
              out[19:23], out[23:26])  # fmt: skip
    # residual force f_R e3 - m (f_B - b_a) in F_B, projected on d_B (or its norm)
    rx = -mass * (imu[7] - x[13])
    ry = -mass * (imu[8] - x[14])
    rz = thrust - mass * (imu[9] - x[15])
    dx, dy, dz = out[23], out[24], out[25]
    if dx != 0.0 or dy != 0.0 or dz != 0.0:
        out[TENSION] = dx * rx + dy * ry + dz * rz
    else:
        out[TENSION] = math.sqrt(rx * rx + ry * ry + rz * rz)
    out[27] = -rx  # the external force, m (f_B - b_a) - f_R e3
    out[28] = -ry
    out[29] = -rz
