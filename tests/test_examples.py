"""Every script in examples/ runs headless and its own assertions hold."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("*.py"))
EXPECT = {
    "01_scenario_and_analysis.py": "binding: offset_torque",
    "02_plan.py": "SOLVED",
    "03_own_controller.py": "success {'1': True, '2': True, '3': True, '4': True, '5': True}",
    "04_judge_and_export.py": "MCAP:",
    "05_gym_expert.py": "landed",
}


def test_every_example_is_listed():
    assert [p.name for p in EXAMPLES] == sorted(EXPECT)


@pytest.mark.slow
@pytest.mark.parametrize("script", EXAMPLES, ids=lambda p: p.name)
def test_example_runs(script: Path, tmp_path: Path):
    env = {**os.environ, "MPLBACKEND": "Agg", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    out = subprocess.run(
        [sys.executable, str(script), str(tmp_path / "out")], capture_output=True, text=True,
        env=env, timeout=900, cwd=tmp_path,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr[-2000:]
    assert EXPECT[script.name] in out.stdout
