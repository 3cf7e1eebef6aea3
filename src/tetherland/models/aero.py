"""Rotors near surfaces and rotor drag: published models, per rotor, over real shapes.

Ground effect (Cheeseman and Bennett 1955). A rotor of radius R whose wake meets a
surface at distance z along its axis gives, at the same speed,
T_IGE / T_OGE = 1 / (1 - (R / (4 z))^2). The formula comes from an image source and holds
for z/R above about 0.5; below that it grows without bound (z = R/4 is a pole). We
evaluate it at max(z, z_min) with z_min = R/2 by default (:data:`Z_MIN_RATIO`), where
it is 4/3: the largest measured in-ground-effect thrust ratios of small rotors at
z/R ~ 0.5 lie near 1.3, and a landed vehicle of this project has its rotors at
z/R ~ 1.3, well above the bound.

Partial ground effect (Sanchez-Cuevas, Heredia and Ollero 2017). A rotor partly over a
surface (over an edge, or over a pipe's curvature) gets less. We sample the disk at
equal-area points (:func:`disk_samples`), cast a ray from each point along the wake
(-z_B) to the real shapes (finite box, finite cylinder, the ground plane), evaluate the
factor with that point's own distance, and average: a disk half over an edge at height z
gets (1 + factor(z)) / 2, the covered area fraction weighting, as a first model.

Ceiling effect (Hsiao and Chirarattananon 2019). A surface on the inflow side (+z_B)
raises a small rotor's thrust at a given speed. We use the image-source form of the
same kind, 1 / (1 - k_c (R / z_c)^2) with z_c the distance along +z_B, bounded at the
same z_c >= z_min; ``k_c = 1/16`` (default) makes it the mirror of the ground effect.
Hsiao and Chirarattananon report that the ceiling effect is the stronger of the two at
the same distance: raise ``k_c`` to model a measured rotor.

Wall effect (a documented simple model, off by default). A wall across the disk plane
(its normal in the rotor plane) draws the rotor toward it; wall-proximity studies
(e.g. Yang et al. 2025, "Wall Inspector", who model and compensate a suction force that
grows with rotor speed and falls with wall distance) report a force of a few percent of
the thrust. We cast :data:`WALL_RAYS` rays in the rotor plane from the rotor centre and
take F_i = k_w f_i (R / max(d, R))^2 n with d the shortest hit distance and n the unit
sum of the ray directions weighted by (R / max(d_j, R))^2 (toward the wall): a force at
the rotor centre, proportional to the rotor's thrust, inverse-square in the distance,
bounded when the disk edge touches the wall. The coefficient k_w is an assumption.

Rotor drag (Faessler, Franchi and Scaramuzza 2018; rotorpy's multirotor). A spinning rotor
moving through the air at v_air gets a force opposite to the velocity's part in the rotor
plane: F_d = -R_WB D R_WB^T v_air, D = diag(d_x, d_y, 0). rotorpy applies it per rotor,
linear in the rotor speed (F_i = -k_d w_i (I - z_B z_B^T) v); we take D as the value at
the hover speed w_h and scale it with the mean rotor speed: D(w) = D sum(w_i) / (4 w_h).

Shapes are packed for the kernels as rows of :data:`SHAPE_WIDTH` floats
(:func:`pack_shape`): [kind, centre (3), R_WL row-major (9), size (3)], with ``kind`` one
of :class:`ShapeKind`, R_WL the shape's local frame in F_W and size its half sizes (box),
(radius, half length, 0) (cylinder, axis local z) or unused (plane: solid below its local
z axis through the centre). The per-step kernel is :func:`aero_into`; beside it sits its
plain reference :func:`aero_reference` (numpy, vectorised over the samples), checked
against it by a property test; :func:`aero_work_into` is the same kernel in a caller's
workspace (the plant's per-step kernel, :mod:`tetherland.sim.step_kernel`).
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from tetherland.config import VehicleConfig
from tetherland.geometry import FloatArray
from tetherland.models.airframe import PROP_HEIGHT, PROP_RADIUS_FRACTION
from tetherland.models.quadrotor import RotorLayout
from tetherland.rotations import quat_to_rotmat

Z_MIN_RATIO = 0.5
"""Default lower bound of the distance used in the ground and ceiling factors, z_min / R."""
CHEESEMAN_BENNETT = 1.0 / 16.0
"""The coefficient of (R/z)^2 in Cheeseman and Bennett's ground effect, (1/4)^2."""
WALL_RAYS = 16
"""In-plane rays per rotor for the wall effect."""
SHAPE_WIDTH = 16
"""Floats per packed shape."""
PARAM_WIDTH = 10
"""Floats in the packed scalar parameters (:func:`pack_params`)."""
_INF = math.inf


