"""Compiled MuJoCo models kept per process, one per distinct MJCF text.

A campaign worker flies many runs of the same scene: the perturbations change what the
robot *believes* (mass, inertia, surface, anchor) and the plant's sensor noise, not the
plant's MJCF, so every run of a scenario compiles the same text. :func:`compiled_model`
compiles each distinct text once per process and hands every caller its own copy
(``mj_copyModel``: every array copied), which the caller may change (the plant widens the
rotors' control range for the ground effect and engages and releases the cable in it).

Why the copy is the model a fresh compile would give: the key is the MJCF text itself
(compared in full, not a digest of it), and the compiler reads nothing but that text (the
scene has no asset files and no plugins); the cached model is never handed out, only
copied, so no run's changes reach it. ``tests/test_model_cache.py`` checks both: every
array of a copy equals that of a fresh compile, also after a run changed its own copy,
and a campaign flown with the cache gives the same records and logs as one without.
"""

from __future__ import annotations

import copy
import threading
from collections import OrderedDict
from dataclasses import dataclass

import mujoco


@dataclass
class ModelCacheStats:
    """What :func:`compiled_model` did in this process.

    Attributes
    ----------
    compiled : int
        Models compiled from MJCF (cache misses) [-].
    reused : int
        Models copied from the cache (hits) [-].
    """

    compiled: int = 0
    reused: int = 0


class ModelCache:
    """Least-recently-used compiled models by MJCF text.

    Parameters
    ----------
    max_entries : int
        Most models kept, in [0, 1000] (0: compile every time) [-]. A sweep over a
        plant parameter (slope, cable length) has one model per value; a model takes a
        few hundred kB.
    """

    def __init__(self, max_entries: int = 16) -> None:
        if not 0 <= max_entries <= 1000:
            raise ValueError(f"max_entries must be in [0, 1000] (got {max_entries})")
        self.max_entries = max_entries
        self.stats = ModelCacheStats()
        self._models: OrderedDict[str, mujoco.MjModel] = OrderedDict()
        self._lock = threading.Lock()

    def __len__(self) -> int:
        return len(self._models)

    def clear(self) -> None:
        """Forget every model and the counts."""
        with self._lock:
            self._models.clear()
            self.stats = ModelCacheStats()

    def model(self, xml: str) -> mujoco.MjModel:
        """A model of the MJCF text ``xml`` that the caller owns (a copy of the cached one,
        or a fresh compile when caching is off)."""
        with self._lock:
            cached = self._models.get(xml) if self.max_entries > 0 else None
            if cached is not None:
                self._models.move_to_end(xml)
                self.stats.reused += 1
                return copy.copy(cached)  # MjModel.__copy__: mj_copyModel, every array
        model = mujoco.MjModel.from_xml_string(xml)
        with self._lock:
            self.stats.compiled += 1
            if self.max_entries == 0:
                return model
            self._models[xml] = copy.copy(model)  # kept apart from the caller's model
            while len(self._models) > self.max_entries:
                self._models.popitem(last=False)
        return model


MODEL_CACHE = ModelCache()
"""This process's cache (campaign workers, ``check_verdicts``, notebooks)."""


def compiled_model(xml: str) -> mujoco.MjModel:
    """The compiled model of the MJCF text ``xml``, the caller's own copy
    (:data:`MODEL_CACHE`)."""
    return MODEL_CACHE.model(xml)
