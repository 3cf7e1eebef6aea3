"""Atomic file output: results are written to a temporary file and renamed into place.

A crash or Ctrl-C therefore never leaves a half-written result on disk.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from tetherland.errors import ConfigError


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; rename it onto ``path`` on success.

    The temporary file keeps the target's suffix so that writers which infer the format
    from the file name (matplotlib, imageio) work. On error the temporary file is removed
    and ``path`` is left untouched.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp_name = tempfile.mkstemp(
        prefix=f".{target.stem}.", suffix=f".tmp{target.suffix}", dir=target.parent
    )
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        if tmp.exists():
            os.chmod(tmp, 0o666 & ~_umask())  # mkstemp makes 0600; give what open() would
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def atomic_write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically and return the path."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def atomic_write_with(path: str | os.PathLike[str], writer: Callable[[Path], Any]) -> Path:
    """Call ``writer(tmp_path)`` and rename the result onto ``path`` atomically."""
    with atomic_path(path) as tmp:
        writer(tmp)
    return Path(path)


def to_jsonable(obj: Any) -> Any:
    """Convert numpy scalars/arrays, tuples, paths and enums to JSON-compatible values.

    Non-finite floats become ``None`` (JSON has no NaN or infinity).
    """
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (np.bool_, bool)):
        return bool(obj)
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        value = float(obj)
        return value if np.isfinite(value) else None
    if isinstance(obj, Path):
        return str(obj)
    if hasattr(obj, "value") and hasattr(obj, "name") and type(obj).__module__ != "builtins":
        return to_jsonable(obj.value)  # enums
    return obj


def dumps_json(obj: Any) -> str:
    """Serialise ``obj`` with :func:`to_jsonable`, indented, with a trailing newline."""
    return json.dumps(to_jsonable(obj), indent=2, allow_nan=False) + "\n"


def atomic_write_json(path: str | os.PathLike[str], obj: Any) -> Path:
    """Write ``obj`` as JSON to ``path`` atomically."""
    return atomic_write_text(path, dumps_json(obj))


def prepare_output_dir(directory: str | Path, option: str = "--out") -> Path:
    """Create ``directory`` and check it is writable, before any work is done.

    Raises
    ------
    ConfigError
        One line naming ``option`` when the directory cannot be created or written.
    """
    path = Path(directory)
    try:
        path.mkdir(parents=True, exist_ok=True)
        fd, probe = tempfile.mkstemp(prefix=".write-test-", dir=path)
        os.close(fd)
        os.unlink(probe)
    except OSError as err:
        raise ConfigError(
            f"{option}: cannot write the output directory '{directory}' ({err.strerror or err})"
        ) from None
    return path


OUTPUT_MARKERS = ("summary.json", "run.json", "plan.json", "design.json")
"""Files by which a directory is known as the output of a tetherland command (a run, a
plan or a design): ``--overwrite`` replaces only such a directory (or an empty one)."""
_AT_FDCWD = -100
_RENAME_EXCHANGE = 2


def _exchange(a: Path, b: Path) -> bool:
    """Swap two paths in one atomic step (Linux ``renameat2(RENAME_EXCHANGE)``).

    Returns False where the system or the file system does not support it.
    """
    import ctypes
    import errno

    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except (OSError, AttributeError):
        return False
    renameat2.argtypes = [ctypes.c_int, ctypes.c_char_p, ctypes.c_int, ctypes.c_char_p,
                          ctypes.c_uint]  # fmt: skip
    renameat2.restype = ctypes.c_int
    if renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE) == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):
        return False
    raise OSError(code, os.strerror(code), str(b))


def _unwritable(directory: Path) -> str | None:
    """Why no file can be created in ``directory`` (None: it can)."""
    try:
        fd, probe = tempfile.mkstemp(prefix=".write-test-", dir=directory)
    except OSError as err:
        return err.strerror or str(err)
    os.close(fd)
    os.unlink(probe)
    return None


class OutputDir:
    """The output directory of one command, written whole or not at all.

    Checked when created (before any work): ``target`` must be absent, an empty
    directory, or, with ``overwrite``, the output of an earlier tetherland command
    (:data:`OUTPUT_MARKERS`), which is then replaced as a whole. :meth:`staging` yields a
    fresh directory next to ``target`` to write into and moves it onto ``target`` only
    when the block succeeds, so no file of an earlier run survives next to the new
    ones, and an error or Ctrl-C leaves ``target`` as it was.

    Raises
    ------
    ConfigError
        One line naming ``option`` when ``target`` holds other output and ``overwrite``
        is not given, holds something that is not a tetherland output, or cannot be
        written.
    """

    def __init__(self, target: str | Path, *, overwrite: bool = False, option: str = "--out"):
        self.path = Path(target)
        self.option = option
        # a symbolic link to a folder: the folder is replaced, the link stays
        path = self._dir = Path(os.path.realpath(target)) if self.path.is_symlink() else self.path
        if path.exists() and not path.is_dir():
            raise ConfigError(f"{option} '{target}' is a file, expected a directory")
        try:
            contents = sorted(p.name for p in path.iterdir()) if path.is_dir() else []
        except OSError as err:
            raise ConfigError(f"{option}: cannot read '{target}' ({err.strerror or err})") from None
        if contents:
            marker = next((m for m in OUTPUT_MARKERS if m in contents), None)
            if marker is None:
                raise ConfigError(
                    f"{option} '{target}' is not empty and holds no tetherland output (no "
                    f"{', '.join(OUTPUT_MARKERS)}); choose another directory"
                )
            if not overwrite:
                raise ConfigError(
                    f"{option} '{target}' already holds an output ({marker}); add --overwrite "
                    "to replace it as a whole, or choose another directory"
                )
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise ConfigError(
                f"{option}: cannot create '{path.parent}' ({err.strerror or err})"
            ) from None
        # staged next to the target (one file system: the final move is a rename); an
        # existing empty target in a folder we may not write is filled in place
        why = _unwritable(path.parent)
        self._in_place = why is not None
        if self._in_place and path.is_dir():
            why = _unwritable(path) if not contents else "its folder cannot be written"
        if why is not None:
            raise ConfigError(f"{option}: cannot write the output directory '{target}' ({why})")

    @contextmanager
    def staging(self) -> Iterator[Path]:
        """A directory to write the output into; it becomes ``self.path`` on success."""
        if self._in_place:  # an empty directory: nothing stale to mix with
            try:
                yield self._dir
            except BaseException:
                for child in self._dir.iterdir():
                    _remove(child)
                raise
            return
        tmp = Path(tempfile.mkdtemp(prefix=f".{self._dir.name}.staging-", dir=self._dir.parent))
        try:
            yield tmp
            os.chmod(tmp, 0o777 & ~_umask())  # mkdtemp makes 0700; give what mkdir would
            self._publish(tmp)
        except BaseException:
            _remove(tmp)
            raise

    def _publish(self, tmp: Path) -> None:
        target = self._dir
        if not target.exists() or (target.is_dir() and not any(target.iterdir())):
            os.replace(tmp, target)  # POSIX: a directory may replace an empty one
        elif _exchange(tmp, target):
            _remove(tmp)  # now the replaced output
        else:  # two renames: target is missing for a moment, never mixed
            old = Path(tempfile.mkdtemp(prefix=f".{target.name}.old-", dir=target.parent))
            os.replace(target, old)
            os.replace(tmp, target)
            _remove(old)


def _remove(path: Path) -> None:
    import shutil

    if path.is_dir() and not path.is_symlink():
        shutil.rmtree(path, ignore_errors=True)
    else:
        path.unlink(missing_ok=True)