class ShapeKind(enum.IntEnum):
    """Kind of a packed shape."""

    PLANE = 0
    """Infinite plane, solid below its local z axis (the ground)."""
    BOX = 1
    """Box with half sizes (a, b, c) along its local axes."""
    CYLINDER = 2
    """Finite cylinder of radius r and half length h along its local z axis."""


@dataclass(frozen=True)
class AeroModel:
    """Everything the aero kernel needs about one vehicle and one scene.

    Attributes
    ----------
    rotor_centres_B : (4, 3) array
        Centre of each rotor disk in F_B [m].
    radius : float
        Rotor radius R [m].
    samples : (S, 2) array
        Sample points on the unit disk (x, y) (multiplied by R) [-].
    shapes : (n, SHAPE_WIDTH) array
        The surfaces, packed (:func:`pack_shape`).
    ground_effect, wall_effect : bool
        Which surface effects act (the ceiling effect comes with the ground effect).
    z_min_ratio : float
        z_min / R of the bound [-].
    ceiling_coefficient : float
        k_c [-].
    wall_coefficient : float
        k_w [-].
    drag : (float, float)
        (d_x, d_y) at the hover rotor speed [N s/m].
    hover_speed : float
        w_h with 4 c_f w_h^2 = m g [rad/s].
    thrust_coefficient : float
        c_f [N/(rad/s)^2].
    """

    rotor_centres_B: FloatArray
    radius: float
    samples: FloatArray
    shapes: FloatArray
    ground_effect: bool = True
    wall_effect: bool = False
    z_min_ratio: float = Z_MIN_RATIO
    ceiling_coefficient: float = CHEESEMAN_BENNETT
    wall_coefficient: float = 0.0
    drag: tuple[float, float] = (0.0, 0.0)
    hover_speed: float = 1.0
    thrust_coefficient: float = 1.0

    @property
    def params(self) -> FloatArray:
        """The scalar parameters packed for :func:`aero_into` (:func:`pack_params`)."""
        return pack_params(self)

    @property
    def factor_bound(self) -> float:
        """Largest surface factor: ground and ceiling both at z = z_min [-]."""
        z2 = self.z_min_ratio**2
        return 1.0 / ((1.0 - CHEESEMAN_BENNETT / z2) * (1.0 - self.ceiling_coefficient / z2))


def rotor_disks(vehicle: VehicleConfig, radius: float | None = None) -> tuple[FloatArray, float]:
    """Centres of the rotor disks in F_B (4, 3) [m] and their radius [m] (by default the
    rotor guards' radius, :data:`~tetherland.models.airframe.PROP_RADIUS_FRACTION` times
    the arm length), the disks at the guards' height above the rotor sites."""
    centres = RotorLayout.from_config(vehicle).positions_B + np.array([0.0, 0.0, PROP_HEIGHT])
    return centres, (PROP_RADIUS_FRACTION * vehicle.arm_length if radius is None else radius)


def ground_factor(z: ArrayLike, radius: float, z_min_ratio: float = Z_MIN_RATIO) -> FloatArray:
    """Cheeseman-Bennett T_IGE/T_OGE = 1 / (1 - (R / (4 max(z, z_min)))^2) [-].

    Parameters
    ----------
    z : array_like
        Distance from the rotor to the surface along its axis [m]; ``inf`` for no surface.
    radius : float
        Rotor radius R [m].
    z_min_ratio : float
        z_min / R (> 1/4, the pole) [-].
    """
    return image_factor(z, radius, CHEESEMAN_BENNETT, z_min_ratio)


def image_factor(
    z: ArrayLike, radius: float, coefficient: float, z_min_ratio: float = Z_MIN_RATIO
) -> FloatArray:
    """1 / (1 - k (R / max(z, z_min))^2), the image-source form of ground and ceiling [-]."""
    zz = np.maximum(np.asarray(z, dtype=float), z_min_ratio * radius)
    return 1.0 / (1.0 - coefficient * (radius / zz) ** 2)


