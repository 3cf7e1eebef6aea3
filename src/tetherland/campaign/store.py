"""The campaign directory: manifest, append-only results table, resume.

``results.jsonl`` gets one line per finished run, written and fsync'ed by the main
process as soon as the run ends, so a crash or Ctrl-C loses nothing; a torn last line
is discarded on reopening. ``results.csv`` is a flattened copy written atomically at the
end (and by ``--resume``).
"""

from __future__ import annotations

import csv
import io
import json
import os
from pathlib import Path
from typing import Any

from tetherland.campaign.spec import CampaignSpec
from tetherland.errors import ConfigError
from tetherland.io import atomic_write_json, atomic_write_text, to_jsonable

MANIFEST = "campaign.json"
RESULTS = "results.jsonl"


def flatten(record: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested dict -> flat dict with dotted keys (lists kept as JSON text)."""
    out: dict[str, Any] = {}
    for k, v in record.items():
        name = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, f"{name}."))
        elif isinstance(v, (list, tuple)):
            out[name] = json.dumps(to_jsonable(v))
        else:
            out[name] = v
    return out


class ResultsStore:
    """Manifest and results of one campaign directory."""

    def __init__(self, directory: str | os.PathLike[str]):
        self.dir = Path(directory)

    @property
    def results_path(self) -> Path:
        return self.dir / RESULTS

    def open(self, spec: CampaignSpec, *, resume: bool, provenance: dict[str, Any]) -> None:
        """Create the directory for ``spec``, or check that it holds the same campaign."""
        manifest = self.dir / MANIFEST
        if manifest.exists():
            old = json.loads(manifest.read_text())
            if not resume:
                raise ConfigError(
                    f"--out {self.dir} already holds a campaign; add --resume to continue it "
                    "or choose another directory"
                )
            if old.get("fingerprint") != spec.fingerprint():
                raise ConfigError(
                    f"--resume: {self.dir} holds a different campaign (scenario, methods, runs, "
                    "sweep or seed differ); choose another --out"
                )
        else:
            self.dir.mkdir(parents=True, exist_ok=True)
            atomic_write_json(
                manifest,
                {
                    "fingerprint": spec.fingerprint(),
                    "spec": spec.to_dict(),
                    "provenance": provenance,
                },
            )
        self._repair_tail()

    def _repair_tail(self) -> None:
        path = self.results_path
        if not path.exists():
            return
        data = path.read_bytes()
        if data and not data.endswith(b"\n"):
            cut = data.rfind(b"\n") + 1  # drop a torn last line
            with open(path, "r+b") as fh:
                fh.truncate(cut)

    def load(self) -> list[dict[str, Any]]:
        """Every complete record in the results table."""
        if not self.results_path.exists():
            return []
        records = []
        for line in self.results_path.read_text().splitlines():
            if line.strip():
                try:
                    records.append(json.loads(line))
                except json.JSONDecodeError:
                    continue
        return records

    def done_ids(self) -> set[str]:
        return {r["run_id"] for r in self.load()}

    def append(self, record: dict[str, Any]) -> None:
        """Append one record durably (flush and fsync)."""
        line = json.dumps(to_jsonable(record), allow_nan=False) + "\n"
        with open(self.results_path, "a", encoding="utf-8") as fh:
            fh.write(line)
            fh.flush()
            os.fsync(fh.fileno())

    def export_csv(self) -> Path:
        """Write ``results.csv`` (flattened records) atomically."""
        rows = [flatten(r) for r in self.load()]
        columns: list[str] = []
        for row in rows:
            columns.extend(k for k in row if k not in columns)
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
        return atomic_write_text(self.dir / "results.csv", buf.getvalue())
