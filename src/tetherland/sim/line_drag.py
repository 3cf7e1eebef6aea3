"""Air drag on the bar mechanism's hanging line (docs/mechanism.md, *Numerics*).

A 0.6 g/m line of 3 mm is mostly drag: moving broadside at v it is pulled back with
q(v) = 1/2 rho C_d D v^2 per metre, equal to its weight at sqrt(2 mu g / (rho C_d D)),
about 1.6 m/s. Without that force a slack line whipped by a falling hook (folds running
along it at several m/s, its joints turning at 100-300 rad/s, 0.1-0.3 rad per physics
step) gained energy from the explicit integration of its velocity-product terms until
MuJoCo flagged a bad acceleration. The drag is the line's own physics, not a damper
tuned to the step: each link is pushed at its centre of mass against the part of its
velocity normal to its axis (skin friction along the axis is two orders smaller and left
out). The hook is compact and dense (20 g on a few cm): its drag is left out.

:func:`line_drag_into` runs once per physics step (compiled); :func:`line_drag_reference`
is its plain numpy statement, which a test compares with it.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tetherland.geometry import FloatArray

AIR_DENSITY = 1.2
"""Density of air at sea level and 20 deg C [kg/m^3]."""
LINE_DRAG_COEFFICIENT = 1.2
"""Drag coefficient C_d of a braided line in crossflow (a cylinder at Reynolds numbers
of 10^2-10^3: 1.0-1.2; the braid's roughness puts it at the top) [-]."""


def link_drag_factor(radius: float, link_length: float) -> float:
    """k = 1/2 rho C_d (2 r) l_s: a link moving broadside at v is pushed back with k v^2
    [kg/m]."""
    return 0.5 * AIR_DENSITY * LINE_DRAG_COEFFICIENT * 2.0 * radius * link_length


@njit(cache=True)
def line_drag_into(bodies: np.ndarray, root: int, k: float, cvel: FloatArray,
                   xipos: FloatArray, xmat: FloatArray, subtree_com: FloatArray,
                   xfrc: FloatArray) -> None:  # fmt: skip
    """Write each link's drag -k |v_n| v_n into ``xfrc`` (MuJoCo's ``xfrc_applied``, at
    the centre of mass, F_W) [N].

    Parameters
    ----------
    bodies : (N,) int array
        Body ids of the links, each a capsule along its local x.
    root : int
        Id of their root body (``cvel`` is taken at its subtree's centre of mass).
    k : float
        :func:`link_drag_factor` [kg/m].
    cvel, xipos, xmat, subtree_com, xfrc
        MjData's arrays of the same names (the state at the start of the step).
    """
    cx, cy, cz = subtree_com[root, 0], subtree_com[root, 1], subtree_com[root, 2]
    for b in bodies:
        wx, wy, wz = cvel[b, 0], cvel[b, 1], cvel[b, 2]
        rx, ry, rz = xipos[b, 0] - cx, xipos[b, 1] - cy, xipos[b, 2] - cz
        vx = cvel[b, 3] + wy * rz - wz * ry
        vy = cvel[b, 4] + wz * rx - wx * rz
        vz = cvel[b, 5] + wx * ry - wy * rx
        tx, ty, tz = xmat[b, 0], xmat[b, 3], xmat[b, 6]  # the link's axis in F_W
        s = vx * tx + vy * ty + vz * tz
        nx, ny, nz = vx - s * tx, vy - s * ty, vz - s * tz
        c = -k * math.sqrt(nx * nx + ny * ny + nz * nz)
        xfrc[b, 0], xfrc[b, 1], xfrc[b, 2] = c * nx, c * ny, c * nz


def line_drag_reference(bodies: np.ndarray, root: int, k: float, cvel: FloatArray,
                        xipos: FloatArray, xmat: FloatArray,
                        subtree_com: FloatArray) -> FloatArray:  # fmt: skip
    """The drag of :func:`line_drag_into` in numpy, one row per link (F_W) [N]."""
    w, v0 = cvel[bodies, 0:3], cvel[bodies, 3:6]
    v = v0 + np.cross(w, xipos[bodies] - subtree_com[root])
    t = xmat[bodies][:, [0, 3, 6]]
    vn = v - np.sum(v * t, axis=1, keepdims=True) * t
    return -k * np.linalg.norm(vn, axis=1, keepdims=True) * vn
