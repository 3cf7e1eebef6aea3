"""Verdict invariance of the fast loop (issue 13): same outcomes at seeds 0-4.

Runs the full mission on ``slope50``, ``pipe60`` and ``steep70`` (hierarchical controller)
and ``slope50`` with DFL at seeds 0-4 and writes one JSON line per run (success, the
failing reasons, the touchdown measures). With ``--compare FILE`` it compares the outcomes
against an earlier record and exits 1 when any outcome changed (float differences allowed).

Run: .venv/bin/python benchmarks/check_verdicts.py --out /tmp/verdicts.jsonl
     .venv/bin/python benchmarks/check_verdicts.py --out /tmp/now.jsonl \
         --compare benchmarks/verdicts_d57bf1a.jsonl

``verdicts_d57bf1a.jsonl`` is the record of commit d57bf1a (before the compiled loop of
issue 13), ``verdicts_27d15a3.jsonl`` that of main 27d15a3 (elastic cable, new planner; the
last main merged before the compiled loop went in). About 2 minutes at 20x real time
(20 missions of 60-80 s).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from tetherland.config import load_scenario
from tetherland.methods import Planners
from tetherland.runs import run_mission

CASES = (
    ("slope50", "hierarchical"),
    ("pipe60", "hierarchical"),
    ("steep70", "hierarchical"),
    ("slope50", "dfl"),
)
SEEDS = range(5)


def _record(summary: dict) -> dict:
    landing = summary["landing"]
    return {
        "scenario": summary["scenario"],
        "controller": summary["controller"],
        "seed": summary["seed"],
        "success": summary["success"],
        "reason": summary["reason"],
        "conditions": landing.get("conditions"),
        "position_error_m": landing.get("position_error_m"),
        "touchdown_speed_mps": landing.get("touchdown_speed_mps"),
        "attitude_error_rad": landing.get("attitude_error_rad"),
        "min_tension_N": landing.get("min_tension_N"),
        "sim_time_s": summary["sim_time_s"],
        "real_time_factor": summary["real_time_factor"],
    }


def _num(rec: dict | None, key: str, scale: float) -> str:
    value = None if rec is None else rec.get(key)
    return "-" if value is None else f"{value * scale:.2f}"


def _key(r: dict) -> tuple:
    return (r["scenario"], r["controller"], r["seed"])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, required=True, help="JSON-lines record to write")
    ap.add_argument("--compare", type=Path, help="earlier record to compare the outcomes with")
    args = ap.parse_args()
    by_scenario: dict[str, Planners] = {}
    records = []
    with args.out.open("w") as fh:
        for name, controller in CASES:
            sc = load_scenario(name)
            planners = by_scenario.setdefault(name, Planners())
            for seed in SEEDS:
                s = run_mission(sc, controller=controller, seed=seed, planners=planners).summary
                rec = _record(s)
                records.append(rec)
                fh.write(json.dumps(rec) + "\n")
                fh.flush()
                print(f"{name:8s} {controller:12s} seed {seed}: {rec['reason']} "
                      f"({rec['real_time_factor']:.1f}x real time)", flush=True)  # fmt: skip
    if args.compare is None:
        return 0
    before = {_key(r): r for r in map(json.loads, args.compare.read_text().splitlines())}
    changed = 0
    print(f"\n{'case':30s} {'before':10s} {'after':10s} position error [mm] / touchdown "
          "speed [mm/s] / min tension [N], before -> after")  # fmt: skip
    for rec in records:
        old = before.get(_key(rec))
        same = old is not None and (old["success"], old["reason"], old["conditions"]) == (
            rec["success"], rec["reason"], rec["conditions"],
        )  # fmt: skip
        changed += not same
        case = f"{rec['scenario']} {rec['controller']} seed {rec['seed']}"
        floats = " / ".join(
            f"{_num(old, key, scale)} -> {_num(rec, key, scale)}"
            for key, scale in (("position_error_m", 1e3), ("touchdown_speed_mps", 1e3),
                               ("min_tension_N", 1.0))
        )  # fmt: skip
        print(f"{case:30s} {old['reason'] if old else '-':10s} {rec['reason']:10s} {floats}"
              f"{'' if same else '  CHANGED'}")  # fmt: skip
    print(f"\n{changed} changed outcome(s) of {len(records)}")
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main())
