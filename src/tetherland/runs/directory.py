"""Run directories: what a run writes, and reading it back to re-judge it.

A run directory holds ``log.npz`` (every control tick), ``run.json`` (the
:class:`~tetherland.verdict.RunRecord`), ``summary.json`` (the verdict, plus the list of
files) and the method's plans as CSV; the tethered method adds the figure 6.5 plots and
the 3D path, and ``--video`` an mp4. :func:`rejudge` recomputes the verdict from the log
and the record alone.
"""

from __future__ import annotations

import zipfile
import zlib
from pathlib import Path

from tetherland.io import atomic_write_json, to_jsonable
from tetherland.methods import get_method
from tetherland.runs.closed_loop import RunResult
from tetherland.sim import SimLog
from tetherland.verdict import RECORD_FILE, RunRecord, RunRecordError, Verdict, judge

LOG_FILE = "log.npz"
SUMMARY_FILE = "summary.json"


def save_run(
    result: RunResult,
    directory: str | Path,
    *,
    video: bool = False,
    listed_as: str | Path | None = None,
) -> dict[str, Path]:
    """Write every file of ``result`` into ``directory`` (which must exist and be writable).

    Returns the written files by role; ``summary.json`` lists them too, under
    ``listed_as`` (default ``directory``): the directory they will live in when
    ``directory`` is a staging directory moved there afterwards
    (:class:`tetherland.io.OutputDir`).
    """
    out = Path(directory)
    files: dict[str, Path] = {"summary": out / SUMMARY_FILE, "record": out / RECORD_FILE}
    result.record.save(out)
    if result.log is not None:
        files["log"] = result.log.save(out / LOG_FILE)
        for name, trajectory in get_method(result.method).trajectories(result.plan).items():
            files[name] = trajectory.save_csv(out / f"{name}.csv")
        if result.method == "tethered":
            from tetherland.report import save_figures

            files["figure_6_5"], files["path_3d"] = save_figures(result, out)
        if video:
            from tetherland.sim.render import render_log

            files["video"] = render_log(
                result.log, out / "mission.mp4", scenario=result.plant_scenario
            ).path
    write_summary(result.summary, files, listed_as if listed_as is not None else out)
    return files


def write_summary(summary: dict, files: dict[str, Path], listed_as: str | Path) -> Path:
    """Write ``summary.json`` (``files["summary"]``) listing ``files`` under ``listed_as``."""
    where = Path(listed_as)
    listed = {k: str(where / Path(v).name) for k, v in files.items()}
    return atomic_write_json(files["summary"], {**summary, "files": listed})


def load_run(directory: str | Path) -> tuple[SimLog, RunRecord]:
    """The log and the record of a run directory.

    Raises
    ------
    RunRecordError
        One line when the directory holds no run, or a run written before run records.
    """
    path = Path(directory)
    if not path.is_dir():
        raise RunRecordError(f"{directory}: not a run directory")
    record = RunRecord.load(path)
    log_path = path / LOG_FILE
    if not log_path.is_file():
        raise RunRecordError(f"{directory}: no {LOG_FILE} (the run was not flown)")
    try:
        log = SimLog.load(log_path)
    except (OSError, ValueError, KeyError, IndexError, TypeError, EOFError,
            zipfile.BadZipFile, zlib.error) as err:  # fmt: skip
        # a truncated or empty file, or a zip that is no log: np.load raises each of these
        why = str(err) or type(err).__name__
        raise RunRecordError(f"{log_path}: unreadable log ({why})") from None
    return log, record


def rejudge(directory: str | Path) -> Verdict:
    """Recompute the verdict of a saved run from its log and record alone."""
    log, record = load_run(directory)
    return judge(log, record)


def jsonable_summary(verdict: Verdict) -> dict:
    """The verdict exactly as ``summary.json`` stores it (without the file list)."""
    return to_jsonable(verdict.to_dict())
