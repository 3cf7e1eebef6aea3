"""The random draws of campaign runs from before the streams were named, for replays.

Earlier versions drew a campaign run's wind gusts and then its model and pose errors from
one generator, ``default_rng(seed)``, and its fault from ``default_rng([seed, 15])``; the
sensor noise came from ``default_rng(seed).spawn(2)``, which the named ``imu`` and
``mocap`` streams still give. :class:`LegacySource` hands out those generators under the
stream names, so that a regression test flies a campaign run recorded then exactly as it
flew.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from tetherland.randomness import RandomSource


class LegacySource(RandomSource):
    """A run's random source as campaigns drew it before the named streams."""

    @cached_property
    def _shared(self) -> np.random.Generator:
        return np.random.default_rng(self.seed)

    def stream(self, name: str) -> np.random.Generator:
        if name in ("wind", "perturbation"):  # one generator, the gusts drawn first
            return self._shared
        if name == "faults":
            return np.random.default_rng([self.seed, 15])
        return super().stream(name)
