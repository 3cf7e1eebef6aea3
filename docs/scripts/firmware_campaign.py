"""The same campaign flown through the firmware and on tetherland's own inner loop, compared
(docs/firmware.md, docs/results.md).

Run: .venv/bin/python docs/scripts/firmware_campaign.py FIRMWARE_DIR OWN_DIR

Both directories come from ``tetherland campaign slope50 --methods tethered --runs 50
--workers 2 --seed 2026 [--firmware betaflight] --out DIR``: the same seed gives every run
the same perturbation in both (common random numbers), so runs pair by ``run_id``. Prints a
Markdown table (successes, medians and 95th percentiles of the landing measures) and every
failure with its verdict.
"""

from __future__ import annotations

import argparse
import json
import statistics
from pathlib import Path

import numpy as np

MEASURES = (
    ("position_error_m", "landing error [mm]", 1e3),
    ("attitude_error_rad", "attitude error [deg]", 180.0 / np.pi),
    ("touchdown_speed_mps", "touchdown speed [mm/s]", 1e3),
    ("touchdown_angular_rate_rps", "touchdown rate [rad/s]", 1.0),
    ("touchdown_accel_mps2", "touchdown accel. [m/s^2]", 1.0),
)


def records(directory: Path) -> dict[str, dict]:
    runs = {}
    for line in (directory / "results.jsonl").read_text().splitlines():
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            continue  # a torn last line
        runs[record["run_id"]] = record
    return runs


def failure(record: dict) -> str:
    v = record["verdict"]
    if record["status"] != "ok":
        return f"error: {record['error']}"
    if v.get("outcome") == "landing_conditions":
        bad = [k for k, ok in sorted(v["landing"]["conditions"].items()) if not ok]
        return "landing condition " + "+".join(bad)
    return f"{v.get('outcome')}: {v.get('abort_reason') or v.get('reason')}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("firmware", type=Path)
    parser.add_argument("own", type=Path)
    args = parser.parse_args()
    sides = {"Betaflight SITL": records(args.firmware), "tetherland's own": records(args.own)}
    common = sorted(set.intersection(*(set(r) for r in sides.values())))
    print(f"{len(common)} paired runs\n")
    header = " | ".join(f"{label}, median (95th pct.)" for _, label, _ in MEASURES)
    print(f"| inner loop | success | {header} | wall per run [s] |")
    print("|---|---|" + "---|" * len(MEASURES) + "---|")
    for name, runs in sides.items():
        rows = [runs[i] for i in common]
        ok = sum(bool(r["verdict"].get("success")) for r in rows)
        cells = []
        for key, _, scale in MEASURES:
            landed = [r["verdict"]["landing"] for r in rows if r["status"] == "ok"]
            values = [scale * m[key] for m in landed if m.get(key) is not None]
            median, p95 = (statistics.median(values), np.percentile(values, 95)) if values else (
                np.nan, np.nan)  # fmt: skip
            cells.append(f"{median:.3g} ({p95:.3g})")
        wall = statistics.median(r["wall_time_s"] for r in rows)
        print(f"| {name} | {ok}/{len(rows)} | " + " | ".join(cells) + f" | {wall:.0f} |")
    print()
    for name, runs in sides.items():
        for run_id in common:
            record = runs[run_id]
            if not record["verdict"].get("success"):
                print(f"{name}: {run_id} (seed {record['seed']}): {failure(record)}")


if __name__ == "__main__":
    main()
