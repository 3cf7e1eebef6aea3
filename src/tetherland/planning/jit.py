"""Compiling CasADi functions to C with the system compiler (``jit``), leaving no files.

CasADi's just-in-time compilation writes the generated C to the working directory and
compiles it in ``jit_options["directory"]``; :func:`compiled` does both in a temporary
directory, removed once the shared library is loaded. The speed-up is in evaluating the
functions (2-3x for the OCP's Hessian and Jacobian, see ``bench_planner.py``); the cost
is the one-off compilation (about 20 s for the landing NLP at N = 50 with ``-O1``).
"""

from __future__ import annotations

import contextlib
import functools
import os
import shutil
import tempfile
from collections.abc import Callable
from typing import Any

import casadi as ca

COMPILER = "gcc"
FLAGS = ("-O1",)
"""C compiler and flags (-O1: about 3x the speed of -O0, half the compile time of -O2)."""


@functools.cache
def available() -> bool:
    """Whether the C compiler is installed."""
    return shutil.which(COMPILER) is not None


def options() -> dict[str, Any]:
    """CasADi function options that compile it to C (files handled by :func:`compiled`)."""
    return {
        "jit": True,
        "compiler": "shell",
        "jit_name": "tetherland_jit",
        "jit_cleanup": False,  # the temporary directory goes as a whole
        "jit_options": {
            "compiler": COMPILER,
            "flags": list(FLAGS),
            "verbose": False,
            "cleanup": False,
        },
    }


def compiled(build: Callable[[dict[str, Any]], ca.Function]) -> ca.Function:
    """``build(opts)`` with the compile options merged in by the caller, run in a
    temporary directory that is removed afterwards (the library stays loaded)."""
    if not available():
        raise RuntimeError(f"jit needs the C compiler '{COMPILER}', which is not installed")
    opts = options()
    with tempfile.TemporaryDirectory(prefix="tetherland_jit_") as tmp:
        opts["jit_options"]["directory"] = tmp + os.sep
        with contextlib.chdir(tmp):
            return build(opts)
