"""The generated reference (docs/reference/) is what the code says: every scenario field with
its unit and range in one row, every log column with its unit and shape, and never stale."""

from __future__ import annotations

import re
from pathlib import Path

from tetherland import docs_reference
from tetherland.config import RENAMES, Scenario
from tetherland.config.schema import fields
from tetherland.sim.log import BASE_COLUMNS, DERIVED

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "docs" / "reference"


def test_the_committed_reference_is_the_generated_one():
    assert docs_reference.stale(REFERENCE) == [], (
        "docs/reference is stale: run `python -m tetherland.docs_reference`"
    )


def _rows(text: str) -> dict[str, list[str]]:
    """First cell (a code span) -> the row's cells, for every table row of a page."""
    rows: dict[str, list[str]] = {}
    for line in text.splitlines():
        cells = [c.strip() for c in re.split(r"(?<!\\)\|", line.strip())[1:-1]]
        if cells and cells[0].startswith("`"):
            key = cells[0].strip("`")
            assert key not in rows, f"two rows for {key}"
            rows[key] = cells
    return rows


def test_every_scenario_field_has_one_row_with_its_unit_range_and_default():
    rows = _rows(docs_reference.scenario_reference())
    for f in fields(Scenario):
        _, type_, unit, rng, default, meaning = rows[f.key]
        assert type_.startswith("`"), f.key
        assert unit == (f.unit or ""), f.key
        assert rng == (f.range or ""), f.key
        assert meaning and default.startswith("`"), f.key
    hold = rows["mission.touchdown.hold_rate"]
    assert hold[2:5] == ["rad/s", "[0, 50]", "`0.15`"]
    assert rows["verdict.touchdown_force"][2] == "N"
    for old, new in RENAMES.items():  # the rename table, old name first
        assert rows[old][1] == f"`{new}`"


def test_every_log_column_has_its_unit_and_shape():
    rows = _rows(docs_reference.log_reference())
    for c in BASE_COLUMNS + DERIVED:
        _, shape, unit, kind, meaning = rows[c.name]
        assert shape == ("(n,)" if c.width == 1 else f"(n, {c.width})")
        assert unit == c.unit and kind == ("integer" if c.integer else "float") and meaning
    assert rows["p_W"][1:3] == ["(n, 3)", "m"]


def test_the_generator_writes_the_pages_and_reports_stale_ones(tmp_path: Path, capsys):
    assert docs_reference.main(["--out", str(tmp_path), "--check"]) == 1
    assert "stale" in capsys.readouterr().out
    assert docs_reference.main(["--out", str(tmp_path)]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(docs_reference.PAGES)
    assert docs_reference.main(["--out", str(tmp_path), "--check"]) == 0
    (tmp_path / "log.md").write_text("edited by hand\n")
    assert docs_reference.stale(tmp_path) == ["log.md"]
