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

Speed (issue 25). The estimator evaluates the model once per control tick and the
ground-effect compensation of the controllers once more (a pose one motor lag ahead), so
the model is compiled for what the belief is: one shape (a box or a finite cylinder), the
ground effect only (no ceiling, no wall, no drag). :func:`believed_factors_into` is
:func:`~tetherland.models.aero.aero_into` for that case, the same operations in the same
order (the same bits: a test compares them exactly), without its general shape loop and
culling masks; :func:`believed_total_thrust` adds the cut-off beyond the rotors' reach
and the sum of the acting thrusts, one compiled call per evaluation. The plain reference
of both is :func:`~tetherland.models.aero.aero_reference`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.config import Scenario
from tetherland.geometry import FloatArray, surface_from_config
from tetherland.models.aero import (
    _INF,
    SHAPE_WIDTH,
    AeroModel,
    ShapeKind,
    _ray_local,
    _reachable,
    _to_local,
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


# ------------------------------------------------------------------ the packed belief
# Fields of the believed model packed for the kernels (:func:`pack_believed`), in order:
B_CENTRES = slice(0, 12)
"""Rotor disk centres in F_B, row-major (4, 3) [m]."""
B_SHAPE = slice(12, 12 + SHAPE_WIDTH)
"""The believed surface as a packed shape (:func:`believed_surface_shapes`)."""
B_RADIUS = B_SHAPE.stop
"""Rotor radius R [m]."""
B_Z_MIN = B_RADIUS + 1
"""Lower bound z_min of the distance in the factor [m]."""
B_FAR = B_Z_MIN + 1
"""Distance beyond which every factor is 1 (:data:`FAR_RATIO` R plus the reach) [m]."""
B_PIPE_RADIUS = B_FAR + 1
"""Pipe radius [m]; 0 for a plane patch."""
B_ORIGIN = B_PIPE_RADIUS + 1
"""Start of the surface origin P_S in F_W (3) [m]."""
B_Z_S = B_ORIGIN + 3
"""Start of the surface normal z_S in F_W (3) [-]."""
B_X_S = B_Z_S + 3
"""Start of the surface axis x_S in F_W (3, the pipe's axis) [-]."""
B_N_SAMPLES = B_X_S + 3
"""Number S of disk samples [-]."""
B_SAMPLES = B_N_SAMPLES + 1
"""Start of the S unit-disk samples (x, y), row-major [-]."""


def pack_believed(model: AeroModel, far: float, surface_origin: FloatArray, z_S: FloatArray,
                  x_S: FloatArray, pipe_radius: float) -> FloatArray:  # fmt: skip
    """The believed ``model`` packed for :func:`believed_factors_into` and
    :func:`believed_total_thrust` (fields ``B_*``): one surface shape, a box or a finite
    cylinder, the ground effect only (no ceiling, wall or drag), and the surface's frame
    for the cut-off beyond ``far`` [m] (``pipe_radius`` [m], 0 for a plane patch)."""
    shapes = np.asarray(model.shapes, dtype=float)
    if (
        shapes.shape[0] != 1 or shapes[0, 0] == ShapeKind.PLANE or not model.ground_effect
        or model.ceiling_coefficient != 0.0 or model.wall_effect or any(model.drag)
    ):  # fmt: skip
        raise ValueError("the compiled belief takes one box or cylinder, ground effect only")
    samples = np.asarray(model.samples, dtype=float)
    pack = np.empty(B_SAMPLES + samples.size)
    pack[B_CENTRES] = np.asarray(model.rotor_centres_B, dtype=float).reshape(12)
    pack[B_SHAPE] = shapes[0]
    pack[B_RADIUS] = model.radius
    pack[B_Z_MIN] = model.z_min_ratio * model.radius  # (as pack_params: the same bits)
    pack[B_FAR] = far
    pack[B_PIPE_RADIUS] = pipe_radius
    pack[B_ORIGIN : B_ORIGIN + 3] = surface_origin
    pack[B_Z_S : B_Z_S + 3] = z_S
    pack[B_X_S : B_X_S + 3] = x_S
    pack[B_N_SAMPLES] = samples.shape[0]
    pack[B_SAMPLES:] = samples.reshape(-1)
    return pack


# ------------------------------------------------------------------ compiled kernels
@njit(cache=True)
def believed_distance(px: float, py: float, pz: float, pack: FloatArray) -> float:
    """A lower bound of the distance from (px, py, pz) [m] to the believed surface patch:
    to its slab, or to the pipe's infinite cylinder [m]."""
    o, z, x = B_ORIGIN, B_Z_S, B_X_S
    dx, dy, dz = px - pack[o], py - pack[o + 1], pz - pack[o + 2]
    zx, zy, zz = pack[z], pack[z + 1], pack[z + 2]
    r = pack[B_PIPE_RADIUS]
    if r == 0.0:
        return abs(dx * zx + dy * zy + dz * zz) - PATCH_HALF_THICKNESS * 2.0
    xx, xy, xz = pack[x], pack[x + 1], pack[x + 2]
    along = dx * xx + dy * xy + dz * xz
    # from the axis
    rx, ry, rz = dx - along * xx + r * zx, dy - along * xy + r * zy, dz - along * xz + r * zz
    return math.sqrt(rx * rx + ry * ry + rz * rz) - r  # to the infinite cylinder


@njit(cache=True)
def rotmat_of(qw: float, qx: float, qy: float, qz: float) -> FloatArray:
    """R_WB (3, 3) of the quaternion (qw, qx, qy, qz), normalised on the way (2 / |q|^2
    in place of 2), with the bits of the rotation in
    :func:`~tetherland.models.aero.aero_into` [-]."""
    s2 = 2.0 / (qw * qw + qx * qx + qy * qy + qz * qz)
    xx, yy, zz = qx * qx, qy * qy, qz * qz
    xy, xz, yz = qx * qy, qx * qz, qy * qz
    wx, wy, wz = qw * qx, qw * qy, qw * qz
    return np.array((
        (1.0 - s2 * (yy + zz), s2 * (xy - wz), s2 * (xz + wy)),
        (s2 * (xy + wz), 1.0 - s2 * (xx + zz), s2 * (yz - wx)),
        (s2 * (xz - wy), s2 * (yz + wx), 1.0 - s2 * (xx + yy)),
    ))  # fmt: skip


@njit(cache=True)
def believed_factors_into(px: float, py: float, pz: float, qw: float, qx: float, qy: float,
                          qz: float, pack: FloatArray, factors: FloatArray) -> None:  # fmt: skip
    """Believed factor of each rotor at the pose p_W = (px, py, pz) [m],
    q_WB = (qw, qx, qy, qz) [-], into ``factors`` (4,) [-]: :func:`aero_into` of the packed
    belief (:func:`pack_believed`), the same operations in the same order."""
    Rm = rotmat_of(qw, qx, qy, qz)
    shapes = np.empty((1, SHAPE_WIDTH))
    shapes[0, :] = pack[B_SHAPE]
    loc = np.empty((1, 12))
    _to_local(shapes, px, py, pz, Rm, loc)
    L = loc[0]
    kind, a, b, c = shapes[0, 0], shapes[0, 13], shapes[0, 14], shapes[0, 15]
    ux, uy, uz = -1.0 * L[9], -1.0 * L[10], -1.0 * L[11]  # the wake, -z_B, shape-local
    R = pack[B_RADIUS]
    z_min = pack[B_Z_MIN]
    n_s = int(pack[B_N_SAMPLES])
    for i in range(4):
        cx, cy, cz = pack[3 * i], pack[3 * i + 1], pack[3 * i + 2]
        if not _reachable(shapes, loc, 0, cx, cy, cz, -1.0, R):
            factors[i] = 1.0  # no ray of the disk hits the surface
            continue
        acc = 0.0
        for j in range(n_s):
            bx = cx + R * pack[B_SAMPLES + 2 * j]
            by = cy + R * pack[B_SAMPLES + 2 * j + 1]
            lx = L[0] + L[3] * bx + L[6] * by + L[9] * cz
            ly = L[1] + L[4] * bx + L[7] * by + L[10] * cz
            lz = L[2] + L[5] * bx + L[8] * by + L[11] * cz
            d = _ray_local(kind, a, b, c, lx, ly, lz, ux, uy, uz)
            g = 1.0
            if d < _INF:
                d = max(d, z_min)
                g = 1.0 / (1.0 - 0.0625 * (R / d) ** 2)
            acc += g
        factors[i] = acc / n_s


@njit(cache=True)
def believed_total_thrust(px: float, py: float, pz: float, qw: float, qx: float, qy: float,
                          qz: float, t0: float, t1: float, t2: float, t3: float,
                          pack: FloatArray, factors: FloatArray) -> float:  # fmt: skip
    """Sum of the rotor thrusts (t0 ... t3) [N] times their believed factors at the pose
    (p_W [m], q_WB [-]) [N], the factors into ``factors``; beyond the rotors' reach
    (:func:`believed_distance` above ``B_FAR``) every factor is 1. Summed left to right,
    as numpy sums four floats."""
    if believed_distance(px, py, pz, pack) > pack[B_FAR]:
        factors[:] = 1.0
        return ((t0 + t1) + t2) + t3
    believed_factors_into(px, py, pz, qw, qx, qy, qz, pack, factors)
    return ((factors[0] * t0 + factors[1] * t1) + factors[2] * t2) + factors[3] * t3


@njit(cache=True)
def believed_total_thrust_of(x: FloatArray, t0: float, t1: float, t2: float, t3: float,
                             pack: FloatArray, factors: FloatArray) -> float:  # fmt: skip
    """:func:`believed_total_thrust` at the pose ``x[0:3]``, ``x[6:10]`` of a navigation
    state [p_W, v_W, q_WB, ...] [N]."""
    return believed_total_thrust(x[0], x[1], x[2], x[6], x[7], x[8], x[9], t0, t1, t2, t3,
                                 pack, factors)  # fmt: skip


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
        """The believed model (:func:`~tetherland.models.aero.aero_reference` reads it)."""
        reach = float(np.max(np.linalg.norm(centres, axis=1))) + radius
        surf = surface_from_config(scenario)
        self.far = FAR_RATIO * radius + reach
        """Beyond this lower bound of the distance to the believed surface every factor is
        taken as 1 [m]."""
        self.packed = pack_believed(
            self.model, self.far, surf.origin, surf.z_S, surf.x_S,
            surf.pipe_radius if surf.kind == "pipe" else 0.0,
        )  # fmt: skip
        """The model packed for the compiled kernels (:func:`pack_believed`)."""
        self._surface = surf
        self._factors, self._ones = np.empty(4), np.ones(4)

    def total_thrust(self, p_W: FloatArray, q_WB: FloatArray, thrusts: FloatArray) -> float:
        """Sum of the rotor ``thrusts`` [N] (out of ground effect) times their believed
        factors at the pose (p_W [m], q_WB [-]) [N].

        Farther than :data:`FAR_RATIO` rotor radii from the believed surface (beyond the
        rotors' reach) the factors are taken as 1 (they differ from it by less than
        2e-4) and the model is not evaluated.
        """
        px, py, pz = np.asarray(p_W, dtype=float).tolist()
        qw, qx, qy, qz = np.asarray(q_WB, dtype=float).tolist()
        t0, t1, t2, t3 = np.asarray(thrusts, dtype=float).tolist()
        return believed_total_thrust(px, py, pz, qw, qx, qy, qz, t0, t1, t2, t3, self.packed,
                                     self._factors)  # fmt: skip

    def total_thrust_of(self, x: FloatArray, thrusts: list[float]) -> float:
        """:meth:`total_thrust` at the pose ``x[0:3]``, ``x[6:10]`` of a navigation state
        [p_W, v_W, q_WB, ...], for four rotor ``thrusts`` as floats [N] (the estimator's
        control-rate path: one compiled call; the same bits)."""
        t0, t1, t2, t3 = thrusts
        return believed_total_thrust_of(x, t0, t1, t2, t3, self.packed, self._factors)

    def beyond_reach(self, p_W: FloatArray) -> bool:
        """True when the pose's centre of mass ``p_W`` [m] is farther than
        :data:`FAR_RATIO` rotor radii (plus the rotors' reach) from the believed surface,
        where every believed factor is taken as exactly 1."""
        return self._distance(p_W) > self.far

    def _distance(self, p_W: FloatArray) -> float:
        """A lower bound of the distance from ``p_W`` to the believed surface patch: to its
        slab, or to the pipe's infinite cylinder [m]."""
        px, py, pz = np.asarray(p_W, dtype=float).tolist()
        return believed_distance(px, py, pz, self.packed)

    def distance_reference(self, p_W: FloatArray) -> float:
        """:meth:`_distance` written plainly with numpy (the compiled form:
        :func:`believed_distance`) [m]."""
        surf = self._surface
        d = np.asarray(p_W, dtype=float) - surf.origin
        if surf.kind != "pipe":
            return float(abs(d @ surf.z_S)) - 2.0 * PATCH_HALF_THICKNESS
        r = surf.pipe_radius
        from_axis = d - (d @ surf.x_S) * surf.x_S + r * surf.z_S
        return float(np.linalg.norm(from_axis)) - r

    def factors_at(self, p_W: FloatArray, q_WB: FloatArray, near: bool = False) -> FloatArray:
        """Believed factor of each rotor at the pose (p_W [m], q_WB [-]) [-] (a view, valid
        until the next call). ``near``: evaluate the model whatever the distance (the
        caller has just found the pose not :meth:`beyond_reach`)."""
        if near:
            px, py, pz = np.asarray(p_W, dtype=float).tolist()
            return self.factors_at_pose([px, py, pz, *np.asarray(q_WB, dtype=float).tolist()])
        self.total_thrust(p_W, q_WB, self._ones)
        return self._factors

    def factors_at_pose(self, pose: list[float]) -> FloatArray:
        """:meth:`factors_at` of a pose given as seven floats [p_W (3), q_WB (4)], known
        not :meth:`beyond_reach` [-] (a view, valid until the next call)."""
        believed_factors_into(*pose, self.packed, self._factors)
        return self._factors

    @property
    def factors(self) -> FloatArray:
        """The factors of the last :meth:`total_thrust` [-] (copy)."""
        return self._factors.copy()
