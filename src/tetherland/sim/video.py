"""What a run's video is to be: frame rate, size and playback speed (no MuJoCo needed).

:mod:`tetherland.sim.render` draws the video; the command line checks these options
before a run flies.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

DEFAULT_FPS = 25
"""Video frames per second [1/s]."""
DEFAULT_SIZE = (640, 480)
"""Video width and height [px]."""
FPS_RANGE = (1.0, 60.0)
"""Allowed frame rates [1/s]."""
SIZE_RANGE = ((64, 1920), (48, 1080))
"""Allowed widths and heights [px]."""


@dataclass(frozen=True)
class VideoOptions:
    """How to render a run's video.

    Attributes
    ----------
    fps : float [1/s]
        Video frames per second, in :data:`FPS_RANGE`.
    width, height : int [px]
        Image size, in :data:`SIZE_RANGE`; even (the H.264 encoder needs it).
    speed : float
        Playback speed factor (> 0): 2 shows 2 s of flight per second of video.

    Raises
    ------
    ValueError
        One line naming the field and its allowed range.
    """

    fps: float = DEFAULT_FPS
    width: int = DEFAULT_SIZE[0]
    height: int = DEFAULT_SIZE[1]
    speed: float = 1.0

    def __post_init__(self) -> None:
        lo, hi = FPS_RANGE
        if not lo <= self.fps <= hi:
            raise ValueError(f"video fps must be in [{lo:g}, {hi:g}] (got {self.fps:g})")
        for name, value, (a, b) in zip(("width", "height"), self.size, SIZE_RANGE, strict=True):
            if not (a <= value <= b and value % 2 == 0):
                raise ValueError(f"video {name} must be even, in [{a}, {b}] px (got {value})")
        if not (self.speed > 0 and math.isfinite(self.speed)):
            raise ValueError(f"video speed must be > 0 (got {self.speed:g})")

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) [px]."""
        return (self.width, self.height)

    @classmethod
    def parse_size(cls, text: str) -> tuple[int, int]:
        """``"640x480"`` -> (640, 480).

        Raises
        ------
        ValueError
            When ``text`` is not WIDTHxHEIGHT.
        """
        parts = text.lower().split("x")
        if len(parts) != 2 or not all(p.strip().isdigit() for p in parts):
            raise ValueError(f"video size must be WIDTHxHEIGHT in pixels, e.g. 640x480 "
                             f"(got {text!r})")  # fmt: skip
        return int(parts[0]), int(parts[1])


FrameProgress = Callable[[int, int], None]
"""Called as ``progress(frames_done, frames_total)`` after each video frame."""


__all__ = ["DEFAULT_FPS", "DEFAULT_SIZE", "FPS_RANGE", "SIZE_RANGE", "FrameProgress",
           "VideoOptions"]  # fmt: skip