def disk_samples(rings: int, sectors: int) -> FloatArray:
    """Equal-area sample points on the unit disk, (rings * sectors, 2) [-].

    Ring m at radius sqrt((m + 1/2) / rings), sector j at angle (j + 1/2) 2 pi / sectors:
    every point stands for the same area, and the pattern is symmetric about the lines at
    multiples of 2 pi / sectors through the centre (no point on them), so a disk whose
    centre lies on a straight edge along such a line has exactly half its points on each
    side.
    """
    if rings < 1 or sectors < 1:
        raise ValueError(f"disk_samples needs rings >= 1 and sectors >= 1, got {rings}, {sectors}")
    r = np.sqrt((np.arange(rings) + 0.5) / rings)
    a = (np.arange(sectors) + 0.5) * 2.0 * math.pi / sectors
    rr, aa = np.meshgrid(r, a, indexing="ij")
    return np.column_stack((np.ravel(rr * np.cos(aa)), np.ravel(rr * np.sin(aa))))


def pack_shape(
    kind: ShapeKind, centre: ArrayLike, R_WL: ArrayLike, size: ArrayLike = (0.0, 0.0, 0.0)
) -> FloatArray:
    """One shape as a row of :data:`SHAPE_WIDTH` floats (see the module doc)."""
    row = np.empty(SHAPE_WIDTH)
    row[0] = float(kind)
    row[1:4] = np.asarray(centre, dtype=float)
    row[4:13] = np.asarray(R_WL, dtype=float).reshape(9)
    row[13:16] = np.asarray(size, dtype=float)
    return row


def ground_plane(z: float) -> FloatArray:
    """The horizontal ground plane at height ``z`` [m], packed."""
    return pack_shape(ShapeKind.PLANE, (0.0, 0.0, z), np.eye(3))


# scalar parameters: R, z_min, k_c, k_w, d_x, d_y, 1/(4 w_h), c_f, ground on, wall on
P_R, P_ZMIN, P_KC, P_KW, P_DX, P_DY, P_INV4WH, P_CF, P_GROUND, P_WALL = range(PARAM_WIDTH)


def pack_params(model: AeroModel) -> FloatArray:
    """The scalar parameters of ``model`` in the order of the ``P_*`` offsets."""
    p = np.empty(PARAM_WIDTH)
    p[P_R] = model.radius
    p[P_ZMIN] = model.z_min_ratio * model.radius
    p[P_KC] = model.ceiling_coefficient
    p[P_KW] = model.wall_coefficient
    p[P_DX], p[P_DY] = np.asarray(model.drag, dtype=float)
    p[P_INV4WH] = 1.0 / (4.0 * model.hover_speed)
    p[P_CF] = model.thrust_coefficient
    p[P_GROUND] = 1.0 if model.ground_effect else 0.0
    p[P_WALL] = 1.0 if model.wall_effect else 0.0
    return p


# ------------------------------------------------------------------ compiled kernel
@njit(cache=True, inline="always")
def _slab(o: float, u: float, h: float, t0: float, t1: float) -> tuple[float, float]:
    """Clip [t0, t1] to the ray's stay in the slab |o + t u| <= h (empty: t0 > t1)."""
    if u == 0.0:
        if o < -h or o > h:
            return _INF, -_INF
        return t0, t1
    e, f = (-h - o) / u, (h - o) / u
    if e > f:
        e, f = f, e
    return max(t0, e), min(t1, f)


@njit(cache=True, inline="always")
def _ray_local(kind: float, a: float, b: float, c: float, lx: float, ly: float, lz: float,
               ux: float, uy: float, uz: float) -> float:  # fmt: skip
    """Distance along the unit ray l + t u (t >= 0, shape-local coordinates) to a shape of
    ``kind`` and size (a, b, c); 0 inside; inf if missed."""
    if kind == 0.0:  # plane z_L = 0, solid below
        if lz <= 0.0:
            return 0.0
        if uz >= 0.0:
            return _INF
        return -lz / uz
    if kind == 1.0:  # box: slabs
        # (an empty interval stays empty: each slab only shrinks it, so stop at the first)
        t0, t1 = _slab(lx, ux, a, 0.0, _INF)
        if t0 > t1:
            return _INF
        t0, t1 = _slab(ly, uy, b, t0, t1)
        if t0 > t1:
            return _INF
        t0, t1 = _slab(lz, uz, c, t0, t1)
        return t0 if t0 <= t1 else _INF
    # cylinder: radius a, half length b along local z
    r, h = a, b
    rho2 = lx * lx + ly * ly
    if rho2 <= r * r and -h <= lz <= h:
        return 0.0
    best = _INF
    q = ux * ux + uy * uy
    if q > 0.0:
        p = lx * ux + ly * uy
        disc = p * p - q * (rho2 - r * r)
        if disc >= 0.0:
            t = (-p - math.sqrt(disc)) / q  # entry through the side
            if t >= 0.0 and -h <= lz + t * uz <= h:
                best = t
    if uz != 0.0:
        for zc in (-h, h):
            t = (zc - lz) / uz
            if 0.0 <= t < best:
                x, y = lx + t * ux, ly + t * uy
                if x * x + y * y <= r * r:
                    best = t
    return best


