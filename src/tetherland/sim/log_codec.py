"""How a log column is stored on disk: its precision, and the lossless codec of its values.

Each column of a run log has a :class:`Precision`. The values are first rounded to that
precision (:func:`to_storage`: float64 kept, float32, float32 rounded to 16 significant
bits, or the smallest integer type that holds an integer column), then encoded without
further loss (:func:`encode`): each component's bit patterns are XORed with the previous
tick's (a smooth signal leaves the high bytes zero), the bytes are shuffled so that equal
byte positions lie together, and the stream is compressed with Zstandard. :func:`decode`
inverts the codec exactly, so a log read back equals the log rounded to its precisions
(:func:`to_storage` then float64) bit for bit.

The rounding to 16 significant bits is IEEE round-to-nearest-even on the float32 mantissa
("bit rounding"): the value stays a float32, its relative error is at most 2^-16
(1.5e-5), and the zeroed low mantissa bits cost nothing once compressed.
"""

from __future__ import annotations

from enum import StrEnum

import numpy as np

from tetherland.geometry import FloatArray

ZSTD_LEVEL = 3
"""Zstandard level: 1-3 compress a 80 s log in about 0.1 s; higher levels gain little."""
_ROUNDED_BITS = 16
"""Significant bits (the implicit leading one included) of :attr:`Precision.ROUNDED16`."""


class Precision(StrEnum):
    """Storage precision of a log column."""

    FLOAT64 = "float64"
    """Exact (IEEE double)."""
    FLOAT32 = "float32"
    """IEEE single: relative error at most 2^-24 (6.0e-8)."""
    ROUNDED16 = "float32/16"
    """IEEE single rounded to 16 significant bits: relative error at most 2^-16 (1.5e-5)."""
    INTEGER = "integer"
    """Exact: the smallest of int8/16/32/64 that holds the column, float32 if it holds NaN
    (exact for the small codes a log stores)."""

    @property
    def relative_error(self) -> float:
        """Largest relative rounding error of a stored value (0 for an exact one)."""
        # rounding to 16 bits follows the rounding to float32: the two errors add
        return {"float32": 2.0**-24, "float32/16": 2.0**-_ROUNDED_BITS + 2.0**-24}.get(
            self.value, 0.0
        )

    @property
    def description(self) -> str:
        """One phrase for the reference page, e.g. ``float32 (rel. 6.0e-08)``."""
        if self is Precision.FLOAT64:
            return "float64 (exact)"
        if self is Precision.INTEGER:
            return "integer (exact)"
        bits = 24 if self is Precision.FLOAT32 else _ROUNDED_BITS
        return f"float32, {bits} bits (rel. {self.relative_error:.1e})"


def _round_mantissa(x: np.ndarray, bits: int) -> np.ndarray:
    """float32 ``x`` rounded to ``bits`` significant bits, to nearest even (finite values;
    NaN and infinities unchanged)."""
    drop = 24 - bits
    u = x.view(np.uint32)
    half = np.uint32((1 << (drop - 1)) - 1)
    mask = np.uint32((0xFFFFFFFF << drop) & 0xFFFFFFFF)
    rounded = (u + half + ((u >> np.uint32(drop)) & np.uint32(1))) & mask
    return np.where(np.isfinite(x), rounded, u).view(np.float32)


def _integer_dtype(values: FloatArray) -> np.dtype:
    if values.size == 0:
        return np.dtype(np.int8)
    lo, hi = float(values.min()), float(values.max())
    for dtype in (np.int8, np.int16, np.int32):
        info = np.iinfo(dtype)
        if info.min <= lo and hi <= info.max:
            return np.dtype(dtype)
    return np.dtype(np.int64)


def to_storage(values: FloatArray, precision: Precision) -> np.ndarray:
    """``values`` (float64, any shape) rounded to ``precision``, in the dtype they are
    stored in."""
    values = np.asarray(values, dtype=float)
    if precision is Precision.FLOAT64:
        return values
    if precision is Precision.INTEGER:
        if np.all(np.isfinite(values)):
            return values.astype(_integer_dtype(values))
        return values.astype(np.float32)
    single = values.astype(np.float32)
    return _round_mantissa(single, _ROUNDED_BITS) if precision is Precision.ROUNDED16 else single


def rounded(values: FloatArray, precision: Precision) -> FloatArray:
    """``values`` as a log read back from disk holds them (float64)."""
    return to_storage(values, precision).astype(float)


def encode(stored: np.ndarray, level: int = ZSTD_LEVEL) -> np.ndarray:
    """Lossless bytes (uint8 array) of a stored column given component-major, shape
    (width, n) (one row per component, each a time series)."""
    import zstandard

    comp = np.ascontiguousarray(stored)
    width, n = comp.shape
    u = comp.view(f"u{comp.dtype.itemsize}")
    delta = u.copy()
    delta[:, 1:] ^= u[:, :-1]
    shuffled = delta.view(np.uint8).reshape(width, n, -1).transpose(0, 2, 1)
    data = zstandard.ZstdCompressor(level=level).compress(np.ascontiguousarray(shuffled))
    return np.frombuffer(data, dtype=np.uint8)


def decode(data: np.ndarray, dtype: str, n: int, width: int) -> FloatArray:
    """The (n, width) float64 values of a column written by :func:`encode`.

    Raises
    ------
    ValueError
        If ``data`` is damaged or does not hold ``n * width`` values of ``dtype``.
    """
    import zstandard

    kind = np.dtype(dtype)
    size = kind.itemsize
    try:
        raw = zstandard.ZstdDecompressor().decompress(
            np.ascontiguousarray(data).tobytes(), max_output_size=n * width * size
        )
    except zstandard.ZstdError as err:
        raise ValueError(f"damaged column data ({err})") from None
    if len(raw) != n * width * size:
        raise ValueError(f"column holds {len(raw)} bytes, expected {n * width * size}")
    shuffled = np.frombuffer(raw, dtype=np.uint8).reshape(width, size, n)
    delta = np.ascontiguousarray(shuffled.transpose(0, 2, 1)).view(f"u{size}").reshape(width, n)
    bits = np.bitwise_xor.accumulate(delta, axis=1)
    return bits.view(kind).T.astype(float)


__all__ = ["Precision", "decode", "encode", "rounded", "to_storage"]
