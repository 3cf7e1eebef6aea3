"""Rest-to-rest polynomial references (the planner-free alternative of section 6.5.1).

s(tau) = 126 tau^5 - 420 tau^6 + 540 tau^7 - 315 tau^8 + 70 tau^9 rises from 0 to 1 on
[0, 1] with zero 1st to 4th derivatives at both ends: the 9th-order polynomial of least
integrated squared 5th derivative between two rests (a "minimum-snap-like" profile).
y(t) = y_0 + (y_1 - y_0) s(t/T) then starts and ends at rest with zero velocity,
acceleration, jerk and snap, as the DFL controller needs (C^4).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from tetherland.geometry import FloatArray

# Coefficients of s(tau) by power 0..9.
_S = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 126.0, -420.0, 540.0, -315.0, 70.0])


_S_DERIVATIVES = [_S]
for _ in range(8):
    _S_DERIVATIVES.append(np.polynomial.polynomial.polyder(_S_DERIVATIVES[-1]))


_S_LISTS = [list(c[::-1]) for c in _S_DERIVATIVES]  # highest power first, for Horner


def smoothstep9_scalar(tau: float, order: int = 4) -> list[float]:
    """:func:`smoothstep9` for one scalar ``tau`` (plain floats, for the control loop).

    The first four are the closed forms of s = 126 u^5 - 420 u^6 + 540 u^7 - 315 u^8 +
    70 u^9 with v = 1 - u, w = 1 - 2u: ds = 630 u^4 v^4, d2s = 2520 u^3 v^3 w,
    d3s = 2520 u^2 v^2 (3 w^2 - 2 u v); higher derivatives by Horner's rule.
    """
    if tau <= 0.0 or tau >= 1.0:
        return [0.0 if tau <= 0.0 else 1.0] + [0.0] * order
    u = tau
    v = 1.0 - u
    w = 1.0 - 2.0 * u
    uv = u * v
    u2v2 = uv * uv
    s = u**5 * (126.0 + u * (-420.0 + u * (540.0 + u * (-315.0 + 70.0 * u))))
    out = [s, 630.0 * u2v2 * u2v2, 2520.0 * u2v2 * uv * w, 2520.0 * u2v2 * (3.0 * w * w - 2.0 * uv)]
    if order < 4:
        return out[: order + 1]
    for k in range(4, order + 1):
        acc = 0.0
        for c in _S_LISTS[k]:
            acc = acc * tau + c
        out.append(acc)
    return out


def smoothstep9(tau: ArrayLike, order: int = 4) -> FloatArray:
    """s(tau) and its derivatives d^k s/dtau^k for k = 0..order, shape (order+1, *tau.shape).

    ``tau`` is clipped to [0, 1] (s = 0 before, 1 after, derivatives zero outside).
    """
    tau = np.asarray(tau, dtype=float)
    inside = (tau >= 0.0) & (tau <= 1.0)
    tc = np.clip(tau, 0.0, 1.0)
    out = np.empty((order + 1, *tau.shape))
    for k in range(order + 1):
        out[k] = np.polynomial.polynomial.polyval(tc, _S_DERIVATIVES[k])
        if k > 0:
            out[k] = np.where(inside, out[k], 0.0)
    return out


def rest_to_rest(y0: float, y1: float, duration: float, t: ArrayLike, order: int = 4) -> FloatArray:
    """y(t) = y0 + (y1 - y0) s(t/T) and its time derivatives up to ``order``.

    Returns shape (order+1, *t.shape); held at y0 before 0 and y1 after T.
    """
    if not duration > 0:
        raise ValueError(f"duration must be > 0, got {duration}")
    ds = smoothstep9(np.asarray(t, dtype=float) / duration, order)
    scale = (y1 - y0) / duration ** np.arange(order + 1)
    out = ds * scale.reshape((-1,) + (1,) * (ds.ndim - 1))
    out[0] += y0
    return out