@njit(cache=True)
def _to_local(shapes: FloatArray, px: float, py: float, pz: float, R_WB: FloatArray,
              out: FloatArray) -> None:  # fmt: skip
    """Per shape: the vehicle position and the columns of R_WB in shape-local coordinates,
    out[k] = [p_L (3), x_L (3), y_L (3), z_L (3)]."""
    for k in range(shapes.shape[0]):
        s = shapes[k]
        dx, dy, dz = px - s[1], py - s[2], pz - s[3]
        for row in range(3):  # local axis ``row`` of the shape: (s[4+row], s[7+row], s[10+row])
            ex, ey, ez = s[4 + row], s[7 + row], s[10 + row]
            out[k, row] = ex * dx + ey * dy + ez * dz
            for col in range(3):
                out[k, 3 + 3 * col + row] = (
                    ex * R_WB[0, col] + ey * R_WB[1, col] + ez * R_WB[2, col]
                )


CULL_MARGIN = 1e-9
"""Margin of the exact culling tests [m]: a shape is skipped only when it misses every ray
of a disk by more than this (far above the rounding of the ray tests)."""


@njit(cache=True)
def _reachable(shapes: FloatArray, loc: FloatArray, k: int, bx: float, by: float, bz: float,
               sign: float, radius: float) -> bool:  # fmt: skip
    """False when no ray along ``sign`` z_B from the disk of ``radius`` [m] about the body
    point (bx, by, bz) (normal to z_B) can hit shape ``k``: the shape lies wholly behind
    the disk's plane (its support function along sign z_B is below it), or its shadow
    along z_B on that plane is separated from the disk along x_B, y_B or the direction to
    its centre (the box, or the cylinder's bounding box, by more than
    :data:`CULL_MARGIN`), or it is a plane the rays leave with every start above it.
    Culled shapes would give ``inf`` for every ray of the disk, so the nearest distances
    are the same with or without them."""
    s, L = shapes[k], loc[k]
    kind = s[0]
    zx, zy, zz = sign * L[9], sign * L[10], sign * L[11]  # sign z_B in shape-local axes
    # the plane point in local coordinates, and its height along sign z_B
    lx = L[0] + L[3] * bx + L[6] * by + L[9] * bz
    ly = L[1] + L[4] * bx + L[7] * by + L[10] * bz
    lz = L[2] + L[5] * bx + L[8] * by + L[11] * bz
    if kind == 0.0:  # plane z_L = 0, solid below: rays going up (or level) from above miss
        low = lz - radius * math.sqrt(L[5] * L[5] + L[8] * L[8])  # lowest start on the disk
        return not (zz >= 0.0 and low > CULL_MARGIN)
    h0 = -(zx * lx + zy * ly + zz * lz)  # the shape centre's height along sign z_B
    a, b, c = s[13], s[14], s[15]
    if kind == 1.0:
        reach = h0 + a * abs(zx) + b * abs(zy) + c * abs(zz)
    else:
        b, c = a, b  # the cylinder's bounding box (r, r, h)
        reach = h0 + a * math.sqrt(max(0.0, 1.0 - zz * zz)) + c * abs(zz)
    if reach <= 0.0:
        return False
    # the shadow: centre offsets and half extents along x_B and y_B (shape-local columns)
    ox = -(L[3] * lx + L[4] * ly + L[5] * lz)
    oy = -(L[6] * lx + L[7] * ly + L[8] * lz)
    gap = radius + CULL_MARGIN
    if abs(ox) > gap + a * abs(L[3]) + b * abs(L[4]) + c * abs(L[5]):
        return False
    if abs(oy) > gap + a * abs(L[6]) + b * abs(L[7]) + c * abs(L[8]):
        return False
    n = math.sqrt(ox * ox + oy * oy)
    if n > 0.0:
        ex, ey = ox / n, oy / n  # toward the centre, in the disk plane
        half = (a * abs(ex * L[3] + ey * L[6]) + b * abs(ex * L[4] + ey * L[7])
                + c * abs(ex * L[5] + ey * L[8]))  # fmt: skip
        if n > gap + half:
            return False
    return True


