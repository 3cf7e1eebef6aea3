"""The campaign directory: manifest, append-only results table, resume, one writer.

``results.jsonl`` gets one line per finished run, written and fsync'ed by the main
process as soon as the run ends, so a crash or Ctrl-C loses nothing; a torn last line is
discarded on reopening. ``results.csv`` is a flattened copy written atomically at the
end (and by ``--resume``). ``runs/`` holds the run directories the campaign keeps
(``--keep``: the failed runs by default), each written by its worker all at once (staged
next to it, then renamed), so a run directory is whole or absent; the staging of a worker
killed while writing is removed when the directory is opened again. One process at a
time writes a campaign directory: it holds an exclusive lock on ``.lock`` there while it
is open. A run recorded as an infrastructure error (its worker or the engine was lost:
:func:`retryable`) is run again by ``--resume``; a run's own failure or error never is.
"""

from __future__ import annotations

import csv
import io
import json
import os
import shutil
from pathlib import Path
from typing import Any

try:
    import fcntl
except ImportError:  # pragma: no cover - not POSIX: no lock
    fcntl = None  # type: ignore[assignment]

from tetherland.campaign.spec import CampaignSpec
from tetherland.errors import ConfigError
from tetherland.io import atomic_write_json, atomic_write_text, to_jsonable

MANIFEST = "campaign.json"
RESULTS = "results.jsonl"
LOCK = ".lock"
"""Lock file of a campaign directory (holds the writer's process id)."""
RUNS_DIR = "runs"
"""Folder of the kept run directories, ``runs/<run_id>``."""
KEEP_POLICIES = ("failures", "all", "none")
"""Which runs keep their run directory: those that did not succeed, every one, none."""
INFRASTRUCTURE = "infrastructure"
"""``error_kind`` of a run whose worker or engine was lost (not a failure of the run)."""


def retryable(record: dict[str, Any]) -> bool:
    """Was this run lost to the infrastructure (a dead worker, an engine that gave up)?

    Such a run says nothing about the mission: ``--resume`` runs it again. Records of
    earlier versions carry no ``error_kind``; theirs start with ``worker lost``.
    """
    if record.get("status") != "error":
        return False
    kind = record.get("error_kind")
    return kind == INFRASTRUCTURE or (kind is None and str(record.get("error")).startswith(
        "worker lost"))  # fmt: skip


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
        self._lock: Any = None

    def __enter__(self) -> ResultsStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def results_path(self) -> Path:
        return self.dir / RESULTS

    def open(self, spec: CampaignSpec, *, resume: bool, provenance: dict[str, Any]) -> None:
        """Create the directory for ``spec``, or check that it holds the same campaign.

        Takes the directory's lock first (released by :meth:`close` or when the process
        ends); with ``resume``, drops the records of runs lost to the infrastructure so
        that they run again.

        Raises
        ------
        ConfigError
            Another process holds the directory, it holds another campaign, or it holds
            this one and ``resume`` is not set.
        """
        self.dir.mkdir(parents=True, exist_ok=True)
        self._acquire()
        manifest = self.dir / MANIFEST
        if manifest.exists():
            try:
                old = json.loads(manifest.read_text())
            except (OSError, ValueError) as err:
                raise ConfigError(f"{manifest}: unreadable campaign manifest ({err})") from None
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
            atomic_write_json(
                manifest,
                {
                    "fingerprint": spec.fingerprint(),
                    "spec": spec.to_dict(),
                    "provenance": provenance,
                },
            )
        self._repair_tail()
        self._remove_staging()
        if resume:
            self._drop_retryable()

    def lock(self) -> None:
        """Take the directory's lock without opening the campaign (a reader that writes
        the campaign's figures); :class:`ConfigError` when another process holds it."""
        self._acquire()

    def _acquire(self) -> None:
        if fcntl is None or self._lock is not None:
            return
        fh = open(self.dir / LOCK, "a+", encoding="utf-8")  # held while open
        try:
            fcntl.flock(fh.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            fh.seek(0)
            holder = fh.read().strip() or "?"
            fh.close()
            raise ConfigError(
                f"--out {self.dir}: another process (pid {holder}) is running this campaign; "
                "wait for it to end, or choose another --out"
            ) from None
        fh.seek(0)
        fh.truncate()
        fh.write(f"{os.getpid()}\n")
        fh.flush()
        self._lock = fh

    def close(self) -> None:
        """Release the directory's lock (the results stay readable by anyone)."""
        if self._lock is not None:
            self._lock.close()  # closing the file releases the flock
            self._lock = None

    def _drop_retryable(self) -> None:
        """Rewrite the results table without the runs lost to the infrastructure."""
        records = self.load()
        kept = [r for r in records if not retryable(r)]
        if len(kept) < len(records):
            text = "".join(json.dumps(to_jsonable(r), allow_nan=False) + "\n" for r in kept)
            atomic_write_text(self.results_path, text)

    @property
    def runs_dir(self) -> Path:
        """Where the kept run directories are (``runs/<run_id>``)."""
        return self.dir / RUNS_DIR

    def _remove_staging(self) -> None:
        """Remove the half-written run directories of workers killed while writing (the
        lock is held: no worker of this campaign writes now)."""
        if not self.runs_dir.is_dir():
            return
        for stale in self.runs_dir.glob(".*"):
            if ".staging-" in stale.name or ".old-" in stale.name:
                shutil.rmtree(stale, ignore_errors=True)

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
        """Runs that need no (further) attempt: every record but the retryable ones."""
        return {r["run_id"] for r in self.load() if not retryable(r)}

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
