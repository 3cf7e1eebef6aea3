"""Small, allocation-light rotation utilities for the 500 Hz / 1 kHz loops.

Quaternions are scalar-first ``q = (w, x, y, z)`` (MuJoCo's order) and unit-norm;
``quat_to_rotmat(q_WB)`` returns ``R_WB`` (maps F_B coordinates to F_W). scipy's
``Rotation`` is scalar-last; convert with :func:`to_scipy_quat` only at boundaries.

The small helpers convert their inputs to Python floats first (``tolist``): scalar
arithmetic on floats is several times cheaper than on numpy scalars, and the results are
the same IEEE doubles. The compiled control and estimation loops use their own inlined
versions (:mod:`tetherland.control.kernels.so3`, :mod:`tetherland.estimation.ukf_kernels`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import ArrayLike

from tetherland.geometry import FloatArray

SMALL_ANGLE = 1e-8
"""Below this rotation angle [rad] the rotation helpers use their small-angle forms."""
_SMALL = SMALL_ANGLE


def _floats(v: ArrayLike) -> list[float]:
    """The entries of a small vector as Python floats."""
    return np.asarray(v, dtype=float).tolist()


def cross3(a: FloatArray, b: FloatArray) -> FloatArray:
    """a x b for two 3-vectors (several times faster than ``np.cross`` on small arrays)."""
    a0, a1, a2 = _floats(a)
    b0, b1, b2 = _floats(b)
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def hat(v: ArrayLike) -> FloatArray:
    """Skew-symmetric matrix with ``hat(a) @ b == cross(a, b)``."""
    x, y, z = _floats(v)
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def vee(S: ArrayLike) -> FloatArray:
    """Inverse of :func:`hat` (uses the antisymmetric part of ``S``)."""
    S = np.asarray(S, dtype=float)
    return 0.5 * np.array([S[2, 1] - S[1, 2], S[0, 2] - S[2, 0], S[1, 0] - S[0, 1]])


def quat_to_rotmat_reference(q: ArrayLike) -> FloatArray:
    """Rotation matrix of a unit quaternion (w, x, y, z): the plain form of
    :func:`quat_to_rotmat` (any array-like; a test checks both give the same bits)."""
    w, x, y, z = _floats(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


@njit("void(float64[:], float64[:, ::1])", cache=True)
def _quat_to_rotmat_into(q: FloatArray, R: FloatArray) -> None:  # pragma: no cover (compiled)
    """Compiled :func:`quat_to_rotmat_reference` of a float64 vector, written into ``R``
    (3, 3) (the same operations in the same order, no fast-math: the same bits)."""
    if q.shape[0] != 4 or R.shape[0] != 3 or R.shape[1] != 3:
        raise ValueError("a quaternion has 4 entries (w, x, y, z), its matrix 3 x 3")
    w, x, y, z = q[0], q[1], q[2], q[3]
    R[0, 0] = 1 - 2 * (y * y + z * z)
    R[0, 1] = 2 * (x * y - w * z)
    R[0, 2] = 2 * (x * z + w * y)
    R[1, 0] = 2 * (x * y + w * z)
    R[1, 1] = 1 - 2 * (x * x + z * z)
    R[1, 2] = 2 * (y * z - w * x)
    R[2, 0] = 2 * (x * z - w * y)
    R[2, 1] = 2 * (y * z + w * x)
    R[2, 2] = 1 - 2 * (x * x + y * y)


_empty = np.empty


def quat_to_rotmat(q: ArrayLike) -> FloatArray:
    """Rotation matrix of a unit quaternion (w, x, y, z).

    A writable float64 vector (every estimate's and the plant's) goes through one compiled
    call (it runs about 45 000 times in an 80 s mission; the matrix is allocated here: a
    compiled function returning an array pays more to box it); anything else through
    :func:`quat_to_rotmat_reference`. Both give the same bits.
    """
    R = _empty((3, 3))
    try:
        _quat_to_rotmat_into(q, R)
    except TypeError:  # not a writable float64 vector: a list, ints, float32, read-only
        return quat_to_rotmat_reference(q)
    return R


def quat_to_rotmat_stack(q: ArrayLike) -> FloatArray:
    """Rotation matrices (n, 3, 3) of n unit quaternions (w, x, y, z) (n, 4): the operations
    of :func:`quat_to_rotmat_reference` on columns (the same bits; a test checks it)."""
    w, x, y, z = np.asarray(q, dtype=float).reshape(-1, 4).T
    R = np.empty((len(w), 3, 3))
    R[:, 0, 0] = 1 - 2 * (y * y + z * z)
    R[:, 0, 1] = 2 * (x * y - w * z)
    R[:, 0, 2] = 2 * (x * z + w * y)
    R[:, 1, 0] = 2 * (x * y + w * z)
    R[:, 1, 1] = 1 - 2 * (x * x + z * z)
    R[:, 1, 2] = 2 * (y * z - w * x)
    R[:, 2, 0] = 2 * (x * z - w * y)
    R[:, 2, 1] = 2 * (y * z + w * x)
    R[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return R


def quat_to_rotmat_many(q: ArrayLike) -> FloatArray:
    """Rotation matrices (n, 3, 3) of n unit quaternions (w, x, y, z) (vectorised, scipy)."""
    from scipy.spatial.transform import Rotation

    q = np.asarray(q, dtype=float).reshape(-1, 4)
    return Rotation.from_quat(q[:, [1, 2, 3, 0]]).as_matrix()


def rotmat_to_quat(R: ArrayLike) -> FloatArray:
    """Unit quaternion (w, x, y, z) with w >= 0 of a rotation matrix (Shepperd's method)."""
    R = np.asarray(R, dtype=float)
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if tr > 0.0:
        s = 2.0 * math.sqrt(tr + 1.0)
        q = np.array(
            [0.25 * s, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s]
        )
    elif R[0, 0] > R[1, 1] and R[0, 0] > R[2, 2]:
        s = 2.0 * math.sqrt(1.0 + R[0, 0] - R[1, 1] - R[2, 2])
        q = np.array(
            [(R[2, 1] - R[1, 2]) / s, 0.25 * s, (R[0, 1] + R[1, 0]) / s, (R[0, 2] + R[2, 0]) / s]
        )
    elif R[1, 1] > R[2, 2]:
        s = 2.0 * math.sqrt(1.0 + R[1, 1] - R[0, 0] - R[2, 2])
        q = np.array(
            [(R[0, 2] - R[2, 0]) / s, (R[0, 1] + R[1, 0]) / s, 0.25 * s, (R[1, 2] + R[2, 1]) / s]
        )
    else:
        s = 2.0 * math.sqrt(1.0 + R[2, 2] - R[0, 0] - R[1, 1])
        q = np.array(
            [(R[1, 0] - R[0, 1]) / s, (R[0, 2] + R[2, 0]) / s, (R[1, 2] + R[2, 1]) / s, 0.25 * s]
        )
    q /= np.linalg.norm(q)
    return -q if q[0] < 0 else q


def quat_multiply(p: ArrayLike, q: ArrayLike) -> FloatArray:
    """Hamilton product p * q (both scalar-first); R(p*q) = R(p) R(q)."""
    pw, px, py, pz = _floats(p)
    qw, qx, qy, qz = _floats(q)
    return np.array(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ]
    )


