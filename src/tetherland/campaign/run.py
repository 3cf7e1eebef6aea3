"""Running a campaign: resume, parallel execution, durable results, summary (issue 7)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tetherland.campaign.executors import Executor
from tetherland.campaign.faults import fault_table
from tetherland.campaign.jobs import Job, execute, lost_record
from tetherland.campaign.spec import CampaignSpec, RunSpec
from tetherland.campaign.stats import RateSummary, summarize
from tetherland.campaign.store import KEEP_POLICIES, ResultsStore, retryable
from tetherland.errors import ConfigError
from tetherland.io import atomic_write_json


@dataclass(frozen=True)
class CampaignResult:
    """What a campaign produced (possibly partially, when interrupted)."""

    directory: Path
    total: int
    done: int
    new: int
    summary: list[RateSummary]
    interrupted: bool = False
    lost: int = 0
    """Runs lost to the infrastructure (their workers died more than ``retries`` times)."""


def campaign_job(spec: CampaignSpec, run: RunSpec, keep: str = "none",
                 keep_dir: str | None = None) -> Job:  # fmt: skip
    """The job of one run of ``spec`` (what a worker, a replay and a resume fly)."""
    return Job(spec.scenario, run, spec.job, spec.controller, spec.firmware, keep, keep_dir)


def pending_jobs(
    spec: CampaignSpec, store: ResultsStore, keep: str = "none"
) -> tuple[list[Job], int]:
    """Jobs not yet in the results table, and the campaign's total size."""
    runs = spec.expand()
    done = store.done_ids()
    keep_dir = str(store.runs_dir) if keep != "none" else None
    todo = [campaign_job(spec, run, keep, keep_dir) for run in runs if run.run_id not in done]
    return todo, len(runs)


def open_store(
    spec: CampaignSpec,
    directory: str | Path,
    *,
    resume: bool = False,
    provenance: dict[str, Any] | None = None,
) -> ResultsStore:
    """Create the campaign directory, or check it holds this campaign (``resume``)."""
    store = ResultsStore(directory)
    store.open(spec, resume=resume, provenance=provenance or {})
    return store


def run_campaign(
    spec: CampaignSpec,
    store: ResultsStore,
    executor: Executor,
    *,
    provenance: dict[str, Any] | None = None,
    on_result: Callable[[dict[str, Any]], None] | None = None,
    on_start: Callable[[int, int], None] | None = None,
    keep: str = "failures",
) -> CampaignResult:
    """Run every run of ``spec`` missing from ``store`` (see :func:`open_store`), appending
    each record as soon as it finishes.

    ``on_start(total, already_done)`` and ``on_result(record)`` drive a progress display.
    ``keep`` (:data:`~tetherland.campaign.store.KEEP_POLICIES`) says which runs keep their
    run directory in the campaign directory's ``runs/`` (default: those that failed).
    A KeyboardInterrupt stops at once: finished runs are kept, the runs in flight are
    abandoned (their workers stopped) and can be resumed. The executor is closed on
    return.
    """
    if keep not in KEEP_POLICIES:
        raise ConfigError(f"--keep must be one of {', '.join(KEEP_POLICIES)} (got {keep!r})")
    jobs, total = pending_jobs(spec, store, keep)
    if on_start:
        on_start(total, total - len(jobs))
    new = 0
    interrupted = False
    seen = store.done_ids()
    stop = executor.close
    try:
        for record in executor.map_unordered(execute, jobs, lost=lost_record):
            if record["run_id"] in seen:  # an engine that retried a lost worker's run
                continue
            seen.add(record["run_id"])
            store.append(record)
            new += 1
            if on_result:
                on_result(record)
    except KeyboardInterrupt:
        interrupted = True
        stop = executor.terminate  # the runs in flight are abandoned: --resume runs them
    except BaseException:
        stop = executor.terminate
        raise
    finally:
        stop()
    # runs lost to the infrastructure say nothing about the mission: not in the rates,
    # and not finished (--resume runs them again)
    restarts = getattr(executor, "restarts", None)  # pools rebuilt after a lost worker
    records = [r for r in store.load() if not retryable(r)]
    finished = {r["run_id"] for r in records}
    lost = sorted({r["run_id"] for r in store.load() if retryable(r)} - finished)
    summary = summarize(records)
    store.export_csv()
    atomic_write_json(
        store.dir / "summary.json",
        {
            "total_runs": total,
            "finished_runs": len(finished),
            "complete": len(finished) == total,
            "lost_runs": lost,
            "kept_runs": sorted(r["run_id"] for r in records if r.get("run_dir")),
            **({"worker_restarts": restarts} if restarts is not None else {}),
            "rates": [s.to_dict() for s in summary],
            **({"faults": fault_table(records)} if spec.faults else {}),
            "spec": spec.to_dict(),
            "provenance": provenance or {},
        },
    )
    return CampaignResult(
        directory=store.dir,
        total=total,
        done=len(finished),
        new=new,
        summary=summary,
        interrupted=interrupted,
        lost=len(lost),
    )
