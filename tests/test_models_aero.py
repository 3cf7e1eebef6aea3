"""The aero model (models/aero.py) against hand-derived values and its plain reference."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland.models.aero import (
    WALL_RAYS,
    AeroModel,
    ShapeKind,
    _plane_bound,
    _reachable,
    _to_local,
    aero_into,
    aero_reference,
    disk_samples,
    ground_factor,
    ground_plane,
    pack_shape,
    ray_distance_reference,
)
from tetherland.rotations import quat_to_rotmat, rotmat_to_quat

R = 0.1
CENTRES = np.array([[0.2, 0.2, 0.02], [-0.2, 0.2, 0.02], [-0.2, -0.2, 0.02], [0.2, -0.2, 0.02]])


def model(shapes, **kw) -> AeroModel:
    base = dict(
        rotor_centres_B=CENTRES,
        radius=R,
        samples=disk_samples(3, 8),
        shapes=np.atleast_2d(shapes),
        drag=(0.0, 0.0),
        hover_speed=500.0,
        thrust_coefficient=1e-5,
    )
    base.update(kw)
    return AeroModel(**base)


def run(m: AeroModel, qpos, v_W=(0.0, 0.0, 0.0), thrusts=(2.5, 2.5, 2.5, 2.5)):
    factors, acting, wrench = np.empty(4), np.empty(4), np.empty(6)
    aero_into(
        np.asarray(qpos, float),
        np.asarray(v_W, float),
        np.asarray(thrusts, float),
        m.rotor_centres_B,
        m.samples,
        m.shapes,
        m.params,
        factors,
        acting,
        wrench,
    )
    return factors, acting, wrench


def level(p) -> np.ndarray:
    return np.array([*p, 1.0, 0.0, 0.0, 0.0])


def test_cheeseman_bennett_values_and_bound():
    # 1/(1 - (R/4z)^2): z = R -> 16/15, z = 2R -> 64/63; bounded at z = R/2 -> 4/3
    np.testing.assert_allclose(ground_factor([R, 2 * R], R), [16 / 15, 64 / 63], rtol=1e-15)
    assert ground_factor(0.0, R) == pytest.approx(4 / 3)
    assert ground_factor(0.3 * R, R) == ground_factor(0.5 * R, R)
    assert ground_factor(np.inf, R) == 1.0
    assert ground_factor(10 * R, R) - 1.0 < 1e-3  # under 0.1 % from z/R = 10 on


def test_disk_samples_are_equal_area_and_symmetric():
    s = disk_samples(3, 8)
    r2 = np.sum(s**2, axis=1)
    assert np.all(r2 < 1.0)
    # the mean of r^2 over the unit disk's area is 1/2; equal-area rings hit it exactly
    assert np.mean(r2) == pytest.approx(0.5, rel=1e-12)
    # no point on the axes, half of them on each side of either axis
    assert np.sum(s[:, 0] > 0) == np.sum(s[:, 0] < 0) == 12
    assert np.sum(s[:, 1] > 0) == np.sum(s[:, 1] < 0) == 12


def test_level_rotors_over_the_ground_get_cheeseman_bennett():
    m = model(ground_plane(0.0))
    for z in (0.06, 0.1, 0.3):
        f, acting, _ = run(m, level((0.0, 0.0, z - 0.02)))
        np.testing.assert_allclose(f, 1.0 / (1.0 - (R / (4 * z)) ** 2), rtol=1e-13)
        np.testing.assert_allclose(acting, 2.5 * f, rtol=1e-15)


def test_a_disk_half_over_an_edge_gets_the_mean_of_its_two_halves():
    # box top face at z = 0 covering x < 0; rotor 0 centred over the edge x = 0 at height
    # z; the other half sees the ground plane at depth H below the disk
    z, H = 0.08, 2.0
    box = pack_shape(ShapeKind.BOX, (-1.0, 0.0, -0.05), np.eye(3), (1.0, 1.0, 0.05))
    m = model(np.vstack((box, ground_plane(-(H - z)))))
    p = np.array([-0.2, -0.2, z - 0.02])  # rotor 0 at (0, 0, z)
    f, _, _ = run(m, level(p))
    cb = lambda d: 1.0 / (1.0 - (R / (4 * d)) ** 2)  # noqa: E731
    assert f[0] == pytest.approx(0.5 * (cb(z) + cb(H)), rel=1e-13)
    assert f[1] == pytest.approx(cb(z), rel=1e-13)  # x = -0.2: fully over the box


def test_over_a_pipe_the_factor_follows_the_disk_coverage():
    # horizontal pipe of radius r along x, top line at z = 0; rotor 0 level at height h,
    # centred a off the top line: each point (x, y) of the disk is above the pipe at
    # h + r - sqrt(r^2 - y^2) for |y| < r and else sees the ground far below
    r, h, a = 0.12, 0.07, 0.05
    pipe = pack_shape(
        ShapeKind.CYLINDER,
        (0.0, 0.0, -r),
        quat_to_rotmat(
            rotmat_to_quat(np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]))
        ),
        (r, 5.0, 0.0),
    )
    m = model(np.vstack((pipe, ground_plane(-50.0))), samples=disk_samples(8, 32))
    p = np.array([0.0 - 0.2, a - 0.2, h - 0.02])
    f, _, _ = run(m, level(p))
    # the exact area average by a fine midpoint rule in polar coordinates
    n = 800
    rho = (np.arange(n) + 0.5) / n * R
    th = (np.arange(n) + 0.5) / n * 2 * math.pi
    RR, TT = np.meshgrid(rho, th, indexing="ij")
    y = a + RR * np.sin(TT)
    depth = np.where(np.abs(y) < r, h + r - np.sqrt(np.maximum(r * r - y * y, 0.0)), 50.0 + h)
    g = ground_factor(depth, R)
    exact = float(np.sum(g * RR) / np.sum(RR))
    assert abs(f[0] - exact) < 0.01 * (exact - 1.0)
    # the default 24 samples stay within 10 % of the effect
    f24, _, _ = run(model(np.vstack((pipe, ground_plane(-50.0)))), level(p))
    assert abs(f24[0] - exact) < 0.1 * (exact - 1.0)


def test_a_surface_above_the_rotor_gives_the_ceiling_effect():
    # a box whose bottom face is at height z_c above rotor 0's disk
    z_c = 0.09
    box = pack_shape(ShapeKind.BOX, (0.2, 0.2, 0.02 + z_c + 0.05), np.eye(3), (0.5, 0.5, 0.05))
    f, _, _ = run(model(box, ceiling_coefficient=0.1), level((0.0, 0.0, 0.0)))
    assert f[0] == pytest.approx(1.0 / (1.0 - 0.1 * (R / z_c) ** 2), rel=1e-13)
    f, _, _ = run(model(box, ceiling_coefficient=0.0), level((0.0, 0.0, 0.0)))
    assert f[0] == 1.0


def test_rotor_drag_opposes_the_air_velocity_in_the_rotor_plane():
    rng = np.random.default_rng(3)
    m = model(ground_plane(-100.0), ground_effect=False, drag=(0.4, 0.3))
    for _ in range(20):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        v = rng.normal(size=3)
        f, _, wrench = run(m, [0, 0, 0, *q], v, np.full(4, 1e-5 * 500.0**2))  # hover speed
        R_WB = quat_to_rotmat(q)
        v_B = R_WB.T @ v
        F_B = R_WB.T @ wrench[:3]
        np.testing.assert_allclose(F_B, [-0.4 * v_B[0], -0.3 * v_B[1], 0.0], atol=1e-13)
        assert wrench[:3] @ v <= 0.0
        np.testing.assert_array_equal(f, 1.0)
    # linear in the mean rotor speed: half the speed, half the drag
    _, _, w_half = run(m, level((0, 0, 0)), (1.0, 0, 0), np.full(4, 1e-5 * 250.0**2))
    assert w_half[0] == pytest.approx(-0.2)


def test_a_wall_beside_a_rotor_pulls_it_toward_the_wall():
    # a vertical wall (box) with its face at x = x_w, level vehicle: rotor 0 at x = 0.2
    x_w = 0.2 + 0.15
    box = pack_shape(ShapeKind.BOX, (x_w + 0.05, 0.0, 0.0), np.eye(3), (0.05, 2.0, 2.0))
    m = model(box, ground_effect=False, wall_effect=True, wall_coefficient=0.05)
    _, _, wrench = run(m, level((0.0, 0.0, -0.02)), thrusts=(2.0, 0.0, 0.0, 0.0))
    # the rays nearest the normal are at +-pi/WALL_RAYS from it: d = 0.15 / cos(pi/16)
    d = 0.15 / math.cos(math.pi / WALL_RAYS)
    np.testing.assert_allclose(wrench[:3], [0.05 * 2.0 * (R / d) ** 2, 0.0, 0.0], atol=1e-14)
    # applied at rotor 0 (0.2, 0.2, 0.02): torque r x F
    np.testing.assert_allclose(wrench[3:], np.cross(CENTRES[0], wrench[:3]), atol=1e-15)


@pytest.mark.parametrize("seed", range(4))
def test_kernel_matches_the_plain_reference(seed):
    rng = np.random.default_rng(seed)
    shapes = np.vstack(
        (
            ground_plane(-0.3),
            pack_shape(
                ShapeKind.BOX,
                rng.normal(0, 0.2, 3),
                quat_to_rotmat(rng.normal(size=4) / 2),
                (0.4, 0.3, 0.05),
            ),
            pack_shape(
                ShapeKind.CYLINDER,
                rng.normal(0, 0.2, 3),
                quat_to_rotmat(rng.normal(size=4) / 2),
                (0.15, 0.6, 0.0),
            ),
        )
    )
    for row in shapes[1:]:  # normalise the random rotations
        row[4:13] = quat_to_rotmat(rotmat_to_quat(row[4:13].reshape(3, 3))).reshape(9)
    m = model(
        shapes, wall_effect=True, wall_coefficient=0.05, drag=(0.4, 0.45), ceiling_coefficient=0.08
    )
    for _ in range(25):
        q = rng.normal(size=4)
        qpos = np.array([*rng.normal(0, 0.3, 3), *(q / np.linalg.norm(q))])
        v = rng.normal(size=3)
        thrusts = rng.uniform(0.0, 5.0, 4)
        f, acting, wrench = run(m, qpos, v, thrusts)
        ref = aero_reference(m, qpos, v, thrusts)
        np.testing.assert_allclose(f, ref.factors, rtol=1e-12)
        np.testing.assert_allclose(acting, ref.thrusts, rtol=1e-12)
        np.testing.assert_allclose(wrench[:3], ref.force_W, atol=1e-12)
        np.testing.assert_allclose(wrench[3:], ref.torque_B, atol=1e-12)
        assert np.all(f <= m.factor_bound * (1 + 1e-12)) and np.all(f >= 1.0)


def _local_frames(shapes, qpos):
    """The kernel's per-shape local frames of the pose (see models/aero.py ``_to_local``)."""
    loc = np.empty((shapes.shape[0], 12))
    _to_local(shapes, qpos[0], qpos[1], qpos[2], quat_to_rotmat(qpos[3:7]), loc)
    return loc


