"""What a campaign directory says: success by point with 95 % intervals, failures by kind
and phase, hooking attempts by outcome, faults by phase, and the figures
(``tetherland campaign report DIR``).

The report is read from the directory alone (``campaign.json`` and ``results.jsonl``), so
it can be made of a finished, interrupted or running campaign.
"""

from __future__ import annotations

import json
from collections import Counter, defaultdict
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from tetherland.campaign.faults import fault_table
from tetherland.campaign.spec import CampaignSpec
from tetherland.campaign.stats import RateSummary, summarize
from tetherland.campaign.store import MANIFEST, ResultsStore, retryable
from tetherland.errors import ConfigError

ERROR_KIND = "error"
"""Failure kind of a run that ended in an error (its own: bad input, an internal error)."""


@dataclass(frozen=True)
class FailureGroup:
    """Runs of one method that failed the same way in the same phase.

    Attributes
    ----------
    method : str
    kind : str
        The deciding failure: an :class:`~tetherland.verdict.Outcome` value (``crashed``,
        ``landing_conditions``, ...) or ``error``.
    phase : str
        The phase it happened in (``-``: not tied to a time; ``unknown``: a record written
        before failures were explained).
    runs : int
    run_ids : tuple of str
        Every such run, in the campaign's order (replay one with ``tetherland replay``).
    """

    method: str
    kind: str
    phase: str
    runs: int
    run_ids: tuple[str, ...]

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def deciding_failure(record: dict[str, Any]) -> tuple[str, str]:
    """(kind, phase) of the failure that decided a failed run (the judge's first)."""
    if record.get("status") != "ok":
        return ERROR_KIND, "-"
    verdict = record["verdict"]
    failures = verdict.get("failures")
    if failures:
        return str(failures[0]["outcome"]), str(failures[0].get("phase") or "-")
    return str(verdict.get("outcome", "failure")), "unknown"


def failure_groups(records: list[dict[str, Any]]) -> list[FailureGroup]:
    """The failed runs grouped by method, deciding failure and phase, most runs first."""
    groups: dict[tuple[str, str, str], list[str]] = defaultdict(list)
    for r in records:
        if r.get("status") == "ok" and r["verdict"].get("success"):
            continue
        kind, phase = deciding_failure(r)
        groups[(r["method"], kind, phase)].append(r["run_id"])
    out = [FailureGroup(m, k, p, len(ids), tuple(ids)) for (m, k, p), ids in groups.items()]
    return sorted(out, key=lambda g: (g.method, -g.runs, g.kind, g.phase))


@dataclass(frozen=True)
class HookingCounts:
    """The hooking attempts of one method at one point, on the plant's truth
    (:mod:`tetherland.verdict.hooking`).

    Attributes
    ----------
    method : str
    sweep_value : float or None
    runs : int
        Runs that flew at least one hooking pass.
    attempts : dict
        Attempts by outcome (``caught``, ``bounced``, ``wrong_side``, ``tangled``,
        ``missed``).
    lost : int
        Runs whose hook, caught for the landing, came off before the release.
    not_released : int
        Runs whose hook was still caught after the robot's release.
    """

    method: str
    sweep_value: float | None
    runs: int
    attempts: dict[str, int]
    lost: int
    not_released: int

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def hooking_counts(records: list[dict[str, Any]]) -> list[HookingCounts]:
    """Hooking attempts by outcome per method and point (runs without a hooking record,
    e.g. contact-free, or from before it, are left out)."""
    points: dict[tuple[str, float | None], list[dict[str, Any]]] = defaultdict(list)
    for r in records:
        h = (r.get("verdict") or {}).get("hooking") if r.get("status") == "ok" else None
        if h and h.get("attempts"):
            points[(r["method"], r.get("sweep_value"))].append(h)
    out = []
    for (method, value), hs in points.items():
        counts = Counter(a for h in hs for a in h["attempts"])
        out.append(HookingCounts(
            method, value, len(hs), dict(counts), sum(h.get("t_lost") is not None for h in hs),
            sum(h.get("release") == "not_released" for h in hs),
        ))  # fmt: skip
    return out