@njit(cache=True, inline="always")
def _nearest(shapes: FloatArray, loc: FloatArray, bx: float, by: float, bz: float,
             sign: float, axis: int, mask: FloatArray) -> float:  # fmt: skip
    """Shortest distance from the body point (bx, by, bz) (F_B, about the centre of mass)
    along ``sign`` times body axis ``axis`` (0 x, 1 y, 2 z) to any shape whose ``mask``
    entry is >= 0 [m]. The entry is a lower bound of the shape's distance (0 if none is
    known): a shape whose bound is not below the nearest hit so far cannot be nearer and
    is not cast. The shapes are taken last to first (planes usually come first, and have
    a bound; the minimum does not depend on the order)."""
    best = _INF
    j = 3 + 3 * axis
    for k in range(shapes.shape[0] - 1, -1, -1):
        bound = mask[k]
        if bound < 0.0 or bound >= best:
            continue
        # (loc[k, i], not a row view: no view object per shape and sample)
        lx = loc[k, 0] + loc[k, 3] * bx + loc[k, 6] * by + loc[k, 9] * bz
        ly = loc[k, 1] + loc[k, 4] * bx + loc[k, 7] * by + loc[k, 10] * bz
        lz = loc[k, 2] + loc[k, 5] * bx + loc[k, 8] * by + loc[k, 11] * bz
        t = _ray_local(shapes[k, 0], shapes[k, 13], shapes[k, 14], shapes[k, 15], lx, ly, lz,
                       sign * loc[k, j], sign * loc[k, j + 1], sign * loc[k, j + 2])  # fmt: skip
        if t < best:
            best = t
    return best


@njit(cache=True)
def _plane_bound(loc: FloatArray, k: int, bx: float, by: float, bz: float, sign: float,
                 radius: float) -> float:  # fmt: skip
    """A lower bound of the distance along ``sign`` z_B from any point of the disk of
    ``radius`` [m] about the body point (bx, by, bz) to plane shape ``k`` [m]: its lowest
    start height over the plane, less :data:`CULL_MARGIN`, over the ray's descent rate
    (0 when a start may lie on or below it, or the rays do not descend)."""
    L = loc[k]
    uz = sign * L[11]
    if uz >= 0.0:
        return 0.0
    lz = L[2] + L[5] * bx + L[8] * by + L[11] * bz
    low = lz - radius * math.sqrt(L[5] * L[5] + L[8] * L[8]) - CULL_MARGIN
    if low <= 0.0:
        return 0.0
    return low / -uz  # (rounded division is monotone: below every start's -lz / uz)


@njit(cache=True, inline="always")
def _nearest_dir(shapes: FloatArray, loc: FloatArray, bx: float, by: float, bz: float,
                 ux: float, uy: float) -> float:  # fmt: skip
    """As :func:`_nearest` along the in-plane body direction (ux, uy, 0)."""
    best = _INF
    for k in range(shapes.shape[0]):
        lx = loc[k, 0] + loc[k, 3] * bx + loc[k, 6] * by + loc[k, 9] * bz
        ly = loc[k, 1] + loc[k, 4] * bx + loc[k, 7] * by + loc[k, 10] * bz
        lz = loc[k, 2] + loc[k, 5] * bx + loc[k, 8] * by + loc[k, 11] * bz
        t = _ray_local(shapes[k, 0], shapes[k, 13], shapes[k, 14], shapes[k, 15], lx, ly, lz,
                       loc[k, 3] * ux + loc[k, 6] * uy, loc[k, 4] * ux + loc[k, 7] * uy,
                       loc[k, 5] * ux + loc[k, 8] * uy)  # fmt: skip
        if t < best:
            best = t
    return best


def aero_work_size(n_shapes: int) -> int:
    """Floats of the workspace :func:`aero_work_into` needs for ``n_shapes`` shapes."""
    return 9 + 36 * n_shapes


@njit(cache=True)
def aero_into(qpos: FloatArray, v_W: FloatArray, thrusts: FloatArray, centres_B: FloatArray,
              samples: FloatArray, shapes: FloatArray, p: FloatArray, factors: FloatArray,
              acting: FloatArray, wrench: FloatArray) -> None:  # fmt: skip
    """Surface factors, acting thrusts and the extra wrench of one physics step.

    Arguments as for :func:`aero_work_into`, which this calls with a fresh workspace.
    """
    work = np.empty(9 + 36 * shapes.shape[0])
    aero_work_into(qpos, v_W, thrusts, centres_B, samples, shapes, p, factors, acting, wrench,
                   work)  # fmt: skip