@pytest.mark.parametrize("seed", range(3))
def test_a_culled_shape_is_missed_by_every_ray_of_the_disk(seed):
    # _reachable may drop a shape for a rotor only when no ray of its disk hits it, and a
    # plane's bound must lie below every ray's distance: check both on a dense disk (far
    # more points than the kernel's samples)
    rng = np.random.default_rng(seed)
    dense = disk_samples(16, 64) * (1.0 - 1e-12)  # strictly inside the unit disk
    culled = kept = bounded = 0
    for _ in range(60):
        kind = ShapeKind.BOX if rng.random() < 0.5 else ShapeKind.CYLINDER
        size = (0.3, 0.2, 0.05) if kind is ShapeKind.BOX else (0.15, 0.4, 0.0)
        shapes = np.vstack((
            ground_plane(rng.uniform(-1.0, 0.0)),
            pack_shape(kind, rng.normal(0, 0.5, 3), quat_to_rotmat(rotmat_to_quat(
                quat_to_rotmat(rng.normal(size=4) / 2))), size),
        ))  # fmt: skip
        q = rng.normal(0, 0.4, 4) + np.array([2.0, 0.0, 0.0, 0.0])  # near level
        qpos = np.array([*rng.normal(0, 0.3, 3), *(q / np.linalg.norm(q))])
        loc = _local_frames(shapes, qpos)
        R_WB = quat_to_rotmat(qpos[3:7])
        for c_B in CENTRES:
            pts = qpos[:3] + R_WB @ c_B + R * (np.outer(dense[:, 0], R_WB[:, 0])
                                               + np.outer(dense[:, 1], R_WB[:, 1]))  # fmt: skip
            for k in range(2):
                for sign in (-1.0, 1.0):
                    if _reachable(shapes, loc, k, *c_B, sign, R):
                        kept += 1
                        if k == 0:  # the plane: its bound is below every ray's distance
                            d = ray_distance_reference(shapes[k], pts, sign * R_WB[:, 2])
                            bound = _plane_bound(loc, k, *c_B, sign, R)
                            assert 0.0 <= bound <= d.min()
                            bounded += bound > 0.0
                        continue
                    culled += 1
                    d = ray_distance_reference(shapes[k], pts, sign * R_WB[:, 2])
                    assert np.all(np.isinf(d)), (k, sign)
    assert culled > 50 and kept > 50 and bounded > 50  # every branch was exercised


