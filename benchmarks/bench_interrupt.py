"""How fast a campaign stops, and how fast a bad cluster address fails (issues 24 and 28).

1. SIGINT to `tetherland campaign slope50 --workers 2` while both workers fly closed-loop
   missions: seconds from the signal to the end of the process (target: under 2 s).
2. `--engine dask|ray --address` of a local server that accepts TCP connections and
   answers nothing: seconds from the command's start to its one-line error (target:
   under 30 s, the command's own start-up included).

Run: .venv/bin/python benchmarks/bench_interrupt.py [repeats]
"""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

EXE = str(Path(sys.executable).with_name("tetherland"))


def _workers_busy(pid: int) -> bool:
    children = Path(f"/proc/{pid}/task/{pid}/children")
    if not children.exists():
        return False
    spawned = 0
    for child in children.read_text().split():
        try:
            spawned += b"spawn_main" in Path(f"/proc/{child}/cmdline").read_bytes()
        except OSError:
            pass
    return spawned >= 2


def stop_time(out: Path) -> float:
    """Seconds from SIGINT to the end of a campaign whose two workers fly missions."""
    cmd = [EXE, "campaign", "slope50", "--runs", "4", "--workers", "2", "--out", str(out)]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    while not _workers_busy(proc.pid):
        time.sleep(0.05)
    time.sleep(10.0)  # into their first missions
    t0 = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    proc.wait()
    assert proc.returncode == 130, proc.returncode
    return time.perf_counter() - t0


def silent_address_time(engine: str, out: Path) -> float:
    """Seconds from the start of a campaign on a silent address to its error."""
    server = socket.create_server(("127.0.0.1", 0))
    conns: list[socket.socket] = []

    def accept() -> None:
        while True:
            try:
                conns.append(server.accept()[0])
            except OSError:
                return

    threading.Thread(target=accept, daemon=True).start()
    port = server.getsockname()[1]
    t0 = time.perf_counter()
    proc = subprocess.run(
        [EXE, "campaign", "slope50", "--job", "analysis", "--runs", "1", "--engine", engine,
         "--address", f"127.0.0.1:{port}", "--out", str(out)],
        capture_output=True, text=True, check=False,
    )  # fmt: skip
    elapsed = time.perf_counter() - t0
    server.close()
    for c in conns:
        c.close()
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    return elapsed


def main() -> None:
    repeats = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    with tempfile.TemporaryDirectory() as d:
        stops = [stop_time(Path(d) / f"c{k}") for k in range(repeats)]
        print(
            "SIGINT to exit, 2 workers in missions: "
            + ", ".join(f"{s:.2f}" for s in stops)
            + f" s (max {max(stops):.2f} s, target < 2 s)"
        )
        for engine in ("dask", "ray"):
            t = silent_address_time(engine, Path(d) / engine)
            print(f"silent --address, --engine {engine}: error after {t:.1f} s (target < 30 s)")


if __name__ == "__main__":
    main()
