"""CasADi functions compiled to C once per machine: generated, compiled with gcc, cached.

CasADi evaluates an SX function in its virtual machine, a few nanoseconds per operation;
the same function generated as C and compiled runs several times faster and gives the
same numbers (the generated code performs the same double operations in the same order,
and ``-O2`` without ``-ffast-math`` keeps them). :func:`library` writes the C source of
some functions, compiles it into a shared library under :func:`cache_dir`, named by a hash
of the source and the flags, and returns its path; a later call with the same functions
finds the file. Used for the fatrop NLP (:mod:`tetherland.planning.stagewise`) and the
flatness map (:mod:`tetherland.models.flatness`).
"""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import subprocess
import tempfile
from collections.abc import Iterable
from pathlib import Path

import casadi as ca

COMPILER = "gcc"
FLAGS = ("-O2", "-fPIC", "-shared")
"""C compiler and flags of the libraries (gcc ``-O2``: about 1.5 s of CPU for the landing
OCP's NLP, any N; 0.25 s for the flatness map)."""
CACHE_ENV = "TETHERLAND_CACHE_DIR"
"""Environment variable naming the cache directory (default: ``~/.cache/tetherland``)."""


@functools.cache
def available() -> bool:
    """Whether the C compiler of :func:`library` is installed."""
    return shutil.which(COMPILER) is not None


def cache_dir() -> Path:
    """Where compiled libraries are kept: ``$TETHERLAND_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/tetherland``, else ``~/.cache/tetherland``."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "tetherland"


def library(functions: Iterable[ca.Function], prefix: str, what: str) -> Path:
    """The shared library of ``functions`` (built once per source and machine), named
    ``<prefix>_<hash>.so`` in :func:`cache_dir`.

    Parameters
    ----------
    functions : iterable of casadi.Function
        The functions to generate (each keeps its name in the library).
    prefix : str
        File name prefix (e.g. ``"nlp"``).
    what : str
        What the functions are, plural, for the error messages (e.g. ``"NLP functions"``).

    Raises
    ------
    RuntimeError
        If the C compiler is missing or fails.
    """
    if not available():
        raise RuntimeError(f"compiled {what} need the C compiler '{COMPILER}'")
    gen = ca.CodeGenerator(f"tetherland_{prefix}.c", {"with_header": False})
    for f in functions:
        gen.add(f)
    source = gen.dump()
    digest = hashlib.sha1((source + " ".join(FLAGS)).encode()).hexdigest()[:20]
    path = cache_dir() / f"{prefix}_{digest}.so"
    if path.exists():
        return path
    path.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(prefix=f"tetherland_{prefix}_", dir=path.parent) as tmp:
        c_file = Path(tmp) / f"{prefix}.c"
        c_file.write_text(source)
        so = Path(tmp) / f"{prefix}.so"
        done = subprocess.run(
            [COMPILER, *FLAGS, str(c_file), "-o", str(so), "-lm"],
            capture_output=True, text=True, check=False,
        )  # fmt: skip
        if done.returncode != 0:
            raise RuntimeError(f"compiling {what} failed: {done.stderr.strip()[:300]}")
        os.replace(so, path)  # atomic: concurrent builders write the same bytes
    return path
