"""Success rates with Wilson score intervals, and error distributions (issue 7)."""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

ERROR_FIELDS = (
    "landing.position_error_m",
    "landing.attitude_error_rad",
    "landing.touchdown_speed_mps",
    "landing.slip_m",
)


def wilson_interval(successes: int, n: int, z: float = 1.959963984540054) -> tuple[float, float]:
    """Wilson score interval for a binomial proportion (95 % by default).

    Well behaved at 0 and n successes, unlike the normal approximation.
    """
    if n == 0:
        return (0.0, 1.0)
    p = successes / n
    denom = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / denom
    half = z / denom * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    # the interval contains p; clamp rounding (e.g. 1 - 1e-16 at p = 1)
    return (max(0.0, min(centre - half, p)), min(1.0, max(centre + half, p)))


def _get(record: dict[str, Any], dotted: str) -> Any:
    node: Any = record.get("verdict", {})
    for part in dotted.split("."):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return node


def succeeded(record: dict[str, Any]) -> bool:
    """Did a campaign run succeed (it ran without error and its verdict says success)?"""
    return record.get("status") == "ok" and _get(record, "success") is True


@dataclass(frozen=True)
class RateSummary:
    """Success rate of one method at one sweep value.

    Attributes
    ----------
    method : str
    sweep_value : float or None
    n, successes, errors : int
        Runs, successful runs, runs that ended in an error (counted as failures).
    rate, ci_low, ci_high : float
        Success rate and its 95 % Wilson interval.
    medians : dict
        Median of each error field over the runs that report it.
    """

    method: str
    sweep_value: float | None
    n: int
    successes: int
    errors: int
    rate: float
    ci_low: float
    ci_high: float
    medians: dict[str, float | None]

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def summarize(records: list[dict[str, Any]]) -> list[RateSummary]:
    """Per (method, sweep value) success rates; each run_id counted once."""
    seen: dict[str, dict[str, Any]] = {}
    for r in records:
        seen[r["run_id"]] = r
    groups: dict[tuple[str, float | None], list[dict[str, Any]]] = defaultdict(list)
    for r in seen.values():
        groups[(r["method"], r.get("sweep_value"))].append(r)
    out = []
    for (method, value), rs in sorted(
        groups.items(), key=lambda kv: (kv[0][0], -math.inf if kv[0][1] is None else kv[0][1])
    ):
        n = len(rs)
        k = sum(1 for r in rs if succeeded(r))
        lo, hi = wilson_interval(k, n)
        medians = {}
        for f in ERROR_FIELDS:
            vals = [v for r in rs if isinstance(v := _get(r, f), (int, float))]
            medians[f] = float(np.median(vals)) if vals else None
        out.append(
            RateSummary(
                method=method,
                sweep_value=value,
                n=n,
                successes=k,
                errors=sum(1 for r in rs if r.get("status") != "ok"),
                rate=k / n,
                ci_low=lo,
                ci_high=hi,
                medians=medians,
            )
        )
    return out
