"""The EPM's pull on the plate (:mod:`tetherland.sim.epm`): the compiled kernel against its
numpy statement, and both against values derived here for a face lying flat, lifted,
tilted on one edge, on its side, on its back and half off the plate."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland.rotations import exp_so3
from tetherland.sim.epm import EPM_GRID, cell_offsets, epm_pull_into, epm_pull_reference

A = 0.02
"""Half side of the face [m]."""
F = 150.0
"""Holding force [N]."""
REACH = 0.001
"""Gap at which a cell's pull is gone [m]."""
HALF_PLATE = 0.075
"""Half side of the plate [m]."""
THICKNESS = 0.01
"""The magnet's thickness (its centre of mass half of it behind the face) [m]."""

R_WP = np.eye(3)
"""The plate: top face at the origin, normal +z."""
TOP = np.zeros(3)


def _pull(R_WM: np.ndarray, face_W: np.ndarray) -> tuple[np.ndarray, float]:
    """(wrench (6,) from the kernel, checked equal to the reference; its normal pull)."""
    com = face_W - 0.5 * THICKNESS * R_WM[:, 2]
    cells = cell_offsets(A)
    args = (face_W, R_WM.ravel(), com, cells, TOP, R_WP.ravel(), HALF_PLATE, F, REACH)
    out = np.empty(6)
    total = epm_pull_into(*args, out)
    assert out == pytest.approx(epm_pull_reference(*args), abs=1e-12)
    assert total == pytest.approx(-out[2], abs=1e-12)  # along -n, n = +z
    return out, total


def _facing_down(tilt: np.ndarray | None = None) -> np.ndarray:
    """The magnet's rotation with its face (local +z) towards the plate (-z_W), turned by
    the rotation vector ``tilt`` (F_W) [-]."""
    R = np.diag([1.0, -1.0, -1.0])
    return R if tilt is None else exp_so3(tilt) @ R


def test_cells_tile_the_face() -> None:
    c = cell_offsets(A)
    assert c.shape == (EPM_GRID**2, 2)
    assert np.allclose(c.mean(axis=0), 0.0)
    step = 2.0 * A / EPM_GRID
    assert np.min(np.abs(c)) == pytest.approx(0.5 * step)  # the centres, not the edges
    assert np.max(np.abs(c)) == pytest.approx(A - 0.5 * step)


def test_flat_on_the_plate_holds_with_the_whole_force_and_no_torque() -> None:
    out, total = _pull(_facing_down(), TOP + np.array([0.01, -0.02, 0.0]))
    assert total == pytest.approx(F)
    assert out[0:2] == pytest.approx([0.0, 0.0], abs=1e-12)
    # the cells are symmetric about the face's centre, which lies on the axis through the
    # centre of mass along the pull: no torque
    assert out[3:6] == pytest.approx(np.zeros(3), abs=1e-12)


@pytest.mark.parametrize("lift", [0.0, 0.25, 0.5, 0.9, 1.0, 1.5])
def test_a_face_lifted_parallel_pulls_in_proportion_to_what_is_left(lift: float) -> None:
    _, total = _pull(_facing_down(), TOP + np.array([0.0, 0.0, lift * REACH]))
    assert total == pytest.approx(F * max(0.0, 1.0 - lift), abs=1e-9)


def test_a_face_tilted_on_one_edge_pulls_itself_flat() -> None:
    """Tilted by theta about x_W with the edge at y = -a on the plate, cell k's gap is
    (a + v_k) sin(theta) (v_k its offset along the face's y towards the lifted edge): with
    every gap below the reach the pull is F (1 - a sin(theta) / reach) (the offsets
    average zero), and the torque about the edge, sum of f_k (a + v_k) cos(theta), turns
    the lifted side down."""
    theta = math.radians(1.0)
    R = _facing_down(np.array([-theta, 0.0, 0.0]))
    y_face = R[:, 1]  # the face's local y (-y_W turned up by theta): the lifted side
    assert y_face[2] == pytest.approx(math.sin(theta))
    face = TOP + A * y_face  # the edge at -a (local y) on the plate
    edge = face - A * y_face
    assert edge[2] == pytest.approx(0.0, abs=1e-15)
    out, total = _pull(R, face)
    v = cell_offsets(A)[:, 1]
    gaps = (A + v) * math.sin(theta)
    assert gaps.max() < REACH
    assert total == pytest.approx(F * (1.0 - A * math.sin(theta) / REACH), rel=1e-12)
    # the moment about the edge, on the axis u about which a positive turn lowers the
    # lifted side (u x y_face points down): each cell's -f_k z at its arm (a + v_k)
    # cos(theta) gives +f_k (a + v_k) cos(theta)
    u = np.cross(y_face, [0.0, 0.0, -1.0])
    u /= np.linalg.norm(u)
    f_k = F / len(v) * (1.0 - gaps / REACH)
    com = face - 0.5 * THICKNESS * R[:, 2]
    about_edge = out[3:6] + np.cross(com - edge, out[0:3])
    expected = float(np.sum(f_k * (A + v) * math.cos(theta)))
    assert float(about_edge @ u) == pytest.approx(expected, rel=1e-9)
    assert expected > 0.0  # the lifted side is pulled down: the face turns flat


def test_a_magnet_on_its_side_or_its_back_pulls_nothing() -> None:
    # on its side: the face stands at 90 deg, its cells' centres at least a / grid up
    side = _facing_down(np.array([0.5 * math.pi, 0.0, 0.0]))
    lowest = A / EPM_GRID
    assert lowest > REACH
    _, total = _pull(side, TOP + A * np.array([0.0, 0.0, 1.0]))
    assert total == 0.0
    # on its back: the face looks away, the thickness above the plate
    back = np.diag([1.0, 1.0, 1.0])
    _, total = _pull(back, TOP + np.array([0.0, 0.0, THICKNESS]))
    assert total == 0.0


def test_half_off_the_plate_holds_with_half() -> None:
    """The face's centre on the plate's edge, its sides along the plate's: the cells of
    one half lie over the plate (the grid has an even count: none on the edge)."""
    assert EPM_GRID % 2 == 0
    _, total = _pull(_facing_down(), TOP + np.array([HALF_PLATE, 0.0, 0.0]))
    assert total == pytest.approx(0.5 * F)


def test_kernel_equals_reference_on_random_poses() -> None:
    rng = np.random.default_rng(7)
    for _ in range(200):
        R = _facing_down(rng.normal(scale=0.05, size=3))
        face = np.array([*rng.uniform(-0.09, 0.09, 2), rng.uniform(-0.0005, 0.0015)])
        _pull(R, face)  # asserts the kernel equals the reference
