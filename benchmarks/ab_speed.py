"""This tree's closed-loop and campaign speed against another commit's, back to back.

The shared machine's speed drifts by a factor of 2-3 between days (commit 009063c flew
the ``slope50`` mission at 30.9x real time on the day issue 25 was filed and at 12.7x on
2026-12-05), so a real-time factor means something only beside a reference measured in
the same session. This script checks the other commit out into a temporary git worktree
and measures both trees alternately (A B A B, the same ``.venv``):

1. the full ``slope50`` and ``wall90`` missions, seed 0, hierarchical and DFL: the
   real-time factor on the process CPU time of the whole ``run_mission`` (after a 1 s
   warm-up run of the same controller in the same process: kernels loaded or compiled,
   planners built);
2. a ``slope50`` campaign of ``--campaign-runs`` runs per method (both methods, two
   workers, seed 1): the CPU of the command and its worker processes (``getrusage`` of
   the joined children) per run.

It prints each measurement and the ratio this / other of the means. Issue 25's targets
were set with 009063c's numbers of its day (30.9x, 1.75 s per run): a ratio r here puts
this tree at r times those numbers on that day's machine.

Both trees' kernels are compiled first (``python -m tetherland.warmup`` in each), so that
no round pays numba's compilation. Run (about 15 minutes):

    .venv/bin/python benchmarks/ab_speed.py [--against 009063c] [--rounds 2]
        [--campaign-runs 20]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

MISSION = """
import json, sys, time
from tetherland.config import load_scenario, with_overrides
from tetherland.runs import run_mission
scenario = load_scenario(sys.argv[1])
short = ["mission.abort_time=0.5", "mission.safe_hover_time=0.5"]
run_mission(with_overrides(scenario, short), controller=sys.argv[2])  # kernels, planners
cpu0 = time.process_time()
s = run_mission(scenario, controller=sys.argv[2], seed=0).summary
cpu = time.process_time() - cpu0
print(json.dumps({"success": bool(s["success"]), "sim_time_s": s["sim_time_s"], "cpu_s": cpu}))
"""

CAMPAIGN = "import sys; sys.argv[0] = 'tetherland'; from tetherland.cli import main; main()"


def _env(tree: Path) -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(tree / "src"), "MPLBACKEND": "Agg"}


def mission_factor(tree: Path, scenario: str, controller: str) -> float:
    """Sim time over the CPU time of one seed-0 mission flown with ``tree``'s code."""
    out = subprocess.run(
        [sys.executable, "-c", MISSION, scenario, controller],
        env=_env(tree), capture_output=True, text=True, check=True,
    ).stdout  # fmt: skip
    r = json.loads(out.strip().splitlines()[-1])
    if not r["success"]:
        print(f"  ({tree.name}: {scenario} {controller} did not succeed)")
    return r["sim_time_s"] / r["cpu_s"]


def campaign_cpu_per_run(tree: Path, runs: int) -> float:
    """CPU seconds per run of a ``slope50`` campaign (both methods, 2 workers, seed 1)."""
    with tempfile.TemporaryDirectory() as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run(
            [sys.executable, "-c", CAMPAIGN, "campaign", "slope50", "--runs", str(runs),
             "--workers", "2", "--seed", "1", "--out", str(Path(tmp) / "c")],
            env=_env(tree), capture_output=True, check=True,
        )  # fmt: skip
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        with open(Path(tmp) / "c" / "results.jsonl") as fh:
            n = sum(1 for line in fh if line.strip())
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu / n


def warm_up(tree: Path) -> None:
    """Compile ``tree``'s kernels into its numba cache (``tetherland.warmup``; a tree
    without that module compiles them on its first mission), so that the first round's
    campaign workers do not compile the kernels the missions never call."""
    subprocess.run([sys.executable, "-m", "tetherland.warmup", "--jobs", "2"], env=_env(tree),
                   capture_output=True)  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--against", default="009063c", help="the other commit")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--campaign-runs", type=int, default=20, help="runs per method")
    args = ap.parse_args()
    head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True, check=True).stdout.strip()  # fmt: skip
    with tempfile.TemporaryDirectory(prefix="tetherland-ab-") as tmp:
        other = Path(tmp) / args.against
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", str(other),
                        args.against], capture_output=True, check=True)  # fmt: skip
        try:
            trees = {args.against: other, f"this ({head})": ROOT}
            factors: dict[tuple[str, str], list[float]] = {}
            cpu: dict[str, list[float]] = {name: [] for name in trees}
            for tree in trees.values():  # every kernel compiled and cached before timing
                warm_up(tree)
            for k in range(args.rounds):
                for name, tree in trees.items():
                    for scenario in ("slope50", "wall90"):
                        for controller in ("hierarchical", "dfl"):
                            f = mission_factor(tree, scenario, controller)
                            factors.setdefault((name, f"{scenario} {controller}"), []).append(f)
                            print(f"round {k + 1} {name:>16s} {scenario} {controller}: "
                                  f"{f:.1f}x real time (CPU)", flush=True)  # fmt: skip
                    if args.campaign_runs:
                        c = campaign_cpu_per_run(tree, args.campaign_runs)
                        cpu[name].append(c)
                        print(f"round {k + 1} {name:>16s} campaign: {c:.2f} s CPU per run",
                              flush=True)  # fmt: skip
        finally:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(other)],
                           capture_output=True)  # fmt: skip
    a, b = trees
    print(f"\nmeans ({args.rounds} rounds), this / {args.against}:")
    for case in ("slope50 hierarchical", "slope50 dfl", "wall90 hierarchical", "wall90 dfl"):
        fa, fb = statistics.mean(factors[a, case]), statistics.mean(factors[b, case])
        print(f"  {case:22s} {fa:5.1f}x -> {fb:5.1f}x  ratio {fb / fa:.2f}")
    if args.campaign_runs:
        ca, cb = statistics.mean(cpu[a]), statistics.mean(cpu[b])
        print(f"  {'campaign CPU per run':22s} {ca:5.2f} s -> {cb:5.2f} s  ratio {cb / ca:.2f}")


if __name__ == "__main__":
    main()
