"""Fuzzing the inputs a user types (issue 28): mutated scenario files and odd overrides.

A seeded generator (``TETHERLAND_FUZZ_SEED`` picks another seed, to explore) mutates the
built-in scenarios' TOML in text and in value, and builds overrides from the scenario's
real keys and from nonsense. Every input must end in exit 0 with a valid result or exit 2
with ``error:`` lines of at most 300 characters: no traceback, no hang (an alarm ends any
call that takes too long). The commands run in process through :func:`main`, and a few
through the installed script.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import tomllib
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from tetherland.cli import MESSAGE_CHARS, main
from tetherland.config import Scenario, load_scenario, scenario_to_toml

SEED = int(os.environ.get("TETHERLAND_FUZZ_SEED", "20260528"))
FILES = 240
"""Mutated scenario files per run (at least 200)."""
OVERRIDES = 80
"""Odd overrides per run (at least 50)."""
ANALYSED = 12
"""Valid mutants also run through `analyze` (the physics of odd but valid values)."""
CALL_LIMIT = 20.0
"""A single in-process call taking longer than this counts as a hang [s]."""
EXE = str(Path(sys.executable).with_name("tetherland"))

BASES = ("slope50", "pipe60", "wall90", "flat", "overhang93")
ODD_VALUES = (
    "true", "false", "1", "0", "-1", "1e400", "-1e400", "nan", "inf", "-inf", "5e-324",
    "1e-310", "-0.0", "9223372036854775807", "-9223372036854775808", "0x1F", "1_000",
    '"yes"', '"50"', '""', '"\\u0000"', '"../../etc"', '"/tmp/x"', "[]", "[1, 2]",
    "[true, 0, 0]", "[[1]]", "{}", "{a = 1}", "1979-05-27", "07:32:00",
    "1979-05-27T07:32:00Z", '"' + "x" * 5000 + '"', "[" * 300 + "]" * 300, "'", '"',
    "= 1", "[1,", "{a=", "\x00", "\udcff".encode("utf-8", "surrogatepass").decode("latin-1"),
)  # fmt: skip
JUNK = ("\x00", "\x7f", "\ufeff", "\n[", "]]", "=", '"', "'''", "#", "\t", "é", "\U0001f680")


class Hang(BaseException):
    """Raised by the alarm: a BaseException, so no `except Exception` in the code under
    test can swallow it."""


@contextmanager
def deadline(seconds: float) -> Iterator[None]:
    def ring(signum, frame):
        raise Hang(f"no answer within {seconds} s")

    previous = signal.signal(signal.SIGALRM, ring)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def leaf_keys(scenario: Scenario) -> list[str]:
    """Every dotted key of a scenario (``vehicle.mass``, ``mission.detection...``)."""
    keys: list[str] = []

    def walk(node: dict, prefix: str) -> None:
        for k, v in node.items():
            if isinstance(v, dict):
                walk(v, f"{prefix}{k}.")
            else:
                keys.append(prefix + k)

    walk(scenario.model_dump(mode="json"), "")
    return keys


def mutate_text(text: str, rng: np.random.Generator) -> str:
    """One to three text mutations of a TOML document."""
    lines = text.splitlines()
    for _ in range(int(rng.integers(1, 4))):
        kind = int(rng.integers(9))
        i = int(rng.integers(len(lines))) if lines else 0
        if not lines:
            lines = [""]
        if kind == 0:  # drop a line
            del lines[i]
        elif kind == 1:  # duplicate a line (duplicate keys, duplicate tables)
            lines.insert(i, lines[i])
        elif kind == 2 and "=" in lines[i]:  # an odd value
            key = lines[i].split("=", 1)[0]
            lines[i] = f"{key}= {ODD_VALUES[int(rng.integers(len(ODD_VALUES)))]}"
        elif kind == 3 and "=" in lines[i]:  # a misspelt or unknown key
            key, value = lines[i].split("=", 1)
            lines[i] = f"{key.strip()[:-1] or 'x'}z ={value}"
        elif kind == 4:  # junk inside a line
            pos = int(rng.integers(len(lines[i]) + 1))
            junk = JUNK[int(rng.integers(len(JUNK)))]
            lines[i] = lines[i][:pos] + junk + lines[i][pos:]
        elif kind == 5:  # truncated file
            joined = "\n".join(lines)
            cut = int(rng.integers(len(joined) + 1))
            lines = joined[:cut].splitlines()
        elif kind == 6:  # an unknown or nested section
            lines.insert(i, f"[{'.'.join(['mission', 'x'] * int(rng.integers(1, 60)))}]")
        elif kind == 7 and "=" in lines[i]:  # a number scaled to the extremes (or inf)
            key, value = lines[i].split("=", 1)
            try:
                number = float(value)
            except ValueError:
                continue
            sign = "-" if rng.random() < 0.5 else ""
            lines[i] = f"{key}= {sign}{abs(number):.6f}e{int(rng.integers(-330, 330))}"
        else:  # a whole section removed (partial files are completed from defaults)
            heads = [k for k, line in enumerate(lines) if line.startswith("[")]
            if heads:
                start = heads[int(rng.integers(len(heads)))]
                end = next((k for k in heads if k > start), len(lines))
                del lines[start:end]
    return "\n".join(lines) + ("\n" if rng.random() < 0.9 else "")


def odd_override(keys: list[str], rng: np.random.Generator) -> str:
    kind = int(rng.integers(6))
    key = keys[int(rng.integers(len(keys)))]
    value = ODD_VALUES[int(rng.integers(len(ODD_VALUES)))]
    if kind == 0:  # a real key, an odd value
        return f"{key}={value}"
    if kind == 1:  # a real key, a number from 1e-330 (0 or subnormal) to 1e330 (inf)
        return f"{key}={rng.uniform(1.0, 10.0):.3f}e{int(rng.integers(-330, 330))}"
    if kind == 2:  # a key one level too deep, or into a value
        return f"{key}.deeper={value}"
    if kind == 3:  # broken syntax
        return ["", "=", "a", "a=", "=1", "..=1", "a..b=1", " . =1", "x" * 400 + "=1",
                "vehicle=1", "vehicle.mass", "surface=[1]"][int(rng.integers(12))]  # fmt: skip
    if kind == 4:  # an unknown key in a real section
        return f"{key.rsplit('.', 1)[0]}.no_such_key={value}"
    return f"{key}={value}{JUNK[int(rng.integers(len(JUNK)))]}"


def check(capsys, code: int, what: str, valid: Callable[[str], None] | None = None) -> bool:
    """Exit 0 with a valid result, or exit 2 with ``error:`` lines; never a traceback.

    Returns True for a valid result."""
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err, f"{what}: {err[-2000:]}"
    if code == 0:
        if valid is not None:
            valid(out)
        return True
    assert code == 2, f"{what}: exit {code}: {err[-600:]}"
    lines = err.rstrip("\n").split("\n")
    assert lines and all(line.startswith("error: ") for line in lines), f"{what}: {err[-600:]}"
    assert all(len(line) <= len("error: ") + MESSAGE_CHARS for line in lines), what
    return False


def show_round_trips(out: str) -> None:
    """`show` printed a scenario that loads back to itself."""
    scenario = tomllib.loads(out)
    again = load_scenario_text(out, scenario.get("name", "custom"))
    assert scenario_to_toml(again) == out


def load_scenario_text(text: str, name: str) -> Scenario:
    from tetherland.config import scenario_from_dict

    return scenario_from_dict(tomllib.loads(text), name)


def test_fuzzed_scenario_files_and_overrides(tmp_path, capsys):
    rng = np.random.default_rng(SEED)
    start = time.monotonic()
    (tmp_path / "dir.toml").mkdir()
    os.mkfifo(tmp_path / "fifo.toml")
    for argv in (["show", str(tmp_path / "dir.toml")], ["plan", str(tmp_path / "fifo.toml")],
                 ["show", str(tmp_path / "missing.toml")], ["show", ""]):  # fmt: skip
        with deadline(CALL_LIMIT):
            assert not check(capsys, main(argv), str(argv))
    texts = {name: scenario_to_toml(load_scenario(name)) for name in BASES}
    valid_files: list[Path] = []
    for k in range(FILES):
        base = BASES[int(rng.integers(len(BASES)))]
        path = tmp_path / f"f{k:03d}.toml"
        if rng.random() < 0.05:  # now and then raw bytes (not UTF-8)
            path.write_bytes(rng.integers(0, 256, int(rng.integers(1, 400)), dtype=np.uint8)
                             .tobytes())  # fmt: skip
        else:
            path.write_text(mutate_text(texts[base], rng), encoding="utf-8", errors="replace")
        with deadline(CALL_LIMIT):
            code = main(["show", str(path)])
        what = f"seed {SEED}, file {k} ({base}): {path.read_bytes()[:3000]!r}"
        if check(capsys, code, what, show_round_trips):
            valid_files.append(path)
    assert 0 < len(valid_files) < FILES  # the mutations hit both sides

    for path in valid_files[:ANALYSED]:  # valid but odd: the analysis must cope
        with deadline(CALL_LIMIT):
            code = main(["analyze", str(path), "--json"])
        out, err = capsys.readouterr()
        assert "Traceback" not in err and code in (0, 1, 2), f"{path}: {err[-1500:]}"
        if code != 2:
            assert err.count("\n") <= 1 and '"tethered"' in out

    keys = leaf_keys(load_scenario("slope50"))
    accepted = 0
    for k in range(OVERRIDES):
        overrides = [odd_override(keys, rng) for _ in range(int(rng.integers(1, 3)))]
        argv = ["show", BASES[k % len(BASES)], *(a for o in overrides for a in ("--set", o))]
        with deadline(CALL_LIMIT):
            code = main(argv)
        accepted += check(capsys, code, f"seed {SEED}: {argv}", show_round_trips)
    assert accepted < OVERRIDES
    print(f"fuzz seed {SEED}: {FILES} files ({len(valid_files)} valid), {OVERRIDES} "
          f"overrides ({accepted} valid) in {time.monotonic() - start:.1f} s")  # fmt: skip


def test_fuzzed_inputs_through_the_installed_script(tmp_path):
    """A few cases through the real script, side by side: a named pipe, binary garbage, a
    2000-deep array, an override with a NUL (a directory and the rest run in process)."""
    fifo = tmp_path / "pipe.toml"
    os.mkfifo(fifo)
    (tmp_path / "bin.toml").write_bytes(bytes(range(256)) * 8)
    (tmp_path / "deep.toml").write_text("a = " + "[" * 2000 + "]" * 2000 + "\n")
    cases = [
        ["plan", str(fifo)],
        ["analyze", str(tmp_path / "bin.toml")],
        ["mission", str(tmp_path / "deep.toml"), "--set", 'name="a\\u0000b"'],
    ]
    procs = [
        subprocess.Popen(
            [EXE, *argv], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path
        )
        for argv in cases
    ]
    for argv, proc in zip(cases, procs, strict=True):
        try:
            _, err = proc.communicate(timeout=120)
        except subprocess.TimeoutExpired:
            proc.kill()
            pytest.fail(f"{argv}: hangs")
        assert proc.returncode == 2 and "Traceback" not in err, (argv, err[-1500:])
        assert err.count("\n") == 1 and err.startswith("error: "), (argv, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bin.toml", "deep.toml", "pipe.toml"]
