"""A missing optional dependency fails with one clear line, not an ImportError traceback."""

from __future__ import annotations

import sys

import pytest

from tetherland.cli import main
from tetherland.errors import MissingDependencyError
from tetherland.optional import require


def test_require_names_the_package_and_the_extra():
    with pytest.raises(MissingDependencyError) as err:
        require("no_such_module_xyz", package="no-such-pkg", extra="viz", feature="the export")
    text = str(err.value)
    assert "no-such-pkg" in text and "tetherland[viz]" in text and "\n" not in text
    assert isinstance(err.value, ImportError)  # still an ImportError for library callers


@pytest.mark.parametrize(
    ("blocked", "argv", "needle"),
    [
        ("foxglove", ["export", "RUN", "--mcap"], "foxglove-sdk"),
        ("foxglove", ["mission", "slope50", "--mcap", "--out", "OUT"], "foxglove-sdk"),
    ],
)
def test_cli_reports_a_missing_sdk_on_one_line(monkeypatch, capsys, tmp_path, blocked, argv,
                                               needle):  # fmt: skip
    for name in list(sys.modules):
        if name == blocked or name.startswith((f"{blocked}.", "tetherland.viz")):
            monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, blocked, None)  # import raises ImportError
    argv = [str(tmp_path) if a == "RUN" else str(tmp_path / "o") if a == "OUT" else a
            for a in argv]  # fmt: skip
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and needle in err and "pip install" in err
    assert not (tmp_path / "o").exists()  # nothing half-written


def test_gym_without_gymnasium_is_one_clear_error(monkeypatch):
    for name in list(sys.modules):
        if name == "gymnasium" or name.startswith(("gymnasium.", "tetherland.gym")):
            monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "gymnasium", None)
    with pytest.raises(MissingDependencyError, match=r"tetherland\[gym\]"):
        import tetherland.gym  # noqa: F401
