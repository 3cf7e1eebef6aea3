"""How much of a mission's control tick is compiled code, and how much the interpreter
around it (valgrind callgrind; load-independent).

The floor of issue 25's loop targets: a tick can get no cheaper than its compiled work
(numba kernels with the MuJoCo steps they call) however little Python calls them. One
full ``slope50`` mission (``hotpaths.py mission 1``, seed 0, hierarchical) runs under
callgrind counting only the runner's loop; the inclusive cost of numba's dispatcher
(``Dispatcher_call``: every compiled call, MuJoCo's ``mj_step1``/``mj_step2`` inside the
physics step included) is the compiled work, its part outside the compiled function
(``call_cfunc``) numba's per-call dispatch, and everything else the interpreter, numpy
and the few C calls made from Python. Prints instructions per control tick of each and
the loop's best possible speed-up with no Python at all, ``total / compiled``.

Run (several minutes; the first callgrind run of a tree recompiles its kernels, which
takes tens of minutes, see ``hotpaths.py``):

    .venv/bin/python benchmarks/callgrind_share.py [python]

Not part of ``make bench``. Measured (issue 25, d4ff42b, 40081 control ticks): 584.2k
instructions per tick, compiled 300.0k (51 %; MuJoCo's two steps 125.4k), numba's
dispatch 18.0k, the interpreter and the rest 266.3k: with no Python at all the loop
would be 1.95x faster, the tethered campaign run about 1.8 s of CPU instead of 3.55 s.
"""

from __future__ import annotations

import re
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent

SYMBOLS = {
    "Dispatcher_call": "compiled calls (numba kernels, MuJoCo inside them), with dispatch",
    "call_cfunc": "compiled calls without numba's argument dispatch",
    "mj_step1": "MuJoCo mj_step1",
    "mj_step2": "MuJoCo mj_step2",
}


def inclusive_costs(annotated: str) -> dict[str, int]:
    """The inclusive instruction count of each of :data:`SYMBOLS` in the output of
    ``callgrind_annotate --inclusive=yes`` (the first, outermost line of each: recursive
    entries are marked with a quote and skipped), and the program total."""
    costs: dict[str, int] = {}
    for line in annotated.splitlines():
        m = re.match(r"\s*([\d,]+)\s+\([^)]*\)\s+(.*)", line)
        if not m:
            continue
        value, where = int(m.group(1).replace(",", "")), m.group(2)
        if where.startswith("PROGRAM TOTALS"):
            costs["total"] = value
            continue
        for symbol in SYMBOLS:
            if re.search(rf"[:\s]{symbol}(\(|\s|$)", where) and symbol not in costs:
                costs[symbol] = value
    return costs


def main() -> None:
    python = sys.argv[1] if len(sys.argv) > 1 else sys.executable
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "callgrind.out"
        run = subprocess.run(
            ["valgrind", "--tool=callgrind", "--toggle-collect=math_fsum",
             f"--callgrind-out-file={out}", python, str(HERE / "hotpaths.py"), "mission", "1"],
            capture_output=True, text=True, check=True,
        )  # fmt: skip
        ticks = int(re.search(r"^ticks=(\d+)", run.stdout, re.M).group(1))  # type: ignore[union-attr]
        annotated = subprocess.run(
            ["callgrind_annotate", "--inclusive=yes", "--threshold=100", str(out)],
            capture_output=True, text=True, check=True,
        ).stdout  # fmt: skip
    c = inclusive_costs(annotated)
    total, compiled = c["total"], c["Dispatcher_call"]
    dispatch = compiled - c["call_cfunc"]
    mujoco = c.get("mj_step1", 0) + c.get("mj_step2", 0)

    def per_tick(n: int) -> str:
        return f"{n / ticks / 1e3:8.1f}k"

    print(f"instructions per control tick (slope50, hierarchical, seed 0, {ticks} ticks):")
    print(f"  total                                      {per_tick(total)}")
    print(f"  compiled (numba kernels with MuJoCo)       {per_tick(c['call_cfunc'])}"
          f"  ({100 * c['call_cfunc'] / total:.0f} %)")  # fmt: skip
    print(f"    of which MuJoCo's mj_step1 and mj_step2  {per_tick(mujoco)}")
    print(f"  numba's dispatch of those calls            {per_tick(dispatch)}")
    print(f"  interpreter, numpy and the rest            {per_tick(total - compiled)}")
    print(f"best speed-up with no Python at all: {total / c['call_cfunc']:.2f}x")


if __name__ == "__main__":
    main()
