"""Named fields of a packed float array: the one layout a packer and both copies of a law read.

A compiled law takes its gains and model as one flat float array (``par``), its memory as
another (``state``) and writes its result into a third (``out``). Each module of
:mod:`tetherland.control.kernels` declares those layouts field by field with a
:class:`Fields`; the field names (module constants: an ``int`` for a scalar, a ``slice``
for a vector) are what the packer writes, and what the plain reference and the compiled
kernel read (numba takes them as compile-time constants). The fields tile
``[0, width)`` in the order they are declared, so no position is written by hand.

>>> f = Fields()
>>> MASS, J = f.scalar(), f.vector(3)
>>> MASS, J, f.width
(0, slice(1, 4, None), 4)
"""

from __future__ import annotations


class Fields:
    """Consecutive fields of a flat float array, laid out in the order they are declared.

    Parameters
    ----------
    start : int
        Position of the first field (e.g. after the mixer's result at the head of ``out``).
    """

    def __init__(self, start: int = 0) -> None:
        self.width = start
        """Positions used so far: the array's width once every field is declared."""

    def scalar(self) -> int:
        """The next position: a one-value field."""
        self.width += 1
        return self.width - 1

    def vector(self, n: int) -> slice:
        """The next ``n`` positions: an ``n``-value field."""
        if n < 1:
            raise ValueError(f"a field has at least one value (got {n})")
        self.width += n
        return slice(self.width - n, self.width)
