"""How this machine's numpy rounds, for the tests that compare two forms of a computation.

The scalar and compiled forms of the control-rate paths (issue 25) were written to give
the bits of the numpy expressions they replace, so that the default missions' logs did not
change by a bit. Those bits are numpy's on machines whose OpenBLAS runs its AVX2 (Haswell)
kernels: a dot product of 3 or 4 floats summed left to right, ``R @ v`` of a C-ordered
3x3 rounded as ``fma(R_i2, v_2, fma(R_i0, v_0, R_i1 v_1))``. OpenBLAS picks its kernels by
CPU: with AVX-512 (e.g. AMD Zen 4, Intel Skylake-X) its dot products sum in another order,
and ``np.linalg.norm(v)``, ``R @ v`` and what is built on them differ from those sums in
the last bits. (``OPENBLAS_CORETYPE=Haswell`` gives such a machine the AVX2 kernels back.)

The tests compare bit for bit where :data:`BLAS_AS_KERNELS` holds, and otherwise to the
rounding of the operations involved: :func:`assert_same` with a bound in units of the
machine epsilon, derived at each call from the number of rounded operations.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
from numpy.typing import ArrayLike

EPS = float(np.finfo(float).eps)
"""Machine epsilon of float64, 2^-52 (twice the unit roundoff)."""


def _fma(a: float, b: float, c: float) -> float:
    """a b + c rounded once (exact arithmetic, then one rounding to float)."""
    return float(Fraction(a) * Fraction(b) + Fraction(c))


def blas_rounds_as_the_kernels() -> bool:
    """True when numpy's ``R @ v`` (C-ordered 3x3 R) rounds each row as
    fma(R_i2, v_2, fma(R_i0, v_0, R_i1 v_1)), ``R.T @ v`` and ``np.linalg.norm`` of 3 and 4
    floats as the plain sums left to right (checked in exact arithmetic)."""
    rng = np.random.default_rng(0)
    for _ in range(300):
        R, v = rng.normal(size=(3, 3)), rng.normal(size=4)
        x, y, z, w = v.tolist()
        rows = [_fma(r[2], z, _fma(r[0], x, r[1] * y)) for r in R.tolist()]
        cols = [c[0] * x + c[1] * y + c[2] * z for c in R.T.tolist()]
        if not (np.array_equal(R @ v[:3], rows) and np.array_equal(R.T @ v[:3], cols)):
            return False
        if float(np.linalg.norm(v[:3])) != (x * x + y * y + z * z) ** 0.5:
            return False
        if float(np.linalg.norm(v)) != (x * x + y * y + z * z + w * w) ** 0.5:
            return False
    return True


BLAS_AS_KERNELS = blas_rounds_as_the_kernels()
"""Whether this machine's numpy rounds as the scalar and compiled forms assume."""


def assert_same(got: ArrayLike, want: ArrayLike, *, ulps: float, scale: float = 1.0,
                equal_nan: bool = False) -> None:  # fmt: skip
    """``got`` equals ``want`` bit for bit where :data:`BLAS_AS_KERNELS`, else within
    ``ulps * EPS * max(scale, |want|)`` elementwise (NaN where ``want`` is NaN when
    ``equal_nan``).

    ``ulps`` is the caller's bound on the rounding of the two forms (the number of rounded
    operations between the inputs and the result, each at most half an epsilon relative,
    for both forms); ``scale`` the magnitude the errors are relative to (e.g. 1 for the
    entries of a rotation matrix, whose rounding errors do not shrink with the entry).
    """
    got_a, want_a = np.asarray(got, dtype=float), np.asarray(want, dtype=float)
    if BLAS_AS_KERNELS:
        assert np.array_equal(got_a, want_a, equal_nan=equal_nan), (got_a, want_a)
        return
    assert got_a.shape == want_a.shape
    if equal_nan:
        assert np.array_equal(np.isnan(got_a), np.isnan(want_a))
        got_a, want_a = got_a[~np.isnan(want_a)], want_a[~np.isnan(want_a)]
    bound = ulps * EPS * np.maximum(scale, np.abs(want_a))
    assert np.all(np.abs(got_a - want_a) <= bound), float(np.max(np.abs(got_a - want_a) / bound))
