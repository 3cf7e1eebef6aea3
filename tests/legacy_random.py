"""The random draws of campaign runs from before the streams were named, for replays.

Earlier versions drew a campaign run's wind gusts and then its model and pose errors from
one generator, ``default_rng(seed)``, and its fault from ``default_rng([seed, 15])``; the
sensor noise came from ``default_rng(seed).spawn(2)``, which the named ``imu`` and
``mocap`` streams still give. :class:`LegacySource` hands out those generators under the
stream names, so that a regression test flies a campaign run recorded then exactly as it
flew.
"""

from __future__ import annotations

import numpy as np

from tetherland.campaign.perturb import sample_gusts
from tetherland.config.perturbation import PerturbationConfig
from tetherland.randomness import RandomSource

LEGACY_GUST_HORIZON = 120.0
"""The span [s] over which those campaigns drew a run's gusts (now the run's time limit)."""


class LegacySource(RandomSource):
    """A run's random source as campaigns drew it before the named streams.

    The gusts and then the errors came from one generator, the gusts over
    :data:`LEGACY_GUST_HORIZON` with the default ``[perturbation]`` wind settings. The
    ``wind`` stream is that generator (its first 120 s of gusts are those; today's longer
    horizon draws later ones from where it goes on), and the ``perturbation`` stream the
    same generator advanced past those 120 s of gusts, so that the errors are those drawn
    then."""

    def stream(self, name: str) -> np.random.Generator:
        if name == "wind":
            return np.random.default_rng(self.seed)
        if name == "perturbation":
            rng = np.random.default_rng(self.seed)
            sample_gusts(PerturbationConfig(), rng, LEGACY_GUST_HORIZON)
            return rng
        if name == "faults":
            return np.random.default_rng([self.seed, 15])
        return super().stream(name)