@njit(cache=True)
def aero_work_into(qpos: FloatArray, v_W: FloatArray, thrusts: FloatArray,
                   centres_B: FloatArray, samples: FloatArray, shapes: FloatArray, p: FloatArray,
                   factors: FloatArray, acting: FloatArray, wrench: FloatArray,
                   work: FloatArray) -> None:  # fmt: skip
    """Surface factors, acting thrusts and the extra wrench of one physics step, in a
    caller's workspace (no allocation: the plant's per-step kernel).

    Parameters
    ----------
    qpos : (7,) array
        [p_W (3), q_WB (4, w x y z)] of the vehicle [m, -].
    v_W : (3,) array
        Velocity of the centre of mass relative to the air, F_W [m/s].
    thrusts : (4,) array
        Rotor thrusts out of ground effect, c_f w_i^2 [N].
    centres_B : (4, 3) array
        Rotor disk centres in F_B [m].
    samples : (S, 2) array
        Unit-disk sample points (:func:`disk_samples`) [-].
    shapes : (n, SHAPE_WIDTH) array
        Packed shapes [m].
    p : (PARAM_WIDTH,) array
        :func:`pack_params`.
    factors : (4,) array, out
        Surface factor of each rotor, T / T_OGE (1 with the ground effect off) [-].
    acting : (4,) array, out
        factors * thrusts [N].
    wrench : (6,) array, out
        [force F_W (3) at the centre of mass, torque F_B (3)]: rotor drag and wall effect
        [N, N m].
    work : (:func:`aero_work_size`,) array
        Scratch: R_WB, the shapes' local frames and the culling masks (overwritten).
    """
    qw, qx, qy, qz = qpos[3], qpos[4], qpos[5], qpos[6]
    s2 = 2.0 / (qw * qw + qx * qx + qy * qy + qz * qz)
    Rm = work[0:9].reshape((3, 3))
    Rm[0, 0] = 1.0 - s2 * (qy * qy + qz * qz)
    Rm[0, 1] = s2 * (qx * qy - qw * qz)
    Rm[0, 2] = s2 * (qx * qz + qw * qy)
    Rm[1, 0] = s2 * (qx * qy + qw * qz)
    Rm[1, 1] = 1.0 - s2 * (qx * qx + qz * qz)
    Rm[1, 2] = s2 * (qy * qz - qw * qx)
    Rm[2, 0] = s2 * (qx * qz - qw * qy)
    Rm[2, 1] = s2 * (qy * qz + qw * qx)
    Rm[2, 2] = 1.0 - s2 * (qx * qx + qy * qy)
    n_shapes = shapes.shape[0]
    frames = work[9:].reshape((3, n_shapes, 12))
    loc = frames[0]
    _to_local(shapes, qpos[0], qpos[1], qpos[2], Rm, loc)
    down, up = frames[1, :, 0], frames[2, :, 0]
    R = p[P_R]
    z_min = p[P_ZMIN]
    k_c = p[P_KC]
    k_w = p[P_KW]
    ground, wall = p[P_GROUND] != 0.0, p[P_WALL] != 0.0
    n_s = samples.shape[0]
    fx = fy = fz = 0.0
    tx = ty = tz = 0.0
    for i in range(4):
        cx, cy, cz = centres_B[i, 0], centres_B[i, 1], centres_B[i, 2]
        k = 1.0
        if ground:
            any_down = any_up = False
            for s_k in range(n_shapes):  # cull the shapes no ray of the disk can hit
                plane = shapes[s_k, 0] == 0.0
                reach_down = _reachable(shapes, loc, s_k, cx, cy, cz, -1.0, R)
                down[s_k] = -1.0
                if reach_down:
                    down[s_k] = _plane_bound(loc, s_k, cx, cy, cz, -1.0, R) if plane else 0.0
                any_down = any_down or reach_down
                reach_up = k_c > 0.0 and _reachable(shapes, loc, s_k, cx, cy, cz, 1.0, R)
                up[s_k] = -1.0
                if reach_up:
                    up[s_k] = _plane_bound(loc, s_k, cx, cy, cz, 1.0, R) if plane else 0.0
                any_up = any_up or reach_up
            acc = 0.0 if (any_down or any_up) else float(n_s)  # (every factor exactly 1)
            for j in range(n_s if (any_down or any_up) else 0):
                bx, by = cx + R * samples[j, 0], cy + R * samples[j, 1]
                g = 1.0
                if any_down:
                    d = _nearest(shapes, loc, bx, by, cz, -1.0, 2, down)  # along the wake
                    if d < _INF:
                        d = max(d, z_min)
                        g = 1.0 / (1.0 - 0.0625 * (R / d) ** 2)
                if any_up:
                    d = _nearest(shapes, loc, bx, by, cz, 1.0, 2, up)  # the inflow side
                    if d < _INF:
                        d = max(d, z_min)
                        g = g / (1.0 - k_c * (R / d) ** 2)
                acc += g
            k = acc / n_s
        factors[i] = k
        f = k * thrusts[i]
        acting[i] = f
        if wall and f > 0.0:
            d_min, sx, sy = _INF, 0.0, 0.0
            for j in range(WALL_RAYS):
                a = (j + 0.5) * 2.0 * math.pi / WALL_RAYS
                ca, sa = math.cos(a), math.sin(a)
                d = _nearest_dir(shapes, loc, cx, cy, cz, ca, sa)
                if d < _INF:
                    w = (R / max(d, R)) ** 2
                    sx += w * ca
                    sy += w * sa
                    d_min = min(d_min, d)
            norm = math.sqrt(sx * sx + sy * sy)
            if 0.0 < d_min < _INF and norm > 0.0:  # (centre inside a shape: a crash)
                m = k_w * f * (R / max(d_min, R)) ** 2 / norm
                bx, by = m * sx, m * sy  # the pull in F_B (in the rotor plane)
                fx += Rm[0, 0] * bx + Rm[0, 1] * by
                fy += Rm[1, 0] * bx + Rm[1, 1] * by
                fz += Rm[2, 0] * bx + Rm[2, 1] * by
                # torque about the centre of mass in F_B: r_i x (bx, by, 0)
                tx += -cz * by
                ty += cz * bx
                tz += cx * by - cy * bx
    # rotor drag: -R_WB diag(dx, dy, 0) R_WB^T v, scaled by sum(w_i) / (4 w_h)
    scale = 0.0
    c_f = p[P_CF]
    for i in range(4):
        if thrusts[i] > 0.0:
            scale += math.sqrt(thrusts[i] / c_f)
    scale *= p[P_INV4WH]
    vx = Rm[0, 0] * v_W[0] + Rm[1, 0] * v_W[1] + Rm[2, 0] * v_W[2]
    vy = Rm[0, 1] * v_W[0] + Rm[1, 1] * v_W[1] + Rm[2, 1] * v_W[2]
    ax, ay = -scale * p[P_DX] * vx, -scale * p[P_DY] * vy
    wrench[0] = fx + Rm[0, 0] * ax + Rm[0, 1] * ay
    wrench[1] = fy + Rm[1, 0] * ax + Rm[1, 1] * ay
    wrench[2] = fz + Rm[2, 0] * ax + Rm[2, 1] * ay
    wrench[3] = tx
    wrench[4] = ty
    wrench[5] = tz


