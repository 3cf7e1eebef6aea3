"""Feed-forward of the believed rotor drag (issue 23, variant b for the controllers).

Rotors moving through the air are pushed back in their plane, F = -R_WB diag(d_x, d_y, 0)
R_WB^T v (Faessler, Franchi and Scaramuzza 2018). On a perching maneuver at 1 m/s that is
0.4 N on a 1 kg vehicle, more than the position loop holds to the centimetre without
notice. A controller wrapper: every position reference (``Reference.p_W`` rows p, v, a,
...) gets, on its acceleration row, the drag of its own velocity at the estimated
attitude divided by the believed mass, a_ff = R_WB diag(d_x, d_y, 0) R_WB^T v_ref / m
(scaled with the rotor speed the reference's thrust needs), and the jerk row its rate
along the reference at the present attitude, R_WB diag(d_x, d_y, 0) R_WB^T a_ref / m, so
that the controller asks for the force that flies the reference through the drag and
turns the thrust axis in time for it (without the jerk term a 20 deg perch, 0.4 N of
drag at 0.9 m/s, still touched down 8 mm off its plan).
The reference velocity, not the estimated one, keeps estimation noise out of the
feed-forward (and out of the motor-lag lead, which differentiates it). The coefficients
are the belief's ``controller.rotor_drag``; the plant's ``[aero]`` is never read.

The jerk term holds the attitude: the drag's rate also has the rotation of the rotor
plane (omega x x_B, with v) and the rate of the rotor speed, and the snap row gets none of
its second derivative. On slow references that is small; through a perching flip at 2 m/s
and 8 rad/s it is not, and the perching planner, which models the same drag, hands its
rows with the drag and all its derivatives already in (``Reference.drag_in_rows``: the
thrust's acceleration, jerk and snap, :meth:`FreeFlightTrajectory.reference_at`); such
rows are passed on unchanged.

Tethered references (link outputs y = [phi, delta, theta_A, psi], no position rows) get
the same force as link accelerations (:func:`link_drag_acceleration`): the tethered laws
set the thrust's components across the link from phi'' and delta'' (the cable takes the
rest), so the drag D of the reference velocity l (cos(delta) phi' z_L - delta' y_L) is
cancelled by phi_d'' += -D.z_L / (m l cos(delta)) and delta_d'' += D.y_L / (m l).
Without it the link integral absorbs the drag of the swing and carries that state into
the touchdown (docs/aero.md).
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

import numpy as np

from tetherland import GRAVITY
from tetherland.config import Scenario
from tetherland.control.ground_effect import GroundEffectCompensation
from tetherland.geometry import FloatArray, LandingGeometry, link_frame
from tetherland.interfaces import Command, Controller, ControlMode, Reference, StateEstimate
from tetherland.rotations import quat_to_rotmat


def drag_acceleration(
    R_WB: FloatArray, v_W: FloatArray, a_W: FloatArray, d_xy: FloatArray, mass: float
) -> FloatArray:
    """Acceleration [m/s^2] the thrust must add to fly at ``v_W`` [m/s] with acceleration
    ``a_W`` [m/s^2] through the rotor drag diag(d_x, d_y, 0) [N s/m] (at the hover rotor
    speed) of a vehicle of ``mass`` [kg] at attitude ``R_WB``.

    The drag grows with the mean rotor speed, w / w_h = sqrt(f / (m g)) for the thrust
    f = m ||a + g z_W|| that the acceleration needs.
    """
    v_B = R_WB.T @ np.asarray(v_W, dtype=float)
    f_B = np.array([d_xy[0] * v_B[0], d_xy[1] * v_B[1], 0.0])
    a = np.asarray(a_W, dtype=float).copy()
    a[2] += GRAVITY
    scale = math.sqrt(float(np.linalg.norm(a)) / GRAVITY)
    return R_WB @ f_B * (scale / mass)


def link_drag_acceleration(
    R_WB: FloatArray, R_WA: FloatArray, Y: FloatArray, thrust: float, d_xy: FloatArray,
    mass: float, length: float,
) -> tuple[float, float]:  # fmt: skip
    """(phi'', delta'') [rad/s^2] the tethered laws must add to fly the link reference
    ``Y`` (rows y, y' of [phi, delta, ...]) through the rotor drag diag(d_x, d_y, 0)
    [N s/m] at attitude ``R_WB``, for a vehicle of ``mass`` [kg] on a link of ``length``
    [m] whose thrust is ``thrust`` [N] (the rotor-speed scale sqrt(thrust / (m g)); 0 or
    less: the hover speed).

    The centre of mass moves with the link end, v_A = l (cos(delta) phi' z_L - delta' y_L)
    (the attachment offset's own motion is left out); the drag D = -R_WB diag(d) R_WB^T v
    is cancelled across the link by phi'' += -D.z_L / (m l cos(delta)) and
    delta'' += D.y_L / (m l).
    """
    phi, delta = float(Y[0, 0]), float(Y[0, 1])
    R_AL = link_frame(phi, delta)
    cd = math.cos(delta)
    v_W = R_WA @ (length * (cd * float(Y[1, 0]) * R_AL[:, 2] - float(Y[1, 1]) * R_AL[:, 1]))
    scale = math.sqrt(thrust / (mass * GRAVITY)) if thrust > 0.0 else 1.0
    v_B = R_WB.T @ v_W
    D_W = -(R_WB @ np.array([d_xy[0] * v_B[0], d_xy[1] * v_B[1], 0.0])) * scale
    D_L = R_AL.T @ (R_WA.T @ D_W)
    return -float(D_L[2]) / (mass * length * cd), float(D_L[1]) / (mass * length)


class RotorDragCompensation:
    """Wraps ``controller``: position references carry the believed drag as feed-forward.

    Parameters
    ----------
    controller : Controller
        The wrapped controller (its other attributes are reached through the wrapper).
    belief : Scenario
        The *believed* scenario (``controller.rotor_drag``, vehicle mass).
    """

    def __init__(self, controller: Controller, belief: Scenario) -> None:
        self.inner = controller
        self.d_xy = np.asarray(belief.controller.rotor_drag, dtype=float)
        self.mass = float(belief.vehicle.mass)
        self.tethered = belief.controller.rotor_drag_tethered
        """Also the tethered references (``controller.rotor_drag_tethered``)."""
        geo = LandingGeometry.from_scenario(belief)
        self.R_WA, self.length = geo.R_WA, float(geo.link_length)

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        if reference.drag_in_rows:  # a plan with the believed drag: its rows carry it
            return self.inner.update(t, estimate, reference)
        rows = reference.p_W
        if rows is None or len(rows) < 2:
            Y = reference.output
            if (
                self.tethered and Y is not None and len(Y) > 2
                and reference.mode is ControlMode.TETHERED
            ):  # fmt: skip
                Y = np.array(Y, dtype=float)
                thrust = reference.thrust_ff if reference.thrust_ff is not None else 0.0
                a_phi, a_delta = link_drag_acceleration(
                    quat_to_rotmat(estimate.body.q_WB), self.R_WA, Y, float(thrust), self.d_xy,
                    self.mass, self.length,
                )  # fmt: skip
                Y[2, 0] += a_phi
                Y[2, 1] += a_delta
                return self.inner.update(t, estimate, replace(reference, output=Y))
            return self.inner.update(t, estimate, reference)
        rows = np.asarray(rows, dtype=float)
        R_WB = quat_to_rotmat(estimate.body.q_WB)
        a_W = rows[2] if len(rows) > 2 else np.zeros(3)
        a_ff = drag_acceleration(R_WB, rows[1], a_W, self.d_xy, self.mass)
        if len(rows) == 2:
            rows = np.vstack((rows, a_ff))
        else:
            rows = rows.copy()
            rows[2] += a_ff
            if len(rows) > 3:  # its rate along the reference (attitude held): D a_ref / m
                rows[3] += drag_acceleration(R_WB, a_W, a_W, self.d_xy, self.mass)
        return self.inner.update(t, estimate, replace(reference, p_W=rows))

    def __getattr__(self, name: str) -> Any:
        return getattr(self.inner, name)


def with_aero_belief(controller: Controller, belief: Scenario) -> Controller:
    """``controller`` as a mission composes it: wrapped in the believed ground-effect
    compensation (``controller.ground_effect_compensation``) and the believed rotor-drag
    feed-forward (``controller.rotor_drag`` not zero), each only when switched on."""
    out: Controller = controller
    if belief.controller.ground_effect_compensation:
        out = GroundEffectCompensation(out, belief)
    if any(d > 0.0 for d in belief.controller.rotor_drag):
        out = RotorDragCompensation(out, belief)
    return out
