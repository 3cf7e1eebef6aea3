"""The robot's own model of the ground effect, from its belief (issue 23, variant b).

The estimator predicts the rotors' thrust from the commanded speeds (motor lag). Near a
surface the rotors push harder than c_f w^2 (:mod:`tetherland.models.aero`); unmodelled,
the extra thrust reads as an external force along z_B, i.e. as a push of the surface,
and lowers the tension estimate by its component along the link. With
``estimator.ground_effect_belief`` the estimator multiplies each rotor's predicted thrust
by its Cheeseman-Bennett factor over the *believed* surface patch (``[surface]`` of the
belief: plane patch or pipe of the believed extent, no ground plane) at the *estimated*
pose, with the believed rotor radius 0.4 arm_length (the rotor guards). Nothing here
reads the plant's ``[aero]``.
"""

from __future__ import annotations

import math

import numpy as np

from tetherland.config import Scenario
from tetherland.geometry import FloatArray, surface_from_config
from tetherland.models.aero import (
    AeroModel,
    ShapeKind,
    aero_into,
    disk_samples,
    pack_shape,
    rotor_disks,
)

PATCH_HALF_THICKNESS = 0.05
"""Half thickness of the believed plane patch [m] (only its top face matters)."""
FAR_RATIO = 20.0
"""Beyond this many rotor radii from the believed surface the factors are 1 [-]."""


def believed_surface_shapes(scenario: Scenario) -> FloatArray:
    """The believed landing surface as packed shapes, (1, SHAPE_WIDTH)."""
    surf = surface_from_config(scenario)
    e = scenario.surface.extent
    if surf.kind == "pipe":
        r = surf.pipe_radius
        R_WL = np.column_stack((surf.y_S, surf.z_S, surf.x_S))  # axis along x_S
        row = pack_shape(ShapeKind.CYLINDER, surf.origin - r * surf.z_S, R_WL, (r, e, 0.0))
    else:
        row = pack_shape(
            ShapeKind.BOX,
            surf.origin - PATCH_HALF_THICKNESS * surf.z_S,
            surf.R_WS,
            (e, e, PATCH_HALF_THICKNESS),
        )
    return row[None, :]


