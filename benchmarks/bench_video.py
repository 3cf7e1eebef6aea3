"""Time to render a mission's video (issue 25, item 4).

Target: ``mission wall90 --video`` renders the video of the flight in at most its flight
time on this 2-core machine (at most 1 s of wall time per second of flight), with the
default frame rate and size. Flies wall90 once (seed 0, not timed), renders its log with
the defaults, then the first seconds of it with the settings before issue 25 (shadows,
reflections, skybox, 4x multisampling, 30 fps: 293 s for the whole flight), back to back.
Prints wall and CPU time (this process with the renderer's threads, and ffmpeg): nothing
waits but for the CPU, so on an idle machine the wall time is at most the CPU time.

Run: MUJOCO_GL=egl .venv/bin/python benchmarks/bench_video.py [scenario] [seconds of the
     before-sample]
"""

from __future__ import annotations

import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from tetherland.config import load_scenario
from tetherland.runs import run_mission
from tetherland.sim import SimLog
from tetherland.sim.render import VideoOptions, render_log

TARGET_S_PER_FLIGHT_S = 1.0


def _cpu() -> float:
    """CPU time of this process (the renderer's threads included) and of its finished
    children (ffmpeg) [s]."""
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def _timed(log: SimLog, path: Path, scenario, options: VideoOptions,
           detail: bool) -> tuple[float, float]:  # fmt: skip
    """Wall and CPU time of rendering ``log`` [s]."""
    t0, c0 = time.perf_counter(), _cpu()
    render_log(log, path, scenario=scenario, options=options, detail=detail)
    return time.perf_counter() - t0, _cpu() - c0


def main() -> None:
    name = sys.argv[1] if len(sys.argv) > 1 else "wall90"
    sample = float(sys.argv[2]) if len(sys.argv) > 2 else 8.0
    scenario = load_scenario(name)
    result = run_mission(scenario, seed=0)
    log = result.log
    assert log is not None, result.summary["reason"]
    flight = float(log.t[-1] - log.t[0])
    options = VideoOptions()
    with tempfile.TemporaryDirectory() as tmp:
        after, after_cpu = _timed(log, Path(tmp) / "after.mp4", result.plant_scenario,
                                  options, False)  # fmt: skip
        rows = log.t <= log.t[0] + sample
        part = SimLog(log.columns, np.ascontiguousarray(log.matrix[rows]), log.metadata)
        span = float(part.t[-1] - part.t[0])
        before, before_cpu = _timed(part, Path(tmp) / "before.mp4", result.plant_scenario,
                        VideoOptions(fps=30, width=640, height=480), True)  # fmt: skip
    frames = int(flight * options.fps) + 1
    print(f"{name}: {flight:.1f} s of flight, video {options.width}x{options.height} at "
          f"{options.fps:g} fps ({frames} frames)")  # fmt: skip
    print(f"  now:    {after:6.1f} s = {after / flight:.2f} s per flight second "
          f"({1e3 * after / frames:.0f} ms per frame), CPU {after_cpu / flight:.2f} s per "
          f"flight second; target <= {TARGET_S_PER_FLIGHT_S:g}")  # fmt: skip
    print(f"  before: {before / span:.2f} s per flight second, CPU {before_cpu / span:.2f} "
          f"(detail images at 30 fps, the first {span:.1f} s); ratio "
          f"{before / span / (after / flight):.1f}x")  # fmt: skip
    verdict = "meets" if after / flight <= TARGET_S_PER_FLIGHT_S else "MISSES"
    print(f"  {verdict} the target (on a busy machine the CPU time bounds the idle wall time)")


if __name__ == "__main__":
    main()
