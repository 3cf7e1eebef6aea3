"""Size and write time of a run directory (issue 25, item 5).

Targets: the demo mission's run directory (``make demo``: slope50, seed 0) at most 8 MB,
its log written in at most 0.3 s. Flies the mission once, then writes the log the way it
is written now and the way it was before (format 1: every column a plain float64 or
int64 array, 37 MB), back to back, best of 5; then the whole run directory (log, record,
summary, plans, figures); then its MCAP file (``tetherland export RUN_DIR --mcap``) with
the per-tick messages formatted column-wise (now) and row by row (the reference, one dict
and ``json.dumps`` per message), CPU time, back to back, best of 3.

Run: .venv/bin/python benchmarks/bench_log.py [scenario]
"""

from __future__ import annotations

import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from tetherland.config import load_scenario
from tetherland.runs import run_mission, save_run
from tetherland.sim import SimLog
from tetherland.sim.log import METADATA_KEY

TARGET_MB = 8.0
TARGET_WRITE_S = 0.3


def _format_1(log: SimLog, path: Path) -> None:
    """The writer before issue 25 (uncompressed float64, integer codes as int64)."""
    arrays = {}
    for c in log.columns:
        col = log[c.name]
        arrays[c.name] = col.astype(np.int64) if c.integer and np.isfinite(col).all() else col
    meta = {**log.metadata, "format_version": 1}
    arrays[METADATA_KEY] = np.array(json.dumps(meta, default=str))
    np.savez(path, **arrays)


def _best(write, path: Path, repeat: int = 5) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        write(path)
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    name = sys.argv[1] if len(sys.argv) > 1 else "slope50"
    result = run_mission(load_scenario(name), seed=0)
    log = result.log
    assert log is not None
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        now = _best(log.save, out / "now.npz")
        before = _best(lambda p: _format_1(log, p), out / "before.npz")
        mb_now = (out / "now.npz").stat().st_size / 1e6
        mb_before = (out / "before.npz").stat().st_size / 1e6
        run = out / "run"
        run.mkdir()
        t0 = time.perf_counter()
        save_run(result, run)
        whole = time.perf_counter() - t0
        mb_dir = sum(f.stat().st_size for f in run.iterdir()) / 1e6
        print(f"{name}: {len(log)} ticks, {len(log.columns)} column groups")
        print(f"  log now:    {mb_now:5.1f} MB written in {now:.3f} s")
        print(f"  log before: {mb_before:5.1f} MB written in {before:.3f} s (format 1)")
        print(f"  run directory: {mb_dir:.1f} MB (target <= {TARGET_MB:g}), written in "
              f"{whole:.2f} s with its figures; log write target <= {TARGET_WRITE_S:g} s")
        ok = mb_dir <= TARGET_MB and now <= TARGET_WRITE_S
        print(f"  {'meets' if ok else 'MISSES'} the targets")
        _mcap(run)


def _mcap(run_dir: Path) -> None:
    """CPU time of writing the run's MCAP file, column-wise and row by row."""
    try:
        from tetherland.viz import load_run
        from tetherland.viz.mcap import write_mcap
    except ImportError as err:
        print(f"  mcap: skipped ({err})")
        return
    run = load_run(run_dir)
    cpu: dict[bool, list[float]] = {False: [], True: []}
    for _ in range(3):
        for by_row in (False, True):
            t0 = time.process_time()
            write_mcap(run, run_dir / "run.mcap", by_row=by_row)
            cpu[by_row].append(time.process_time() - t0)
    mb = (run_dir / "run.mcap").stat().st_size / 1e6
    now, reference = min(cpu[False]), min(cpu[True])
    print(f"  mcap ({mb:.1f} MB, {len(run.log)} ticks): {now:.2f} s CPU column-wise, "
          f"{reference:.2f} s row by row ({reference / now:.1f}x)")


if __name__ == "__main__":
    main()