class BelievedGroundEffect:
    """Ground-effect factors of the believed surface at an estimated pose.

    Parameters
    ----------
    scenario : Scenario
        The *believed* scenario.
    """

    def __init__(self, scenario: Scenario) -> None:
        v = scenario.vehicle
        centres, radius = rotor_disks(v)
        self.model = AeroModel(
            rotor_centres_B=centres,
            radius=radius,
            samples=disk_samples(3, 8),
            shapes=believed_surface_shapes(scenario),
            ceiling_coefficient=0.0,
            thrust_coefficient=v.thrust_coefficient,
        )
        m = self.model
        reach = float(np.max(np.linalg.norm(centres, axis=1))) + radius
        self._far = FAR_RATIO * radius + reach
        surf = surface_from_config(scenario)
        self._origin_f = tuple(float(x) for x in surf.origin)
        self._z_S_f = tuple(float(x) for x in surf.z_S)
        self._x_S_f = tuple(float(x) for x in surf.x_S)
        self._pipe_radius = surf.pipe_radius if surf.kind == "pipe" else None
        self._args = (m.rotor_centres_B, m.samples, m.shapes, m.params)
        self._qpos = np.empty(7)
        self._thrusts = np.empty(4)
        self._zero3 = np.zeros(3)
        self._ones = np.ones(4)
        self._factors, self._acting, self._wrench = np.empty(4), np.empty(4), np.empty(6)

    def total_thrust(self, p_W: FloatArray, q_WB: FloatArray, thrusts: FloatArray) -> float:
        """Sum of the rotor ``thrusts`` [N] (out of ground effect) times their believed
        factors at the pose (p_W [m], q_WB [-]) [N].

        Farther than :data:`FAR_RATIO` rotor radii from the believed surface (beyond the
        rotors' reach) the factors are taken as 1 (they differ from it by less than
        2e-4) and the model is not evaluated.
        """
        px, py, pz = np.asarray(p_W, dtype=float).tolist()
        if self._distance3(px, py, pz) > self._far:
            self._factors[:] = 1.0
            return float(np.sum(thrusts))
        return self._evaluate(p_W, q_WB, thrusts)

    def total_thrust_of(self, x: FloatArray, thrusts: list[float]) -> float:
        """:meth:`total_thrust` at the pose ``x[0:3]``, ``x[6:10]`` of a navigation state
        [p_W, v_W, q_WB, ...], for four rotor ``thrusts`` as floats [N] (the estimator's
        control-rate path: one list conversion, no temporary arrays; the same bits)."""
        px, py, pz = x[0:3].tolist()
        t0, t1, t2, t3 = thrusts
        if self._distance3(px, py, pz) > self._far:
            self._factors[:] = 1.0
            return ((t0 + t1) + t2) + t3  # (numpy's order for 4 terms: the same bits)
        q, f = self._qpos, self._thrusts
        q[0:3] = x[0:3]
        q[3:7] = x[6:10]
        f[:] = thrusts
        aero_into(q, self._zero3, f, *self._args, self._factors, self._acting,
                  self._wrench)  # fmt: skip
        return float(self._acting.sum())

    def _evaluate(self, p_W: FloatArray, q_WB: FloatArray, thrusts: FloatArray) -> float:
        """The believed model at the pose, whatever the distance: the sum of the acting
        thrusts [N] (the factors in ``_factors``)."""
        q = self._qpos
        q[0:3] = p_W
        q[3:7] = q_WB
        aero_into(q, self._zero3, thrusts, *self._args, self._factors, self._acting,
                  self._wrench)  # fmt: skip
        return float(self._acting.sum())

    def beyond_reach(self, p_W: FloatArray) -> bool:
        """True when the pose's centre of mass ``p_W`` [m] is farther than
        :data:`FAR_RATIO` rotor radii (plus the rotors' reach) from the believed surface,
        where every believed factor is taken as exactly 1."""
        px, py, pz = np.asarray(p_W, dtype=float).tolist()
        return self._distance3(px, py, pz) > self._far

    def _distance(self, p_W: FloatArray) -> float:
        """A lower bound of the distance from ``p_W`` to the believed surface patch: to its
        slab, or to the pipe's infinite cylinder [m]."""
        px, py, pz = np.asarray(p_W, dtype=float).tolist()
        return self._distance3(px, py, pz)

    def _distance3(self, px: float, py: float, pz: float) -> float:
        """:meth:`_distance` of the point (px, py, pz) [m] (scalar form: a control-rate
        path)."""
        ox, oy, oz = self._origin_f
        dx, dy, dz = px - ox, py - oy, pz - oz
        zx, zy, zz = self._z_S_f
        if self._pipe_radius is None:
            return abs(dx * zx + dy * zy + dz * zz) - PATCH_HALF_THICKNESS * 2.0
        r = self._pipe_radius
        xx, xy, xz = self._x_S_f
        along = dx * xx + dy * xy + dz * xz
        # from the axis
        rx, ry, rz = dx - along * xx + r * zx, dy - along * xy + r * zy, dz - along * xz + r * zz
        return math.sqrt(rx * rx + ry * ry + rz * rz) - r  # to the infinite cylinder

    def factors_at(self, p_W: FloatArray, q_WB: FloatArray, near: bool = False) -> FloatArray:
        """Believed factor of each rotor at the pose (p_W [m], q_WB [-]) [-] (a view, valid
        until the next call). ``near``: the caller has just found the pose not
        :meth:`beyond_reach` (the check is not made again)."""
        if near:
            self._evaluate(p_W, q_WB, self._ones)
        else:
            self.total_thrust(p_W, q_WB, self._ones)
        return self._factors

    def factors_at_pose(self, pose: list[float]) -> FloatArray:
        """:meth:`factors_at` of a pose given as seven floats [p_W (3), q_WB (4)], known
        not :meth:`beyond_reach` [-] (a view, valid until the next call)."""
        q = self._qpos
        q[:] = pose
        aero_into(q, self._zero3, self._ones, *self._args, self._factors, self._acting,
                  self._wrench)  # fmt: skip
        return self._factors

    @property
    def factors(self) -> FloatArray:
        """The factors of the last :meth:`total_thrust` [-] (copy)."""
        return self._factors.copy()
