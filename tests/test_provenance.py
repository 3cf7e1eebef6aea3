"""What a result records about the code that computed it: the commit, and whether the
checkout's tracked files differed from it."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from tetherland.provenance import checkout_commit

pytestmark = pytest.mark.skipif(shutil.which("git") is None, reason="needs git")


def _git(repo: Path, *args: str) -> str:
    out = subprocess.run(
        ["git", "-c", "user.name=t", "-c", "user.email=t@t", *args],
        cwd=repo, capture_output=True, text=True, check=True,
    )  # fmt: skip
    return out.stdout.strip()


def test_a_changed_tracked_file_marks_the_commit_dirty(tmp_path: Path) -> None:
    """A clean checkout records its commit (the 7-character short hash, even with a tag on
    it); a tracked file changed, in the work tree or only staged, appends ``-dirty``; an
    untracked file does not; outside a checkout there is no commit."""
    repo = tmp_path / "repo"
    (repo / "src").mkdir(parents=True)
    _git(repo, "init", "-q")
    (repo / "src" / "law.py").write_text("GAIN = 1.0\n")
    _git(repo, "add", ".")
    _git(repo, "commit", "-q", "-m", "first")
    _git(repo, "tag", "v0.1.0")
    head = _git(repo, "rev-parse", "HEAD")
    assert checkout_commit(repo / "src") == head[:7]
    (repo / "notes.txt").write_text("untracked\n")
    assert checkout_commit(repo / "src") == head[:7]
    (repo / "src" / "law.py").write_text("GAIN = 2.0\n")
    assert checkout_commit(repo / "src") == head[:7] + "-dirty"
    _git(repo, "add", "src/law.py")  # staged only: still not the commit
    assert checkout_commit(repo / "src") == head[:7] + "-dirty"
    _git(repo, "commit", "-q", "-m", "second")
    assert checkout_commit(repo) == _git(repo, "rev-parse", "--short=7", "HEAD")
    outside = tmp_path / "plain"
    outside.mkdir()
    assert checkout_commit(outside) is None
