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

Each tick is one compiled call (:mod:`tetherland.control.kernels.aero`: the rows,
:func:`~tetherland.control.kernels.aero.drag_rows_into`, or the link accelerations,
:func:`~tetherland.control.kernels.aero.link_drag_into`), beside the plain forms
:func:`drag_acceleration` and :func:`link_drag_acceleration` (defined there, and
importable from here).
"""

from __future__ import annotations

import operator
from dataclasses import fields
from typing import Any

import numpy as np

from tetherland.config import Scenario
from tetherland.control.kernels.aero import (
    drag_acceleration,
    drag_rows_into,
    link_drag_acceleration,
    link_drag_into,
    pack_drag,
)
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import Command, Controller, ControlMode, Reference, StateEstimate

__all__ = [
    "RotorDragCompensation",
    "drag_acceleration",
    "link_drag_acceleration",
    "replaced",
]

_FIELDS = tuple(f.name for f in fields(Reference))
_VALUES = operator.attrgetter(*_FIELDS)
_P_W, _OUTPUT = _FIELDS.index("p_W"), _FIELDS.index("output")


def replaced(reference: Reference, field: int, value: Any) -> Reference:
    """``dataclasses.replace(reference, <field>=value)`` for the field at position
    ``field`` of :class:`Reference` (every other field copied), without replace's generic
    walk of the fields (a control-rate path)."""
    values = list(_VALUES(reference))
    values[field] = value
    return Reference(*values)


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
        self.packed = pack_drag(self.d_xy, self.mass, self.length, self.R_WA)
        """The drag packed for the compiled kernels
        (:func:`~tetherland.control.kernels.aero.pack_drag`)."""

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
                a_phi, a_delta = link_drag_into(estimate.body.q_WB, Y, float(thrust), self.packed)
                Y[2, 0] += a_phi
                Y[2, 1] += a_delta
                return self.inner.update(t, estimate, replaced(reference, _OUTPUT, Y))
            return self.inner.update(t, estimate, reference)
        rows = np.asarray(rows, dtype=float)
        out = np.empty((max(len(rows), 3), 3))
        drag_rows_into(estimate.body.q_WB, rows, self.packed, out)
        return self.inner.update(t, estimate, replaced(reference, _P_W, out))

    def __getattr__(self, name: str) -> Any:
        return getattr(self.inner, name)
