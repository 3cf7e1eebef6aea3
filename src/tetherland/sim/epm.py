"""The electro-permanent magnet's pull on the steel plate (docs/mechanism.md, *The
magnet*).

An EPM pulls through the steel its pole face touches: its flux closes through the plate
only where the face lies on it, and the force falls steeply with the air gap (most of it
is gone within a millimetre). The plant therefore pulls on the face, not on the magnet's
contacts: the face is cut into ``EPM_GRID`` x ``EPM_GRID`` equal cells, and each cell
whose centre lies over the plate pulls the face towards the plate, along the plate's
normal, at its centre, with

    f_k = (F / n_cells) w(g_k),  w(g) = 1 for g <= 0, 1 - g / g_r for 0 < g < g_r, else 0,

where F is ``mechanism.magnet_force``, g_k the gap of the cell's centre from the plate's
top face and g_r :data:`tetherland.sim.mjcf.EPM_RANGE`. So a face lying flat on the plate
is held with F, a face tilted on one edge pulls itself flat with what lies within g_r, a
magnet on its side (its face at 90 deg: the cells' centres at least a / EPM_GRID off the
plate, a the face's half side) or on its back pulls nothing, and a magnet half off the
plate's edge holds with the half that lies on it. The contact between the face and the
plate (a stiff pair, no margin) carries the push; this force is the only pull.

:func:`epm_pull_into` runs once per physics step while the EPM is on (compiled);
:func:`epm_pull_reference` is its plain numpy statement, which a test compares with it.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from tetherland.geometry import FloatArray

EPM_GRID = 4
"""Cells along each side of the magnet's face for the pull (16 cells) [-]."""


def cell_offsets(half_side: float, grid: int = EPM_GRID) -> FloatArray:
    """Centres of the face's ``grid`` x ``grid`` cells in the face's plane, (grid^2, 2),
    from the face's centre along the magnet's local x and y [m]."""
    u = (np.arange(grid) + 0.5) / grid * 2.0 - 1.0  # cell centres in (-1, 1)
    uu, vv = np.meshgrid(u, u, indexing="ij")
    return half_side * np.column_stack((uu.ravel(), vv.ravel()))


@njit(cache=True)
def epm_pull_into(face_W: FloatArray, R_WM: FloatArray, com_W: FloatArray,
                  cells: FloatArray, top_W: FloatArray, R_WP: FloatArray,
                  half_plate: float, force: float, reach: float,
                  out: FloatArray) -> float:  # fmt: skip
    """Write the EPM's pull on the magnet into ``out`` (6: force F_W at the centre of
    mass, then torque about it, MuJoCo's ``xfrc_applied`` row) [N, N m]; returns the
    pull's size along the plate's normal [N].

    Parameters
    ----------
    face_W : (3,) array
        Centre of the magnet's face [m].
    R_WM : (9,) array
        The magnet's rotation, row-major (MuJoCo's ``xmat`` row); its local x and y span
        the face.
    com_W : (3,) array
        The magnet's centre of mass [m].
    cells : (n, 2) array
        :func:`cell_offsets` [m].
    top_W : (3,) array
        Centre of the plate's top face [m].
    R_WP : (9,) array
        The plate's rotation, row-major; its local z is the top face's outward normal.
    half_plate : float
        Half side of the square plate [m].
    force : float
        Holding force F of the face lying flat on the plate [N].
    reach : float
        Gap g_r at which a cell's pull has fallen to zero [m].
    out : (6,) array
        Written.
    """
    nx, ny, nz = R_WP[2], R_WP[5], R_WP[8]
    px, py, pz = R_WP[0], R_WP[3], R_WP[6]
    qx, qy, qz = R_WP[1], R_WP[4], R_WP[7]
    ax, ay, az = R_WM[0], R_WM[3], R_WM[6]
    bx, by, bz = R_WM[1], R_WM[4], R_WM[7]
    share = force / cells.shape[0]
    total = 0.0
    tx = ty = tz = 0.0
    for k in range(cells.shape[0]):
        u, v = cells[k, 0], cells[k, 1]
        cx = face_W[0] + u * ax + v * bx
        cy = face_W[1] + u * ay + v * by
        cz = face_W[2] + u * az + v * bz
        dx, dy, dz = cx - top_W[0], cy - top_W[1], cz - top_W[2]
        if abs(dx * px + dy * py + dz * pz) > half_plate:
            continue
        if abs(dx * qx + dy * qy + dz * qz) > half_plate:
            continue
        gap = dx * nx + dy * ny + dz * nz
        if gap >= reach:
            continue
        f = share if gap <= 0.0 else share * (1.0 - gap / reach)
        total += f
        rx, ry, rz = cx - com_W[0], cy - com_W[1], cz - com_W[2]
        # the cell pulls with -f n at its centre: torque r x (-f n)
        tx -= f * (ry * nz - rz * ny)
        ty -= f * (rz * nx - rx * nz)
        tz -= f * (rx * ny - ry * nx)
    out[0], out[1], out[2] = -total * nx, -total * ny, -total * nz
    out[3], out[4], out[5] = tx, ty, tz
    return total


def epm_pull_reference(face_W: FloatArray, R_WM: FloatArray, com_W: FloatArray,
                       cells: FloatArray, top_W: FloatArray, R_WP: FloatArray,
                       half_plate: float, force: float, reach: float) -> FloatArray:  # fmt: skip
    """The wrench of :func:`epm_pull_into` in numpy, (6,): force F_W, torque about the
    centre of mass [N, N m]."""
    R_M, R_P = np.reshape(R_WM, (3, 3)), np.reshape(R_WP, (3, 3))
    centres = face_W + cells @ R_M[:, 0:2].T
    rel = centres - top_W
    over = np.all(np.abs(rel @ R_P[:, 0:2]) <= half_plate, axis=1)
    gap = rel @ R_P[:, 2]
    w = np.clip(1.0 - np.maximum(gap, 0.0) / reach, 0.0, 1.0) * over
    f = -(force / len(cells)) * w[:, None] * R_P[:, 2]
    return np.concatenate((f.sum(axis=0), np.cross(centres - com_W, f).sum(axis=0)))
