"""The warm-up compiles every kernel specialisation the closed loop uses.

``make test`` runs ``python -m tetherland.warmup --jobs 2`` before the test workers start,
so that they (and the campaign workers they spawn) load the compiled kernels instead of
all compiling them at once. That only helps if the warm-up leaves nothing for a mission
to compile: here a fresh process runs the warm-up, notes the signatures of every numba
kernel of tetherland, flies the whole default mission (every phase, both controllers'
wrappers as a mission composes them) and a contact-free perching run (its tracker and
maneuver reference), and compares.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from tetherland import warmup

SCRIPT = """
import json, sys
from numba.core.registry import CPUDispatcher

def signatures():
    out = {}
    for name, module in list(sys.modules.items()):
        if name.split(".")[0] != "tetherland":
            continue
        for obj in list(vars(module).values()):
            if isinstance(obj, CPUDispatcher):
                key = obj.py_func.__module__ + "." + obj.py_func.__qualname__
                out[key] = sorted(map(str, obj.signatures))
    return out

from tetherland.config import load_scenario
from tetherland.runs import run_mission
from tetherland.warmup import warm_up

warm_up()
warmed = signatures()
result = run_mission(load_scenario("slope50"))
perched = run_mission(load_scenario("slope50", ["surface.slope_deg=20"]), method="free-flight")
flown = signatures()
print(json.dumps({
    "success": bool(result.summary["success"]),
    "perched": perched.log is not None and len(perched.log) > 0,
    "warmed": len([k for k, v in warmed.items() if v]),
    "flown": len([k for k, v in flown.items() if v]),
    "new": {k: sorted(set(v) - set(warmed.get(k, []))) for k, v in flown.items()
            if set(v) - set(warmed.get(k, []))},
}))
"""


@pytest.mark.slow
def test_a_whole_mission_after_the_warm_up_compiles_nothing_more():
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, check=True,
        env={**os.environ, "MPLBACKEND": "Agg"},
    )  # fmt: skip
    got = json.loads(done.stdout.strip().splitlines()[-1])
    assert got["success"] and got["perched"]
    # The flight ran compiled kernels (so "nothing new" is not vacuous), and each of them
    # was already there after the warm-up. (How many dispatchers show signatures depends
    # on the on-disk cache: a kernel loaded from it carries the kernels it calls inside
    # its machine code, so those callees never get a signature of their own.)
    assert got["flown"] > 0
    assert got["warmed"] == got["flown"]
    assert got["new"] == {}, got["new"]


def test_jobs_below_one_is_refused_in_one_line(capsys):
    with pytest.raises(SystemExit) as err:
        warmup.main(["--jobs", "0"])
    assert err.value.code == 2
    assert "--jobs = 0: must be at least 1" in capsys.readouterr().err
