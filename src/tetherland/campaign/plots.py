"""Campaign figures: success rate versus the swept value, and error distributions."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

from tetherland.campaign.stats import ERROR_FIELDS, RateSummary, _get
from tetherland.io import atomic_write_with

_COLORS = {"tethered": "tab:blue", "free-flight": "tab:orange"}


def plot_success(summary: list[RateSummary], path: Path, sweep_key: str | None) -> Path:
    """Success rate per method with 95 % Wilson intervals, versus the sweep value."""
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for method in sorted({s.method for s in summary}):
        rows = [s for s in summary if s.method == method]
        xs = [s.sweep_value if s.sweep_value is not None else 0.0 for s in rows]
        ys = [100 * s.rate for s in rows]
        err = [
            [100 * (s.rate - s.ci_low) for s in rows],
            [100 * (s.ci_high - s.rate) for s in rows],
        ]
        ax.errorbar(
            xs, ys, yerr=err, marker="o", capsize=3, label=method, color=_COLORS.get(method)
        )
    ax.set_xlabel(sweep_key or "scenario")
    ax.set_ylabel("success rate [%] (95 % CI)")
    ax.set_ylim(-5, 105)
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    atomic_write_with(path, lambda p: fig.savefig(p, dpi=120))
    plt.close(fig)
    return path


def plot_errors(records: list[dict[str, Any]], path: Path) -> Path | None:
    """Box plots of the landing errors per method (None if no run reports them)."""
    methods = sorted({r["method"] for r in records})
    data = {
        f: [
            [v for r in records if r["method"] == m and isinstance(v := _get(r, f), (int, float))]
            for m in methods
        ]
        for f in ERROR_FIELDS
    }
    fields = [f for f in ERROR_FIELDS if any(data[f])]
    if not fields:
        return None
    fig, axes = plt.subplots(1, len(fields), figsize=(3.2 * len(fields), 3.6), squeeze=False)
    for ax, f in zip(axes[0], fields, strict=True):
        ax.boxplot([d if d else [float("nan")] for d in data[f]], tick_labels=methods)
        ax.set_title(f.split(".")[-1], fontsize=9)
        ax.set_yscale("log")
        ax.grid(alpha=0.3)
    fig.tight_layout()
    atomic_write_with(path, lambda p: fig.savefig(p, dpi=120))
    plt.close(fig)
    return path