def quat_conjugate(q: ArrayLike) -> FloatArray:
    """Inverse of a unit quaternion."""
    w, x, y, z = _floats(q)
    return np.array([w, -x, -y, -z])


def exp_so3(phi: ArrayLike) -> FloatArray:
    """Rotation matrix exp(hat(phi)) of a rotation vector (Rodrigues)."""
    phi = np.asarray(phi, dtype=float)
    angle = float(np.linalg.norm(phi))
    K = hat(phi)
    if angle < _SMALL:
        return np.eye(3) + K + 0.5 * K @ K
    return np.eye(3) + (math.sin(angle) / angle) * K + ((1.0 - math.cos(angle)) / angle**2) * K @ K


def log_so3(R: ArrayLike) -> FloatArray:
    """Rotation vector phi with exp_so3(phi) = R, |phi| <= pi."""
    q = rotmat_to_quat(R)
    return quat_to_rotvec(q)


def quat_to_rotvec(q: ArrayLike) -> FloatArray:
    """Rotation vector of a unit quaternion (shortest rotation)."""
    q = np.asarray(q, dtype=float)
    if q[0] < 0:
        q = -q
    s = float(np.linalg.norm(q[1:]))
    if s < _SMALL:
        return 2.0 * q[1:]
    angle = 2.0 * math.atan2(s, q[0])
    return q[1:] * (angle / s)


def rotvec_to_quat(phi: ArrayLike) -> FloatArray:
    """Unit quaternion (w, x, y, z) of a rotation vector."""
    phi = np.asarray(phi, dtype=float)
    angle = float(np.linalg.norm(phi))
    if angle < _SMALL:
        q = np.array([1.0, 0.5 * phi[0], 0.5 * phi[1], 0.5 * phi[2]])
        return q / np.linalg.norm(q)
    axis = phi / angle
    return np.concatenate(([math.cos(0.5 * angle)], math.sin(0.5 * angle) * axis))


def rotation_from_z_and_yaw(z_B: ArrayLike, psi: float) -> FloatArray:
    """R_WB with third column ``z_B`` whose x_B projects on the heading ``psi``.

    x_C = [cos psi, sin psi, 0]; y_B = z_B x x_C / ||.||; x_B = y_B x z_B (Lee et al. 2010).
    Singular when z_B is horizontal along x_C; raises :class:`SingularityError` there.
    """
    from tetherland.errors import SingularityError

    zx, zy, zz = _floats(z_B)
    n = math.sqrt(zx * zx + zy * zy + zz * zz)
    zx, zy, zz = zx / n, zy / n, zz / n
    cx, cy = math.cos(psi), math.sin(psi)  # x_C = [cx, cy, 0]
    yx, yy, yz = -zz * cy, zz * cx, zx * cy - zy * cx  # z x x_C
    n = math.sqrt(yx * yx + yy * yy + yz * yz)
    if n < 1e-9:
        raise SingularityError("thrust axis is aligned with the desired heading: yaw undefined")
    yx, yy, yz = yx / n, yy / n, yz / n
    xx, xy, xz = yy * zz - yz * zy, yz * zx - yx * zz, yx * zy - yy * zx  # y x z
    return np.array([[xx, yx, zx], [xy, yy, zy], [xz, yz, zz]])


def to_scipy_quat(q: ArrayLike) -> FloatArray:
    """(w, x, y, z) -> (x, y, z, w) for ``scipy.spatial.transform.Rotation``."""
    q = np.asarray(q, dtype=float)
    return np.array([q[1], q[2], q[3], q[0]])


def from_scipy_quat(q: ArrayLike) -> FloatArray:
    """(x, y, z, w) -> (w, x, y, z)."""
    q = np.asarray(q, dtype=float)
    return np.array([q[3], q[0], q[1], q[2]])


def angle_between(a: ArrayLike, b: ArrayLike) -> float:
    """Angle between two vectors [rad], robust near 0 and pi."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return math.atan2(float(np.linalg.norm(np.cross(a, b))), float(a @ b))