# ------------------------------------------------------------------ plain reference
def ray_distance_reference(
    shape: FloatArray, origins: FloatArray, direction: ArrayLike
) -> FloatArray:
    """Distances along ``direction`` from each of ``origins`` (n, 3) to one packed shape
    (0 inside, inf when missed), vectorised [m]."""
    kind = ShapeKind(int(shape[0]))
    R_WL = shape[4:13].reshape(3, 3)
    o = (np.atleast_2d(origins) - shape[1:4]) @ R_WL
    u = np.asarray(direction, dtype=float) @ R_WL
    n = o.shape[0]
    with np.errstate(divide="ignore", invalid="ignore"):
        if kind is ShapeKind.PLANE:
            t = np.where(u[2] < 0.0, -o[:, 2] / u[2] if u[2] != 0 else np.inf, np.inf)
            return np.where(o[:, 2] <= 0.0, 0.0, t)
        if kind is ShapeKind.BOX:
            h = shape[13:16]
            lo, hi = np.full(n, -np.inf), np.full(n, np.inf)
            miss = np.zeros(n, dtype=bool)
            for ax in range(3):
                if u[ax] == 0.0:
                    miss |= np.abs(o[:, ax]) > h[ax]
                    continue
                a, b = (-h[ax] - o[:, ax]) / u[ax], (h[ax] - o[:, ax]) / u[ax]
                lo, hi = np.maximum(lo, np.minimum(a, b)), np.minimum(hi, np.maximum(a, b))
            entry = np.maximum(lo, 0.0)
            return np.where(miss | (hi < entry), np.inf, entry)
        r, h = shape[13], shape[14]
        inside = (o[:, 0] ** 2 + o[:, 1] ** 2 <= r * r) & (np.abs(o[:, 2]) <= h)
        best = np.full(n, np.inf)
        a = u[0] ** 2 + u[1] ** 2
        if a > 0.0:
            b = o[:, 0] * u[0] + o[:, 1] * u[1]
            c = o[:, 0] ** 2 + o[:, 1] ** 2 - r * r
            disc = b * b - a * c
            t = (-b - np.sqrt(np.maximum(disc, 0.0))) / a
            ok = (disc >= 0.0) & (t >= 0.0) & (np.abs(o[:, 2] + t * u[2]) <= h)
            best = np.where(ok, t, best)
        if u[2] != 0.0:
            for zc in (-h, h):
                t = (zc - o[:, 2]) / u[2]
                x, y = o[:, 0] + t * u[0], o[:, 1] + t * u[1]
                ok = (t >= 0.0) & (x * x + y * y <= r * r) & (t < best)
                best = np.where(ok, t, best)
        return np.where(inside, 0.0, best)


