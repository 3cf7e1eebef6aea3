"""Thrust compensation for the believed ground effect (issue 23, variant b for the controllers).

A controller wrapper: each rotor's commanded speed is divided by the square root of its
believed ground-effect factor (:class:`~tetherland.estimation.ground_effect.
BelievedGroundEffect`: the believed surface patch at the estimated pose), so that the
thrust it believes acting, c_f w^2 k, is the thrust the controller wanted. Switched on by
``controller.ground_effect_compensation``; the plant's ``[aero]`` is never read.

Motor lag. A speed command acts through the first-order lag tau_m of the believed
vehicle, and the factor grows quickly in the last centimetres (about 0.12 1/s on a
perching approach): dividing by sqrt(k(t)) leaves c_f w^2 (k(t) - k(t - tau_m)) of
surplus thrust, enough to hold a contact-free vehicle 2 mm off the surface at its planned
touchdown. The command therefore uses the factor at the pose predicted tau_m ahead,
(p + v tau_m, q exp(omega tau_m / 2)): to first order w_c = w_a + tau_m w_a' for the
wanted acting speed w_a = w / sqrt(k), the same lead the controllers give their own
thrust (:mod:`tetherland.control.tracking`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from tetherland.config import Scenario
from tetherland.estimation.ground_effect import BelievedGroundEffect
from tetherland.geometry import FloatArray
from tetherland.interfaces import Command, Controller, Reference, StateEstimate
from tetherland.rotations import SMALL_ANGLE, quat_multiply, rotvec_to_quat


def predicted_attitude(q_WB: FloatArray, omega_B: FloatArray, tau: float) -> list[float]:
    """q_WB exp(tau omega_B / 2), normalised, as four floats [-] (scalar form, the same bits
    as :func:`predicted_attitude_reference`).

    ``omega_B`` in [rad/s], ``tau`` in [s].
    """
    w, x, y, z = np.asarray(q_WB, dtype=float).tolist()
    ox, oy, oz = np.asarray(omega_B, dtype=float).tolist()
    ax, ay, az = tau * ox, tau * oy, tau * oz
    angle = math.sqrt(ax * ax + ay * ay + az * az)  # (np.linalg.norm's bits: a test checks)
    if angle < SMALL_ANGLE:
        bw, bx, by, bz = 1.0, 0.5 * ax, 0.5 * ay, 0.5 * az
        n = math.sqrt(bw * bw + bx * bx + by * by + bz * bz)
        bw, bx, by, bz = bw / n, bx / n, by / n, bz / n
    else:
        s = math.sin(0.5 * angle)
        bw, bx, by, bz = math.cos(0.5 * angle), s * (ax / angle), s * (ay / angle), s * (az / angle)
    qw = w * bw - x * bx - y * by - z * bz
    qx = w * bx + x * bw + y * bz - z * by
    qy = w * by - x * bz + y * bw + z * bx
    qz = w * bz + x * by - y * bx + z * bw
    n = math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    return [qw / n, qx / n, qy / n, qz / n]


def predicted_attitude_reference(q_WB: FloatArray, omega_B: FloatArray, tau: float) -> FloatArray:
    """:func:`predicted_attitude` written plainly with the rotation helpers [-]."""
    q = quat_multiply(q_WB, rotvec_to_quat(tau * np.asarray(omega_B, dtype=float)))
    return q / np.linalg.norm(q)


class GroundEffectCompensation:
    """Wraps ``controller``: the same commands, rotor speeds divided by sqrt(k_i).

    Parameters
    ----------
    controller : Controller
        The wrapped controller (its other attributes are reached through the wrapper).
    belief : Scenario
        The *believed* scenario (surface, vehicle).
    """

    def __init__(self, controller: Controller, belief: Scenario) -> None:
        self.inner = controller
        self.ground_effect = BelievedGroundEffect(belief)
        self.lead = float(belief.vehicle.motor_time_constant)
        """Prediction horizon of the factor: the believed motor time constant [s]."""

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        cmd = self.inner.update(t, estimate, reference)
        w = np.asarray(cmd.rotor_speeds, dtype=float)
        if not w.any():
            return cmd
        b = estimate.body
        tau = self.lead
        # scalar form of the numpy reference below (a test checks the same bits):
        # p = p_W + tau v_W, q = q_WB exp(tau omega_B / 2) normalised
        px, py, pz = np.asarray(b.p_W, dtype=float).tolist()
        vx, vy, vz = np.asarray(b.v_W, dtype=float).tolist()
        px, py, pz = px + tau * vx, py + tau * vy, pz + tau * vz
        ge = self.ground_effect
        if ge._distance3(px, py, pz) > ge._far:
            return cmd  # every believed factor is 1: the command as it is
        k = ge.factors_at_pose([px, py, pz, *predicted_attitude(b.q_WB, b.omega_B, tau)])
        # (the fields as dataclasses.replace would copy them, without its generic walk)
        return Command(w / np.sqrt(k), cmd.thrust, cmd.torque_B, cmd.diagnostics)

    def __getattr__(self, name: str) -> Any:
        return getattr(self.inner, name)
