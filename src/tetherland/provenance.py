"""What every output records: the version, the scenario, the parameters and the seed."""

from __future__ import annotations

import functools
import platform
import subprocess
import sys
from datetime import UTC, datetime
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import TYPE_CHECKING, Any

from tetherland import __version__

if TYPE_CHECKING:
    from tetherland.config import Scenario

_LIBRARIES = ("numpy", "scipy", "casadi", "mujoco", "pydantic")


@functools.cache
def _git_commit() -> str | None:
    """The commit of this checkout, asked once per process (``git`` is a subprocess: a
    campaign worker would otherwise pay it for every run); see :func:`checkout_commit`."""
    return checkout_commit(Path(__file__).resolve().parent)


def checkout_commit(directory: Path) -> str | None:
    """The short commit of the git checkout holding ``directory``, with ``-dirty`` appended
    when a tracked file differs from it (untracked files do not count), or None outside a
    checkout or without git: a result computed from changed sources does not claim a
    commit that did not compute it. One ``git describe`` call, without optional locks (a
    campaign's workers must not contend for the index with the user's own git)."""
    try:
        out = subprocess.run(
            ["git", "--no-optional-locks", "describe", "--always", "--dirty", "--abbrev=7",
             "--exclude=*"],
            cwd=directory,
            capture_output=True,
            text=True,
            timeout=5,
            check=False,
        )  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None if out.returncode == 0 else None


def library_versions() -> dict[str, str]:
    """Versions of the numerical libraries the results depend on."""
    return dict(_library_versions())


@functools.cache
def _library_versions() -> dict[str, str]:
    """Read once per process: the libraries a process has imported do not change under
    it (a package installed meanwhile is not the one that computed its results)."""
    versions = {}
    for name in _LIBRARIES:
        try:
            versions[name] = version(name)
        except PackageNotFoundError:
            versions[name] = "not installed"
    return versions


def provenance(
    scenario: Scenario | None = None,
    *,
    seed: int | None = None,
    command: list[str] | None = None,
    extra: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Return a JSON-ready record of how a result was produced.

    Parameters
    ----------
    scenario
        The resolved scenario (after overrides); stored in full.
    seed
        The random seed of the run, if any.
    command
        The command line, defaults to ``sys.argv``.
    extra
        Further parameters worth recording (solver, method, ...).
    """
    record: dict[str, Any] = {
        "tetherland_version": __version__,
        "git_commit": _git_commit(),
        "created_utc": datetime.now(UTC).isoformat(timespec="seconds"),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "libraries": library_versions(),
        "command": list(sys.argv if command is None else command),
        "seed": seed,
    }
    if scenario is not None:
        record["scenario_name"] = scenario.name
        record["scenario"] = scenario.model_dump(mode="json")
    if extra:
        record.update(extra)
    return record
