"""Options and helpers shared by every command."""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console
from rich.progress import (
    BarColumn,
    Progress,
    SpinnerColumn,
    TaskID,
    TaskProgressColumn,
    TextColumn,
    TimeElapsedColumn,
)

from tetherland.cli import INTERRUPTED as INTERRUPTED  # the exit code after Ctrl-C, SIGTERM
from tetherland.config import Scenario, load_scenario
from tetherland.config.checks import check_name
from tetherland.errors import ConfigError
from tetherland.sim.video import DEFAULT_FPS, DEFAULT_SIZE, FrameProgress, VideoOptions

ScenarioArg = Annotated[
    str,
    typer.Argument(
        help="Built-in scenario name (see `tetherland scenarios`) or path to a TOML file."
    ),
]
SetOption = Annotated[
    list[str] | None,
    typer.Option(
        "--set",
        help="Override a scenario value, e.g. --set surface.slope_deg=70 (value parsed as TOML). "
        "Repeatable.",
        metavar="SECTION.KEY=VALUE",
    ),
]
JsonOption = Annotated[
    bool, typer.Option("--json", help="Print a JSON document on stdout instead of tables.")
]

OverwriteOption = Annotated[
    bool,
    typer.Option(
        "--overwrite",
        help="Replace the output directory as a whole if it holds an earlier output.",
    ),
]

VideoOption = Annotated[
    bool, typer.Option("--video", help="Also render mission.mp4 (offscreen).")
]
DEFAULT_VIDEO_SIZE = f"{DEFAULT_SIZE[0]}x{DEFAULT_SIZE[1]}"
VIDEO_FPS = DEFAULT_FPS
VideoFpsOption = Annotated[
    float, typer.Option("--video-fps", help="With --video: frames per second (1-60).")
]
VideoSizeOption = Annotated[
    str,
    typer.Option("--video-size", help="With --video: WIDTHxHEIGHT in pixels, even numbers.",
                 metavar="WxH"),
]  # fmt: skip
McapOption = Annotated[bool, typer.Option("--mcap", help="Also write run.mcap (Foxglove, Rerun).")]

OUTPUT_ROOT = Path("out")
"""Root of the default output directories, out/<scenario name>/<command>."""

console = Console()
err_console = Console(stderr=True)


def video_options(fps: float, size: str) -> VideoOptions:
    """The video options of ``--video-fps`` and ``--video-size``.

    Raises
    ------
    ConfigError
        One line naming the option and its allowed range.
    """
    try:
        width, height = VideoOptions.parse_size(size)
        return VideoOptions(fps=fps, width=width, height=height)
    except ValueError as err:
        option = "--video-fps" if "fps" in str(err) else "--video-size"
        raise ConfigError(f"{option}: {err}") from None


def run_progress(quiet: bool) -> Progress:
    """The transient progress display of a run: a line per task (the flight with the
    simulated time and phase, the video with a bar); nothing when ``quiet`` (--json)."""
    return Progress(
        SpinnerColumn(), TextColumn("{task.description}"), BarColumn(), TaskProgressColumn(),
        TimeElapsedColumn(), console=console, transient=True, disable=quiet,
    )  # fmt: skip


def frame_progress(progress: Progress) -> FrameProgress:
    """A video frame callback that shows a bar ``rendering video`` in ``progress``."""
    task: TaskID | None = None

    def on_frame(done: int, total: int) -> None:
        nonlocal task
        if task is None:
            task = progress.add_task("rendering video", total=total)
        progress.update(task, completed=done)

    return on_frame


def resolve_scenario(source: str, overrides: list[str] | None) -> Scenario:
    """Load the scenario named on the command line (raises ConfigError on bad input)."""
    return load_scenario(source, overrides or [])


def default_output(name: str, kind: str) -> Path:
    """``out/<name>/<kind>``, confined to :data:`OUTPUT_ROOT` (a name is a label, not a path).

    Raises
    ------
    ConfigError
        When ``name`` would lead outside the output root.
    """
    try:
        check_name(name)
    except ValueError as err:
        raise ConfigError(f"name: {err}") from None
    path = OUTPUT_ROOT / name / kind
    if Path(os.path.normpath(path)).parent.parent != OUTPUT_ROOT:  # what check_name ensures
        raise ConfigError(f"name {name!r} leads outside {OUTPUT_ROOT}/")
    return path


def deg(value: float | None, digits: int = 2) -> str:
    """Format radians as degrees, or '-' for None."""
    return "-" if value is None else f"{math.degrees(value):.{digits}f} deg"


def vec(v) -> str:
    """Format a 3-vector."""
    return "[" + ", ".join(f"{float(x):+.3f}" for x in v) + "]"


_COLOURS = {"success": "green", "safe stop": "yellow"}


def outcome_text(summary: dict) -> str:
    """The verdict's outcome as one coloured word: success, failure, safe stop, crash or
    not flown (:attr:`tetherland.verdict.Outcome.label`)."""
    from tetherland.verdict import Outcome  # the judge loads numba: not for `show`

    label = Outcome(summary["outcome"]).label
    return f"[{_COLOURS.get(label, 'red')}]{label}[/{_COLOURS.get(label, 'red')}]"


def conditions_text(landing: dict) -> str:
    """The landing conditions the method requires, ``1:ok 2:NO ...``; the others are named
    as not required (the contact-free method does not require (4))."""
    conditions = landing["conditions"]
    required = landing.get("required_conditions") or list(conditions)
    text = " ".join(f"{k}:{'ok' if conditions[k] else 'NO'}" for k in required)
    others = [k for k in conditions if k not in required]
    return text + (f" ({', '.join(others)} not required)" if others else "")


def perturbation_text(p: dict) -> str:
    """A drawn perturbation (``run.json`` provenance ``perturbation``) on one line."""
    e = (p["anchor_error_x_S"], p["anchor_error_y_S"], p["anchor_error_z_S"])
    return (
        f"perturbation of seed {p['seed']}: mass x{p['mass_factor']:.3f}, thrust coefficient "
        f"x{p['thrust_coefficient_factor']:.3f}, slope {p['slope_error_deg']:+.2f} deg, "
        f"azimuth {p['azimuth_error_deg']:+.2f} deg, anchor [{e[0]:+.3f}, {e[1]:+.3f}, "
        f"{e[2]:+.3f}] m, surface {p['surface_offset']:+.3f} m, noise x{p['noise_scale']:.2f}, "
        f"{p['gust_count']} gusts up to {p['gust_peak_N']:.2f} N"
    )
