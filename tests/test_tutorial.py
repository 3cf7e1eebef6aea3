"""docs/tutorial.md runs as written: its files are written and its shell blocks run in order,
in an empty directory, and what its prose promises holds (the hover ratio and the binding
limit it quotes, the design it writes, a successful mission, a campaign report and an
exact replay).

Campaigns run with fewer runs than the tutorial shows: ``--runs N`` becomes ``--runs``
``$TETHERLAND_TUTORIAL_RUNS`` (default 1), so that the whole tutorial takes about a minute.
"""

from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from tetherland.config import load_scenario

ROOT = Path(__file__).resolve().parents[1]
TUTORIAL = ROOT / "docs" / "tutorial.md"
RUNS = int(os.environ.get("TETHERLAND_TUTORIAL_RUNS", "1"))

FENCE = re.compile(r"^```(?P<info>[^\n`]*)\n(?P<body>.*?)^```[ \t]*$", re.M | re.S)


@dataclass(frozen=True)
class Block:
    """One fenced block of the tutorial: ``bash`` (run), ``toml file=NAME`` (written)."""

    lang: str
    file: str | None
    body: str


def blocks(text: str) -> list[Block]:
    """The fenced blocks of a Markdown text, in order."""
    out = []
    for m in FENCE.finditer(text):
        words = m.group("info").split()
        lang = words[0] if words else ""
        attrs = dict(w.split("=", 1) for w in words[1:] if "=" in w)
        out.append(Block(lang, attrs.get("file"), m.group("body")))
    return out


def reduced(script: str, runs: int) -> str:
    """The script with every ``--runs N`` and ``--verify N`` given ``runs`` instead."""
    return re.sub(r"--(runs|verify)\s+\d+", rf"--\g<1> {runs}", script)


def tetherland_commands(script: str) -> list[str]:
    """The subcommands of the ``tetherland`` calls of a script (``campaign report`` as one)."""
    found = re.findall(r"^\s*tetherland\s+([a-z-]+)(?:\s+(report|run)\b)?", script, re.M)
    return [" ".join(p for p in parts if p) for parts in found]


def test_blocks_and_reduction_parse_what_the_tutorial_uses():
    text = (
        "a\n```toml file=x.toml\nk = 1\n```\n```bash\ntetherland campaign x --runs 20 \\\n"
        "    --seed 1\ntetherland campaign report out\n```\n```text\nno\n```\n"
    )
    got = blocks(text)
    assert [(b.lang, b.file) for b in got] == [("toml", "x.toml"), ("bash", None), ("text", None)]
    assert got[0].body == "k = 1\n"
    assert "--runs 3 " in reduced(got[1].body, 3) and "--runs 20" not in reduced(got[1].body, 3)
    assert tetherland_commands(got[1].body) == ["campaign", "campaign report"]


def test_the_tutorial_walks_from_a_vehicle_file_to_a_campaign_report():
    """The steps the tutorial promises are all there, in order, with files it writes."""
    bl = blocks(TUTORIAL.read_text(encoding="utf-8"))
    assert [b.file for b in bl if b.file] == ["my_robot.toml"]
    commands = [c for b in bl if b.lang == "bash" for c in tetherland_commands(b.body)]
    for step in (
        "show",
        "analyze",
        "design",
        "mission",
        "judge",
        "campaign",
        "campaign report",
        "replay",
    ):
        assert step in commands, step
    order = [
        commands.index(s)
        for s in ("analyze", "design", "mission", "campaign", "campaign report", "replay")
    ]
    assert order == sorted(order)


@pytest.mark.slow
def test_the_tutorial_runs_as_written(tmp_path: Path):
    bl = blocks(TUTORIAL.read_text(encoding="utf-8"))
    env = dict(os.environ, MPLBACKEND="Agg", MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["COLUMNS"] = "200"  # one table row per line, so that the output can be searched
    output = []
    for block in bl:
        if block.file:
            (tmp_path / block.file).write_text(block.body, encoding="utf-8")
        elif block.lang == "bash":
            script = reduced(block.body, RUNS)
            done = subprocess.run(
                ["bash", "-euo", "pipefail", "-c", script],
                cwd=tmp_path,
                env=env,
                capture_output=True,
                text=True,
                timeout=900,
            )
            assert done.returncode == 0, f"{script}\n{done.stdout[-3000:]}{done.stderr[-3000:]}"
            output.append(done.stdout)
    said = "\n".join(output)

    # Step 2: the prose quotes the hover ratio 4 f_max / (m g) and the binding limit.
    mine = load_scenario(str(tmp_path / "my_robot.toml"))
    ratio = 4 * mine.vehicle.f_max / (mine.vehicle.mass * 9.81)
    assert f"{ratio:.2f}" == "2.33" and "2.33" in said
    assert "friction_motors_off" in said

    # Step 3: the two best designs flown RUNS times each, ranked by the interval's lower
    # bound (then by margins); my_design.toml is my_robot.toml with the first applied.
    designs = json.loads((tmp_path / "design.json").read_text())["designs"]
    flown = [d["verified"] for d in designs if d.get("verified")]
    assert len(flown) == min(2, len(designs)) and all(v["runs"] == RUNS for v in flown)
    assert designs[0].get("verified") and designs[0]["verified"]["ci_low"] == max(
        v["ci_low"] for v in flown
    )
    best = designs[0]["overrides"]
    design = load_scenario(str(tmp_path / "my_design.toml"))
    length = float(next(o for o in best if o.startswith("tether.length=")).split("=")[1])
    assert math.isclose(design.tether.length, length)
    assert design.vehicle.mass == mine.vehicle.mass == 1.4

    # Step 4: the mission succeeded; the perturbed one records its draw.
    summary = json.loads((tmp_path / "out/my_design/mission/summary.json").read_text())
    assert summary["outcome"] == "success"
    record = json.loads((tmp_path / "out/my_design/perturbed/run.json").read_text())
    assert record["provenance"]["perturbation"]

    # Steps 5-7: RUNS runs, all kept, the report read them, the replay was exact (exit 0).
    campaign = tmp_path / "out/my_design/campaign"
    rows = [json.loads(line) for line in (campaign / "results.jsonl").read_text().splitlines()]
    assert sorted(r["run_id"] for r in rows) == [f"tethered-base-{i:05d}" for i in range(RUNS)]
    assert len(list((campaign / "runs").iterdir())) == RUNS
    assert f"{RUNS} of {RUNS} runs finished" in said
    assert (tmp_path / "out/my_design/replay/summary.json").is_file()
