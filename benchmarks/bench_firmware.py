"""Real-time factor of the full mission through the Betaflight SITL, and where the time goes.

Target (issue 27): at least 2x real time per mission through the firmware on one core.
Prints, per seed, the real-time factor of slope50 through the firmware and on
tetherland's own inner loop (back to back: the machine is shared), then the firmware's
share: the wall time per IMU sample spent in the lockstep exchange (one state packet,
one loop of the firmware, its motor packet) and the time to start a configured firmware.
The simulation runs on one core; the firmware process runs in lockstep with it, so the
two never compute at the same time.

Run: .venv/bin/python benchmarks/bench_firmware.py [scenario] [seeds]
"""

from __future__ import annotations

import statistics
import sys
import time

from tetherland.config import load_scenario
from tetherland.firmware import BetaflightSitl, FirmwareInnerLoop, ensure_firmware
from tetherland.runs import run_mission

TARGET_RTF = 2.0


def main() -> None:
    name = sys.argv[1] if len(sys.argv) > 1 else "slope50"
    seeds = range(int(sys.argv[2]) if len(sys.argv) > 2 else 3)
    scenario = load_scenario(name)
    build = ensure_firmware()
    print(f"firmware: {build.executable.name} (built in {build.build_seconds} s)")
    step_time = [0.0, 0]
    original = FirmwareInnerLoop.step

    def timed(self, imu):
        t0 = time.perf_counter()
        try:
            return original(self, imu)
        finally:
            step_time[0] += time.perf_counter() - t0
            step_time[1] += 1

    FirmwareInnerLoop.step = timed  # type: ignore[method-assign]
    start_time = []
    original_start = FirmwareInnerLoop.start

    def timed_start(self):
        t0 = time.perf_counter()
        original_start(self)
        start_time.append(time.perf_counter() - t0)

    FirmwareInnerLoop.start = timed_start  # type: ignore[method-assign]
    rtf = {"firmware": [], "own": []}
    for seed in seeds:
        for kind in ("firmware", "own"):
            inner = BetaflightSitl() if kind == "firmware" else None
            s = run_mission(scenario, seed=seed, inner_loop=inner).summary
            rtf[kind].append(s["real_time_factor"])
            print(f"seed {seed} {kind:8s}: {s['outcome']}, {s['sim_time_s']:.1f} s simulated, "
                  f"{s['real_time_factor']:.2f}x real time", flush=True)  # fmt: skip
    fw, own = statistics.median(rtf["firmware"]), statistics.median(rtf["own"])
    print(f"median real-time factor: firmware {fw:.2f}x (target >= {TARGET_RTF:g}x), "
          f"tetherland's own inner loop {own:.2f}x")
    print(f"lockstep exchange per IMU sample (boot included): "
          f"{1e6 * step_time[0] / max(step_time[1], 1):.1f} us; "
          f"start of a configured firmware (boot 2 s of firmware time included): "
          f"{statistics.median(start_time):.2f} s")


if __name__ == "__main__":
    main()