def nearest_distance_reference(
    shapes: FloatArray, origins: FloatArray, direction: ArrayLike
) -> FloatArray:
    """Shortest distance along ``direction`` from each origin to any of ``shapes`` [m]."""
    out = np.full(np.atleast_2d(origins).shape[0], np.inf)
    for s in np.atleast_2d(shapes):
        out = np.minimum(out, ray_distance_reference(s, origins, direction))
    return out


@dataclass(frozen=True)
class AeroResult:
    """One evaluation of the aero model.

    Attributes
    ----------
    factors : (4,) array
        T / T_OGE of each rotor [-].
    thrusts : (4,) array
        Acting thrusts [N].
    force_W : (3,) array
        Rotor drag plus wall force at the centre of mass, F_W [N].
    torque_B : (3,) array
        Torque of the wall forces about the centre of mass, F_B [N m].
    """

    factors: FloatArray
    thrusts: FloatArray
    force_W: FloatArray
    torque_B: FloatArray


def aero_reference(
    model: AeroModel, qpos: ArrayLike, v_W: ArrayLike, thrusts: ArrayLike
) -> AeroResult:
    """:func:`aero_into` written plainly with numpy (for tests and off-line use)."""
    q = np.asarray(qpos, dtype=float)
    p_W, R_WB = q[0:3], quat_to_rotmat(q[3:7] / np.linalg.norm(q[3:7]))
    f = np.asarray(thrusts, dtype=float)
    R = model.radius
    x_B, y_B, z_B = R_WB.T
    factors = np.ones(4)
    force, torque = np.zeros(3), np.zeros(3)
    for i, c_B in enumerate(np.asarray(model.rotor_centres_B, dtype=float)):
        c_W = p_W + R_WB @ c_B
        if model.ground_effect:
            pts = c_W + R * np.outer(model.samples[:, 0], x_B) + R * np.outer(
                model.samples[:, 1], y_B
            )
            down = nearest_distance_reference(model.shapes, pts, -z_B)
            up = nearest_distance_reference(model.shapes, pts, z_B)
            g = image_factor(down, R, CHEESEMAN_BENNETT, model.z_min_ratio) * image_factor(
                up, R, model.ceiling_coefficient, model.z_min_ratio
            )
            factors[i] = float(np.mean(g))
        if model.wall_effect and factors[i] * f[i] > 0.0:
            a = (np.arange(WALL_RAYS) + 0.5) * 2.0 * math.pi / WALL_RAYS
            dirs = np.outer(np.cos(a), x_B) + np.outer(np.sin(a), y_B)
            d = np.array(
                [nearest_distance_reference(model.shapes, c_W[None, :], u)[0] for u in dirs]
            )
            hit = np.isfinite(d)
            if np.any(hit) and d.min() > 0.0:
                s = ((R / np.maximum(d[hit], R)) ** 2) @ dirs[hit]
                if np.linalg.norm(s) > 0.0:
                    F = (
                        model.wall_coefficient
                        * factors[i]
                        * f[i]
                        * (R / max(float(d[hit].min()), R)) ** 2
                        * s
                        / np.linalg.norm(s)
                    )
                    force += F
                    torque += np.cross(c_B, R_WB.T @ F)
    w_sum = float(np.sum(np.sqrt(np.maximum(f, 0.0) / model.thrust_coefficient)))
    D = np.diag([model.drag[0], model.drag[1], 0.0]) * w_sum / (4.0 * model.hover_speed)
    force += -R_WB @ D @ R_WB.T @ np.asarray(v_W, dtype=float)
    return AeroResult(factors, factors * f, force, torque)
