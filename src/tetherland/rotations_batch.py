"""Vectorised rotation helpers over stacks of quaternions / rotation vectors.

Used by the UKF to move all sigma points at once, written to minimise the number of
numpy calls (the arrays are small, so call overhead dominates). Shapes: quaternions
(N, 4) scalar-first, rotation vectors and 3-vectors (N, 3).
"""

from __future__ import annotations

import numpy as np

from tetherland.geometry import FloatArray

# L(p) with p * q = L(p) q:  [[w,-x,-y,-z],[x,w,-z,y],[y,z,w,-x],[z,-y,x,w]]
_L_IDX = np.array([[0, 1, 2, 3], [1, 0, 3, 2], [2, 3, 0, 1], [3, 2, 1, 0]])
_L_SGN = np.array([[1, -1, -1, -1], [1, 1, -1, 1], [1, 1, 1, -1], [1, -1, 1, 1]], dtype=float)
# R(q) as a quadratic form: vec(R) = M @ vec(q q^T), row-major 3x3 from the 4x4 outer product
_R_QUAD = np.zeros((9, 16))
for _r, _terms in enumerate(
    [
        [(0, 0, 1), (1, 1, 1), (2, 2, -1), (3, 3, -1)],
        [(1, 2, 2), (0, 3, -2)],
        [(1, 3, 2), (0, 2, 2)],
        [(1, 2, 2), (0, 3, 2)],
        [(0, 0, 1), (1, 1, -1), (2, 2, 1), (3, 3, -1)],
        [(2, 3, 2), (0, 1, -2)],
        [(1, 3, 2), (0, 2, -2)],
        [(2, 3, 2), (0, 1, 2)],
        [(0, 0, 1), (1, 1, -1), (2, 2, -1), (3, 3, 1)],
    ]
):
    for _i, _j, _c in _terms:
        _R_QUAD[_r, 4 * _i + _j] += _c
_CONJ = np.array([1.0, -1.0, -1.0, -1.0])


def left_matrix_batch(p: FloatArray) -> FloatArray:
    """Stack of 4x4 matrices L(p_i) with p_i * q = L(p_i) q."""
    return p[:, _L_IDX] * _L_SGN


def quat_multiply_batch(p: FloatArray, q: FloatArray) -> FloatArray:
    """Row-wise Hamilton products p_i * q_i; either argument may be a single (4,) quaternion."""
    if p.ndim == 1:
        return q @ (p[_L_IDX] * _L_SGN).T
    if q.ndim == 1:
        q = np.broadcast_to(q, p.shape)
    return np.einsum("nij,nj->ni", p[:, _L_IDX] * _L_SGN, q)


def rotvec_to_quat_batch(phi: FloatArray) -> FloatArray:
    """Quaternions of rotation vectors, row-wise (exact, smooth through zero).

    sin(a/2)/a is evaluated as sin(a/2)/(a + 1e-300): exact for every a > 1e-284, and for
    a = 0 the vector part phi * 0 is 0 anyway.
    """
    angle = np.sqrt(np.einsum("ij,ij->i", phi, phi))
    half = 0.5 * angle
    out = np.empty((phi.shape[0], 4))
    out[:, 0] = np.cos(half)
    out[:, 1:] = phi * (np.sin(half) / (angle + 1e-300))[:, None]
    return out


def quat_to_rotvec_batch(q: FloatArray) -> FloatArray:
    """Rotation vectors (shortest rotation) of unit quaternions, row-wise."""
    sign = np.copysign(1.0, q[:, 0])
    s = np.sqrt(np.einsum("ij,ij->i", q[:, 1:], q[:, 1:]))
    # angle / s with angle = 2 atan2(s, |w|); -> 2/|w| as s -> 0, and 0 * finite at s = 0
    scale = sign * 2.0 * np.arctan2(s, np.abs(q[:, 0])) / (s + 1e-300)
    return q[:, 1:] * scale[:, None]


def rotation_matrices_batch(q: FloatArray) -> FloatArray:
    """Stack of rotation matrices (N, 3, 3) of unit quaternions."""
    outer = np.einsum("ni,nj->nij", q, q).reshape(-1, 16)
    return (outer @ _R_QUAD.T).reshape(-1, 3, 3)


def rotate_batch(q: FloatArray, v: FloatArray) -> FloatArray:
    """R(q_i) v_i row-wise."""
    return np.einsum("nij,nj->ni", rotation_matrices_batch(q), v)


def quat_conjugate_batch(q: FloatArray) -> FloatArray:
    """Row-wise conjugates (inverses of unit quaternions)."""
    return q * _CONJ
