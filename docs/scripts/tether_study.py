"""Table and figure of the cable study (docs/results.md): tethered success and landing error
against cable material and attachment offset, from the study's campaign directories.

Run: .venv/bin/python docs/scripts/tether_study.py RUNS_DIR [--png docs/tether_study.png]

RUNS_DIR holds one campaign directory per point, named MATERIAL_offR (R the offset in m,
e.g. ``nylon_off0.06``), each written by ``tetherland campaign slope50 --set
tether.length=1.2 --set tether.hook_drop=1.0 --set tether.material='"MATERIAL"' --set
"vehicle.cable_attachment=[0,0,-R]" --methods tethered --runs 100 --sweep
surface.slope_deg=50,70 --seed 2026 --out RUNS_DIR/MATERIAL_offR``. The default cable and
offset (Dyneema, 3 cm) are those of the 1000-run slope study, whose directory (same
command and seeds) may stand in for ``dyneema_off0.03``: only its tethered runs at 50 and
70 deg are read.
"""

from __future__ import annotations

import argparse
import json
import statistics
from collections import Counter
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

MATERIALS = ("ideal", "dyneema", "nylon")
OFFSETS = ("0.0", "0.03", "0.06")
SLOPES = (50.0, 70.0)


def _records(path: Path) -> list[dict]:
    runs: dict[str, dict] = {}
    for line in path.read_text().splitlines():
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            continue  # a torn last line
        runs[record["run_id"]] = record
    return list(runs.values())


def _failure(record: dict) -> str:
    verdict = record["verdict"]
    if record["status"] != "ok":
        return "error"
    if verdict.get("outcome") == "landing_conditions":
        bad = [k for k, ok in sorted(verdict["landing"]["conditions"].items()) if not ok]
        return "condition " + "+".join(bad)
    return "not flown" if verdict.get("outcome") == "no_run" else str(verdict.get("outcome"))


def point(records: list[dict], slope: float) -> dict:
    """Runs, successes, median landing error [m] and touchdown speed [m/s], failures."""
    runs = [r for r in records if r["method"] == "tethered" and r["sweep_value"] == slope]
    landed = [r["verdict"]["landing"] for r in runs
              if r["verdict"].get("landing", {}).get("position_error_m") is not None]  # fmt: skip
    return {
        "n": len(runs),
        "successes": sum(bool(r["verdict"].get("success")) for r in runs),
        "position_error_m": statistics.median(x["position_error_m"] for x in landed)
        if landed else None,
        "touchdown_speed_mps": statistics.median(x["touchdown_speed_mps"] for x in landed)
        if landed else None,
        "failures": Counter(_failure(r) for r in runs if not r["verdict"].get("success")),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs_dir", type=Path)
    parser.add_argument("--png", type=Path, default=Path("docs/tether_study.png"))
    args = parser.parse_args()
    points = {}
    for material in MATERIALS:
        for offset in OFFSETS:
            path = args.runs_dir / f"{material}_off{offset}" / "results.jsonl"
            if path.exists():
                records = _records(path)
                points[material, offset] = {s: point(records, s) for s in SLOPES}
    cols = ("cable", "offset", "50 deg: success", "median p_RL error / touchdown speed",
            "70 deg: success", "median p_RL error / touchdown speed", "failures (50 / 70 deg)")
    print("| " + " | ".join(cols) + " |")
    print("|---|---|---|---|---|---|---|")
    for (material, offset), by_slope in points.items():
        cells, fails = [], []
        for s in SLOPES:
            p = by_slope[s]
            cells.append(f"{p['successes']}/{p['n']}")
            cells.append("-" if p["position_error_m"] is None else
                         f"{1e3 * p['position_error_m']:.1f} mm / "
                         f"{1e3 * p['touchdown_speed_mps']:.0f} mm/s")  # fmt: skip
            fails.append(", ".join(f"{k} {n}" for k, n in p["failures"].most_common()) or "-")
        print(f"| {material} | {100 * float(offset):.0f} cm | " + " | ".join(cells)
              + f" | {fails[0]} / {fails[1]} |")  # fmt: skip
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.4))
    width = 0.13
    for j, s in enumerate(SLOPES):
        for i, material in enumerate(MATERIALS):
            for k, offset in enumerate(OFFSETS):
                p = points.get((material, offset), {}).get(s)
                if p is None or p["n"] == 0:
                    continue
                x = i + (k - 1) * 1.2 * width + (j - 0.5) * 0.45
                rate = 100.0 * p["successes"] / p["n"]
                axes[0].bar(x, rate, width, color=f"C{k}", label=f"{100 * float(offset):.0f} cm"
                            if i == 0 and j == 0 else None)  # fmt: skip
                if rate == 0.0:  # no success (e.g. not flown: no plan): mark the point
                    axes[0].plot(x, 2.0, marker="x", color=f"C{k}")
                if p["position_error_m"] is not None:
                    axes[1].bar(x, 1e3 * p["position_error_m"], width, color=f"C{k}")
    for ax, label in zip(axes, ("tethered success [%]", "median landing error [mm]"), strict=True):
        ax.set_xticks([i + d for i in range(3) for d in (-0.225, 0.225)])
        ax.set_xticklabels([f"{m}\n{int(s)} deg" for m in MATERIALS for s in SLOPES], fontsize=8)
        ax.set_ylabel(label)
        ax.grid(axis="y", alpha=0.3)
    axes[0].set_ylim(0, 135)
    axes[0].legend(title="attachment offset (x: none landed)", fontsize=8, title_fontsize=8,
                   loc="upper center", ncol=3)  # fmt: skip
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)
    print(f"figure: {args.png}")


if __name__ == "__main__":
    main()
