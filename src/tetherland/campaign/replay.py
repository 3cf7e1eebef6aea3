"""Replay one campaign run exactly and compare it with what the campaign recorded.

A campaign run is a pure function of its job (the campaign's specification from
``campaign.json`` and the run's id): :func:`replay` rebuilds the job and flies it through
the same :func:`~tetherland.campaign.jobs.run_job` the campaign's workers use (the same
draw of perturbation, wind and fault, the same seed), then compares the new record with
the run's line of ``results.jsonl`` after a JSON round trip, so equal means equal bit for
bit. Only what depends on the machine is left out (:data:`MACHINE_FIELDS`).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tetherland.campaign.jobs import VOLATILE, run_job
from tetherland.campaign.report import CampaignReport
from tetherland.campaign.run import campaign_job
from tetherland.campaign.spec import RunSpec
from tetherland.io import to_jsonable
from tetherland.runs import RunResult

MACHINE_FIELDS = ("wall_time_s", "cpu_time_s", "run_dir", "run_dir_error")
"""Record fields that say how the run was executed, not what it did (the verdict's
:data:`~tetherland.campaign.jobs.VOLATILE` fields are left out too)."""


@dataclass(frozen=True)
class Replay:
    """A campaign run flown again.

    Attributes
    ----------
    directory : Path
        The campaign directory.
    run : RunSpec
    record : dict
        The replay's record, as the campaign writes it.
    result : RunResult or None
        The flown run (None for an analysis campaign, or when the run raised an error).
    recorded : dict or None
        The run's record in ``results.jsonl`` (None: not finished yet).
    differences : tuple of str
        Where the replay differs from the recorded run (empty: identical).
    """

    directory: Path
    run: RunSpec
    record: dict[str, Any]
    result: RunResult | None
    recorded: dict[str, Any] | None
    differences: tuple[str, ...]

    @property
    def identical(self) -> bool | None:
        """The replay equals the recorded run (None: nothing recorded to compare)."""
        return None if self.recorded is None else not self.differences


def comparable(record: dict[str, Any]) -> Any:
    """A record as written to ``results.jsonl`` and read back, without the machine's fields."""
    doc = json.loads(json.dumps(to_jsonable(record), allow_nan=False))
    for key in MACHINE_FIELDS:
        doc.pop(key, None)
    for key in VOLATILE:
        doc.get("verdict", {}).pop(key, None)
    return doc


def differences(recorded: Any, replayed: Any, path: str = "") -> Iterator[str]:
    """Where ``replayed`` differs from ``recorded`` (JSON documents): a key the record has
    and the replay has not, or another value. Keys only the replay has are fields added
    after the campaign ran (an older tetherland) and are not compared."""
    if isinstance(recorded, dict) and isinstance(replayed, dict):
        for key, value in recorded.items():
            where = f"{path}.{key}" if path else key
            if key not in replayed:
                yield f"{where}: recorded {value!r:.60}, not in the replay"
            else:
                yield from differences(value, replayed[key], where)
    elif isinstance(recorded, list) and isinstance(replayed, list) and len(recorded) == len(
        replayed
    ):
        for i, (a, b) in enumerate(zip(recorded, replayed, strict=True)):
            yield from differences(a, b, f"{path}[{i}]")
    elif recorded != replayed or type(recorded) is not type(replayed):
        yield f"{path}: recorded {recorded!r:.60}, replayed {replayed!r:.60}"


def replay(directory: str | Path, run_id: str) -> Replay:
    """Fly run ``run_id`` of the campaign in ``directory`` again, as its worker did.

    Raises
    ------
    ConfigError
        One line when ``directory`` holds no campaign or ``run_id`` is none of its runs.
    """
    report = CampaignReport.load(directory)  # reads the manifest: one line if it is none
    run = report.spec.run(run_id)
    recorded = next((r for r in report.records if r["run_id"] == run_id), None)
    record, result = run_job(campaign_job(report.spec, run))
    found = () if recorded is None else tuple(differences(comparable(recorded),
                                                          comparable(record)))  # fmt: skip
    return Replay(Path(directory), run, record, result, recorded, found)
