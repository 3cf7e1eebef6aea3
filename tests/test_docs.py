"""The repository stands alone: references to the theory note land on existing sections,
and nothing points at notes outside the repository."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
THEORY = ROOT / "docs" / "theory.md"

REFERENCE = re.compile(
    r"theory\.md[`)\]]*\s+\(?sections?\s+"
    r"(?P<list>\d+(?:\.\d+)?(?:\s*(?:,|-|and|,\s*and)\s*\d+(?:\.\d+)?)*)"
)
"""A reference to the note: '<note> section 5', '<note> sections 3, 4, 12', '... sections 8,
9 and 12', '... sections 4-5', '... section 6.7', also across a line break and after a
Markdown link to the note."""

# Assembled at run time from pieces so that neither this file nor its bytecode contains
# what it forbids (the compiler folds "a" + "b" into one constant; a join it leaves alone).
OUTSIDE = tuple(
    "".join(parts) for parts in (("DESIGN", ".md"), ("shared", "/seed"), ("../", "shared"))
)
"""Paths of notes that are not part of the repository."""

REFERENCE_ROOTS = ("src", "tests", "benchmarks", "README.md")
STANDALONE_ROOTS = ("README.md", "docs", "src", "tests", "examples")
SKIP_PARTS = ("__pycache__", ".egg-info")


def _files(roots: tuple[str, ...]) -> list[Path]:
    files: list[Path] = []
    for name in roots:
        path = ROOT / name
        if path.is_file():
            files.append(path)
        elif path.is_dir():
            files.extend(p for p in sorted(path.rglob("*")) if p.is_file())
    return [p for p in files if not any(part in str(p) for part in SKIP_PARTS)]


def _text(path: Path) -> str | None:
    try:
        return path.read_text(encoding="utf-8")
    except UnicodeDecodeError:  # binary (a figure): it cannot hold a reference
        return None


def _sections(text: str) -> set[str]:
    """Section numbers of the note: '## N. Title' and '### N.M Title' headings."""
    numbers = set(re.findall(r"^## (\d+)\. ", text, flags=re.M))
    numbers |= set(re.findall(r"^### (\d+\.\d+) ", text, flags=re.M))
    return numbers


def _numbers(listing: str) -> list[str]:
    """'3, 4, 12' -> ['3', '4', '12']; '4-5' -> ['4', '5'] (a range of top-level sections)."""
    out: list[str] = []
    for part in re.split(r"\s*(?:,\s*and|,|and)\s*", listing.strip()):
        bounds = [b.strip() for b in part.split("-")]
        if len(bounds) == 2 and all(b.isdigit() for b in bounds):
            out += [str(n) for n in range(int(bounds[0]), int(bounds[1]) + 1)]
        else:
            out += [b for b in bounds if b]
    return out


def _references() -> list[tuple[str, int, str]]:
    refs = []
    for path in _files(REFERENCE_ROOTS):
        text = _text(path)
        if text is None:
            continue
        for match in REFERENCE.finditer(text):
            line = text.count("\n", 0, match.start()) + 1
            for number in _numbers(match.group("list")):
                refs.append((str(path.relative_to(ROOT)), line, number))
    return refs


def test_reference_parser_reads_every_form():
    note = "docs/theory" + ".md"  # split: this file's own text is scanned for references
    text = (
        f"see {note} section 5 and [`{note}`]({note}) section 2; ({note} sections 3, 4, 12)"
        f" {note} sections 8, 9 and 12, {note}\n  sections 4-5, {note} section 6.7,"
        f" [`{note}`]({note}) (section 10 for the mission); {note} section 3, chapter 6.2"
    )
    found = [_numbers(m.group("list")) for m in REFERENCE.finditer(text)]
    assert found == [
        ["5"],
        ["2"],
        ["3", "4", "12"],
        ["8", "9", "12"],
        ["4", "5"],
        ["6.7"],
        ["10"],
        ["3"],
    ]


def test_theory_note_exists_with_numbered_sections():
    sections = _sections(THEORY.read_text(encoding="utf-8"))
    assert {"2", "3", "4", "5", "6", "7", "8", "9", "10", "13"} <= sections


def test_references_exist():
    refs = _references()
    assert len(refs) >= 30, "the reference pattern no longer finds the code's references"


@pytest.mark.parametrize(
    ("where", "line", "number"), _references(), ids=lambda v: str(v).replace("/", ".")
)
def test_every_theory_reference_names_an_existing_section(where: str, line: int, number: str):
    sections = _sections(THEORY.read_text(encoding="utf-8"))
    assert number in sections, f"{where}:{line} cites docs/theory.md section {number}, not in it"


def test_nothing_points_outside_the_repository():
    offenders = []
    for path in _files(STANDALONE_ROOTS):
        text = _text(path)
        if text is None:
            continue
        for needle in OUTSIDE:
            for match in re.finditer(re.escape(needle), text):
                line = text.count("\n", 0, match.start()) + 1
                offenders.append(f"{path.relative_to(ROOT)}:{line}: {needle}")
    assert not offenders, "references outside the repository:\n" + "\n".join(offenders)
