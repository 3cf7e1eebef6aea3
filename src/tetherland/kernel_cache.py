"""Where numba keeps the compiled kernels: a directory named by the kernels' sources.

numba's on-disk cache of a function is invalidated only by the timestamp of the function's
own source file. A kernel that calls another compiled function carries that callee's
code compiled into it, so after an edit of the callee alone (say the mixer's
``mix_into``) its callers (the free-flight law, the tracker) would load their stale
machine code from the cache and run the old callee, silently.

:func:`configure` (called when :mod:`tetherland` is imported, before numba is) points
``NUMBA_CACHE_DIR`` at a directory named by a hash of every module of the package that
mentions numba (:func:`kernel_source_hash`): any edit of any kernel source starts a fresh
cache, and the caches of other sources stay untouched beside it (another checkout, a
campaign still running on an earlier commit). The directory is ``__pycache__/numba-<hash>``
inside the package when it can be written, else ``$XDG_CACHE_HOME/tetherland/numba-<hash>``
(``~/.cache`` by default). A ``NUMBA_CACHE_DIR`` set by the user is kept.
"""

from __future__ import annotations

import hashlib
import os
import sys
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

PACKAGE_ROOT = Path(__file__).resolve().parent
"""The directory of the :mod:`tetherland` package."""

HASH_LENGTH = 16
"""Hex digits of the source hash in the cache directory's name."""


def kernel_source_hash(root: Path = PACKAGE_ROOT) -> str:
    """Hash of every ``*.py`` under ``root`` whose text mentions numba (path and bytes,
    in path order), and of numba's version (its cache format) [hex]."""
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        text = path.read_bytes()
        if b"numba" in text:
            digest.update(path.relative_to(root).as_posix().encode())
            digest.update(b"\0")
            digest.update(text)
            digest.update(b"\0")
    try:
        digest.update(version("numba").encode())
    except PackageNotFoundError:  # pragma: no cover - numba is a dependency
        pass
    return digest.hexdigest()[:HASH_LENGTH]


def cache_dir(root: Path = PACKAGE_ROOT) -> Path:
    """The cache directory for the kernels under ``root`` (see the module doc)."""
    name = f"numba-{kernel_source_hash(root)}"
    local = root / "__pycache__"
    if os.access(local if local.exists() else root, os.W_OK):
        return local / name
    user = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return user / "tetherland" / name


def configure() -> str | None:
    """Set ``NUMBA_CACHE_DIR`` to :func:`cache_dir` unless the user set it or numba is
    already imported (it reads the variable once, at its import); the directory set, or
    None when left alone."""
    if os.environ.get("NUMBA_CACHE_DIR") or "numba" in sys.modules:
        return None
    path = str(cache_dir())
    os.environ["NUMBA_CACHE_DIR"] = path
    return path