@dataclass(frozen=True)
class CampaignReport:
    """A campaign directory read back.

    Attributes
    ----------
    directory : Path
    spec : CampaignSpec
    total : int
        Runs the campaign has.
    records : list of dict
        The finished runs' records (lost ones left out), in the campaign's order.
    rates : list of RateSummary
        Success by method and sweep value, with 95 % Wilson intervals.
    failures : list of FailureGroup
    faults : dict or None
        Fault campaigns: fault kind -> phase at the fault time -> outcome -> runs.
    lost : list of str
        Runs lost to the infrastructure (``--resume`` runs them).
    hooking : list of HookingCounts
        Hooking attempts by outcome per method and point (plant truth).
    """

    directory: Path
    spec: CampaignSpec
    total: int
    records: list[dict[str, Any]]
    rates: list[RateSummary]
    failures: list[FailureGroup]
    faults: dict[str, dict[str, dict[str, int]]] | None
    lost: list[str]
    hooking: list[HookingCounts]

    @property
    def complete(self) -> bool:
        return len(self.records) == self.total

    @classmethod
    def load(cls, directory: str | Path) -> CampaignReport:
        """Read a campaign directory.

        Raises
        ------
        ConfigError
            One line when ``directory`` holds no campaign.
        """
        path = Path(directory)
        manifest = path / MANIFEST
        if not manifest.is_file():
            raise ConfigError(f"{directory}: not a campaign directory (no {MANIFEST})")
        try:
            spec = CampaignSpec.from_dict(json.loads(manifest.read_text(encoding="utf-8"))["spec"])
        except (OSError, ValueError, KeyError, TypeError) as err:
            raise ConfigError(f"{manifest}: unreadable campaign manifest ({err})") from None
        order = {r.run_id: i for i, r in enumerate(spec.expand())}
        latest = {r["run_id"]: r for r in ResultsStore(path).load() if r.get("run_id") in order}
        records = sorted((r for r in latest.values() if not retryable(r)),
                         key=lambda r: order[r["run_id"]])  # fmt: skip
        lost = sorted(k for k, r in latest.items() if retryable(r))
        return cls(
            directory=path, spec=spec, total=len(order), records=records,
            rates=summarize(records), failures=failure_groups(records),
            faults=fault_table(records) if spec.faults else None, lost=lost,
            hooking=hooking_counts(records),
        )  # fmt: skip

    def outcomes(self) -> dict[str, int]:
        """Runs per verdict outcome (``error`` for runs that ended in an error)."""
        return dict(Counter(
            r["verdict"].get("outcome", "failure") if r.get("status") == "ok" else ERROR_KIND
            for r in self.records
        ))  # fmt: skip

    def draw(self) -> dict[str, Path]:
        """Write ``success_rate.png`` and ``errors.png`` (when some run reports landing
        errors) into the campaign directory; returns them by role."""
        from tetherland.campaign.plots import plot_errors, plot_success

        sweep = self.spec.sweep.key if self.spec.sweep else None
        files = {"success_rate": plot_success(self.rates, self.directory / "success_rate.png",
                                              sweep)}  # fmt: skip
        errors = plot_errors(self.records, self.directory / "errors.png")
        if errors is not None:
            files["errors"] = errors
        return files

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (``tetherland campaign report DIR --json``)."""
        return {
            "directory": str(self.directory),
            "total_runs": self.total,
            "finished_runs": len(self.records),
            "complete": self.complete,
            "lost_runs": self.lost,
            "outcomes": self.outcomes(),
            "rates": [s.to_dict() for s in self.rates],
            "failures": [g.to_dict() for g in self.failures],
            "hooking": [h.to_dict() for h in self.hooking],
            **({"faults": self.faults} if self.faults is not None else {}),
            "kept_runs": [r["run_id"] for r in self.records if r.get("run_dir")],
        }
