"""One seeded random source per run, with named streams (docs/randomness.md).

Every random draw of a run comes from its seed through :class:`RandomSource`: each
consumer asks for its own stream by name, and the stream's generator is

    numpy.random.default_rng(numpy.random.SeedSequence(seed, spawn_key=(key,)))

with ``key`` the stream's fixed entry in :data:`STREAMS`. Streams are independent of
each other and of how many draws the others make, so e.g. more wind gusts leave the
model errors of a seed unchanged, and a new stream (a new name with a new key) moves no
other stream's draws. Keys are never reused or changed.

=============  ===  ===========================================================
stream         key  draws
=============  ===  ===========================================================
imu            0    IMU initial biases, white noise and bias walks
mocap          1    motion-capture noise and dropout times
perturbation   2    the belief's model and pose errors, the plant's noise scale
wind           3    wind gusts: start times, peak forces, headings
faults         4    the injected fault of a fault-campaign run (time, rotor, ...)
=============  ===  ===========================================================

Keys 0 and 1 are those that ``default_rng(seed).spawn(2)`` gave the IMU and motion
capture before the streams were named, so a seed's sensor noise is unchanged. A sensor
spawns child streams of its own from its stream (:mod:`tetherland.sim.sensors`).

A campaign derives each run's seed from its base seed with :func:`derive_seed` (the run
index, the sweep point, the fault kind); the run then draws everything from
``RandomSource(run_seed)``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

STREAMS: Mapping[str, int] = MappingProxyType({
    "imu": 0,
    "mocap": 1,
    "perturbation": 2,
    "wind": 3,
    "faults": 4,
})  # fmt: skip
"""Stream name -> its fixed spawn key (never reused or changed)."""


@dataclass(frozen=True)
class RandomSource:
    """The random source of one run: a seed and its named streams.

    Parameters
    ----------
    seed : int
        The run's seed, >= 0.
    """

    seed: int

    def __post_init__(self) -> None:
        if isinstance(self.seed, bool) or int(self.seed) != self.seed or self.seed < 0:
            raise ValueError(f"a seed must be an integer >= 0, got {self.seed!r}")
        object.__setattr__(self, "seed", int(self.seed))

    def seed_sequence(self, name: str) -> np.random.SeedSequence:
        """The seed sequence of stream ``name`` (one of :data:`STREAMS`)."""
        try:
            key = STREAMS[name]
        except KeyError:
            raise ValueError(
                f"unknown random stream '{name}' (streams: {', '.join(STREAMS)})"
            ) from None
        return np.random.SeedSequence(self.seed, spawn_key=(key,))

    def stream(self, name: str) -> np.random.Generator:
        """A fresh generator of stream ``name``: the same draws every time it is asked for."""
        return np.random.default_rng(self.seed_sequence(name))


def derive_seed(*words: int) -> int:
    """A 32-bit seed derived from integers (e.g. a campaign's base seed, a sweep point and
    a run index): ``SeedSequence(words).generate_state(1)[0]``."""
    return int(np.random.SeedSequence([int(w) for w in words]).generate_state(1)[0])