def test_a_shape_beside_the_rotors_leaves_the_factors_bit_identical():
    # a box whose shadow misses every disk is culled: the same bits as without it
    ground = ground_plane(-0.3)
    beside = pack_shape(ShapeKind.BOX, (1.0, 0.0, -0.25), np.eye(3), (0.4, 0.4, 0.05))
    qpos = level((0.0, 0.0, 0.0))
    assert 0.2 + R < 1.0 - 0.4  # the nearest disk edge is short of the box's edge
    with_box = run(model(np.vstack((ground, beside))), qpos)
    without = run(model(ground), qpos)
    for a, b in zip(with_box, without, strict=True):
        assert np.array_equal(a, b)
    # moved under the rotors it acts: the factor of the rotors over it grows
    under = pack_shape(ShapeKind.BOX, (0.2, 0.0, -0.25), np.eye(3), (0.4, 0.4, 0.05))
    f_under = run(model(np.vstack((ground, under))), qpos)[0]
    assert np.all(f_under > without[0])


def test_rays_that_leave_a_plane_cull_it():
    # rotors above the ground, level: the inflow rays (+z_B) never meet it
    ground = ground_plane(-0.3)
    qpos = level((0.0, 0.0, 0.0))
    loc = _local_frames(ground[None, :], qpos)
    for c_B in CENTRES:
        assert not _reachable(ground[None, :], loc, 0, *c_B, 1.0, R)
        assert _reachable(ground[None, :], loc, 0, *c_B, -1.0, R)
    # upside down, the wake goes up: then the downward (inflow) side meets the ground
    flipped = np.array([0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0])
    loc = _local_frames(ground[None, :], flipped)
    for c_B in CENTRES:
        assert _reachable(ground[None, :], loc, 0, *c_B, 1.0, R)
        assert not _reachable(ground[None, :], loc, 0, *c_B, -1.0, R)
