"""Loading scenarios: built-in names or TOML files, ``--set`` overrides, clear errors."""

from __future__ import annotations

import json
import stat
import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from tetherland.config.mechanism import MechanismConfig
from tetherland.config.renames import renamed_keys
from tetherland.config.scenario import Scenario
from tetherland.config.schema import allowed_range as _allowed_range
from tetherland.errors import ConfigError, ConfigErrors

_BUILTIN_PACKAGE = "tetherland.scenarios"


@dataclass(frozen=True)
class ScenarioInfo:
    """A built-in scenario: its name, one-line description and file."""

    name: str
    description: str
    path: Path


def builtin_scenarios() -> list[ScenarioInfo]:
    """The scenarios shipped with the package, sorted by name."""
    infos = []
    for entry in resources.files(_BUILTIN_PACKAGE).iterdir():
        if entry.name.endswith(".toml"):
            data = tomllib.loads(entry.read_text(encoding="utf-8"))
            infos.append(
                ScenarioInfo(
                    name=entry.name.removesuffix(".toml"),
                    description=str(data.get("description", "")),
                    path=Path(str(entry)),
                )
            )
    return sorted(infos, key=lambda i: i.name)


MAX_SCENARIO_BYTES = 16 * 1024 * 1024
"""Largest scenario file read [bytes] (a scenario is a few kB of TOML)."""


def _read_source(source: str | Path) -> tuple[dict[str, Any], str]:
    path = Path(source)
    builtins = {info.name: info for info in builtin_scenarios()}
    if str(source) in builtins and not path.exists():
        path = builtins[str(source)].path
    elif not path.exists():
        if path.suffix == ".toml" or path.parent != Path("."):
            raise ConfigError(f"scenario file '{source}' does not exist")
        raise ConfigError(
            f"scenario '{source}' is neither a built-in ({', '.join(sorted(builtins))}) "
            "nor an existing file"
        )
    if path.is_dir():
        raise ConfigError(f"scenario '{source}' is a directory, expected a TOML file")
    try:
        # only regular files: a named pipe or a device would block or never end
        if not stat.S_ISREG(path.stat().st_mode):
            raise ConfigError(f"scenario '{source}' is not a regular file, expected a TOML file")
        if path.stat().st_size > MAX_SCENARIO_BYTES:
            raise ConfigError(
                f"scenario file '{path}' is {path.stat().st_size / 2**20:.0f} MiB; a scenario "
                f"is at most {MAX_SCENARIO_BYTES // 2**20} MiB of TOML"
            )
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"scenario file '{path}' is not valid TOML: {err}") from None
    except (OSError, UnicodeDecodeError) as err:
        raise ConfigError(f"scenario file '{path}' cannot be read: {err}") from None
    except RecursionError:
        raise ConfigError(f"scenario file '{path}': tables or arrays nested too deeply") from None
    return data, path.stem


def parse_override(text: str) -> tuple[list[str], Any]:
    """Split ``"section.key=value"`` into a key path and a value parsed as TOML.

    A value that is not valid TOML is taken as a plain string, so ``surface.kind=pipe``
    works as well as ``surface.kind="pipe"``.
    """
    key, sep, raw = text.partition("=")
    keys = [k.strip() for k in key.strip().split(".")]
    if not sep or not all(keys) or not raw.strip():
        raise ConfigError(
            f"override '{text}': expected section.key=value, e.g. surface.slope_deg=60"
        )
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    except RecursionError:
        raise ConfigError(f"override '{text[:60]}': value nested too deeply") from None
    return keys, value


def apply_overrides(data: dict[str, Any], overrides: Sequence[str]) -> dict[str, Any]:
    """Return a copy of ``data`` with every ``section.key=value`` override applied."""
    import copy

    try:
        out = copy.deepcopy(data)
    except RecursionError:
        raise ConfigError("scenario: tables or arrays nested too deeply") from None
    for text in overrides:
        keys, value = parse_override(text)
        node = out
        for depth, k in enumerate(keys[:-1]):
            child = node.setdefault(k, {})
            if not isinstance(child, dict):
                where = ".".join(keys[: depth + 1])
                raise ConfigError(f"override '{text}': '{where}' is a value, not a section")
            node = child
        node[keys[-1]] = value
    return out


def _field_info(model: type[BaseModel], loc: Sequence[Any]):
    """Walk ``loc`` through nested models; return the FieldInfo of the last named field."""
    info = None
    current: Any = model
    for part in loc:
        if isinstance(part, int) or not (
            isinstance(current, type) and issubclass(current, BaseModel)
        ):
            continue
        info = current.model_fields.get(part)
        if info is None:
            return None
        current = info.annotation
    return info


VALUE_CHARS = 60
"""Longest quoted input value in an error message [characters]."""


def _short_repr(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= VALUE_CHARS else text[: VALUE_CHARS - 3] + "..."


def _format_one(error: Any, model: type[BaseModel]) -> str:
    """One line for one pydantic error: the field, what is wrong, the allowed range."""
    loc = list(error["loc"])
    name = ""
    for part in loc:
        name += f"[{part}]" if isinstance(part, int) else (f".{part}" if name else str(part))
    msg = str(error["msg"]).removeprefix("Value error, ")
    if error["type"] == "json_invalid":  # the JSON form's parser: only its depth limit
        return "scenario: tables or arrays nested too deeply" if "recursion" in msg else msg
    if error["type"] == "extra_forbidden":
        parent = _field_info(model, loc[:-1])
        parent_model = parent.annotation if parent is not None else model
        allowed = sorted(getattr(parent_model, "model_fields", {}))
        return f"{name}: unknown key (allowed keys: {', '.join(allowed)})"
    text = f"{name}: {msg}" if name else msg
    section = _field_info(model, loc)
    section_model = section.annotation if section is not None else None
    first_word = msg.split(" ", 1)[0]
    if error["type"] == "value_error" and first_word in getattr(section_model, "model_fields", {}):
        text = f"{name}.{msg}"  # a section-level check that names its field first
    if "input" in error and error["type"] not in ("value_error", "assertion_error"):
        value = error["input"]
        if not isinstance(value, dict):
            text += f" (got {_short_repr(value)})"
    rng = _allowed_range(_field_info(model, loc))
    if rng and error["type"] not in ("value_error",):
        text += f"; allowed range {rng}"
    return text


def format_validation_errors(err: ValidationError, model: type[BaseModel] = Scenario) -> list[str]:
    """One line per bad field: its name, what is wrong and the allowed range."""
    return [_format_one(e, model) for e in err.errors(include_url=False)]


def format_validation_error(err: ValidationError, model: type[BaseModel] = Scenario) -> str:
    """One line naming the first bad field, what is wrong and the allowed range."""
    lines = format_validation_errors(err, model)
    text = lines[0]
    if len(lines) > 1:
        text += f" (and {len(lines) - 1} more error{'s' if len(lines) > 2 else ''})"
    return text


def _json_value(value: Any) -> Any:
    """Values TOML has and JSON not (dates, times) become text, which no field accepts."""
    item = getattr(value, "item", None)  # numpy scalars
    return item() if callable(item) else str(value)


def bar_anchor_height(data: dict[str, Any]) -> dict[str, Any]:
    """``data`` with ``anchor.h_A`` = ``mechanism.standoff`` when the mechanism is the bar
    and ``anchor.h_A`` is 0 or absent: the bar's anchor is its axis, so "on the surface"
    means the mechanism fixed on the surface with its axis at the standoff. For the magnet,
    ``anchor.h_A`` = ``plate_thickness + magnet_thickness`` (the cable's eye on the magnet
    held on the plate)."""
    mech, anchor = data.get("mechanism"), data.get("anchor", {})
    if not isinstance(mech, dict) or mech.get("kind") not in ("bar", "magnet") or not isinstance(
            anchor, dict):  # fmt: skip
        return data
    h_A = anchor.get("h_A", 0.0)
    if isinstance(h_A, bool) or not isinstance(h_A, (int, float)) or h_A != 0.0:
        return data
    fields = MechanismConfig.model_fields
    if mech.get("kind") == "magnet":  # the cable's eye on the magnet held on the plate
        parts = [mech.get(k, fields[k].default) for k in ("plate_thickness", "magnet_thickness")]
        if not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in parts):
            return data  # the field's own error names it
        height = float(parts[0] + parts[1])
        return {**data, "anchor": {**anchor, "h_A": height}}
    standoff = mech.get("standoff", fields["standoff"].default)
    return {**data, "anchor": {**anchor, "h_A": standoff}}


def scenario_from_dict(data: dict[str, Any], default_name: str = "custom") -> Scenario:
    """Validate a nested dict (TOML layout) into a :class:`Scenario`.

    Types are strict: a number field takes an integer or a float, never a boolean or a
    string; a boolean field takes only ``true`` or ``false``; an integer field no float.
    An old field name is named with its new one (:mod:`tetherland.config.renames`).

    Raises
    ------
    ConfigErrors
        One line per bad field (every field error at once).
    """
    data = bar_anchor_height(dict(data))
    data.setdefault("name", default_name)
    try:
        # strict validation of the JSON form: no bool <-> number or "yes" -> bool coercion,
        # while TOML arrays still fill tuples (strict Python mode would refuse them)
        document = json.dumps(data, default=_json_value)
        return Scenario.model_validate_json(document, strict=True)
    except ValidationError as err:
        renamed = dict(renamed_keys(data))
        lines = []
        for error in err.errors(include_url=False):
            dotted = ".".join(str(part) for part in error["loc"])
            if error["type"] == "extra_forbidden" and dotted in renamed:
                lines.append(f"{dotted} was renamed: use {renamed[dotted]}")
            else:
                lines.append(_format_one(error, Scenario))
        raise ConfigErrors(sorted(lines, key=lambda line: "was renamed" not in line)) from None
    except RecursionError:
        raise ConfigError("scenario: tables or arrays nested too deeply") from None
    except ArithmeticError as err:  # a check's arithmetic on an extreme value (1/5e-324)
        raise ConfigError(f"scenario: a value is out of any usable range ({err})") from None


def load_scenario(source: str | Path, overrides: Sequence[str] = ()) -> Scenario:
    """Load a built-in scenario by name, or a TOML file by path, and apply overrides.

    Parameters
    ----------
    source
        A built-in name (see :func:`builtin_scenarios`) or a path to a TOML file.
    overrides
        ``section.key=value`` strings; values are parsed as TOML.

    Raises
    ------
    ConfigError
        With a one-line message naming the field and the allowed range.
    """
    data, stem = _read_source(source)
    return scenario_from_dict(apply_overrides(data, overrides), default_name=stem)


def with_overrides(scenario: Scenario, overrides: Sequence[str]) -> Scenario:
    """A validated copy of ``scenario`` with ``section.key=value`` overrides applied."""
    if not overrides:
        return scenario
    return scenario_from_dict(
        apply_overrides(scenario.model_dump(mode="python", exclude_none=True), overrides),
        scenario.name,
    )


def scenario_to_toml(scenario: Scenario) -> str:
    """Render a scenario as TOML (every field, including defaults), loadable again."""
    dumped = scenario.model_dump(mode="json", exclude_none=True)
    lines: list[str] = []

    def fmt(v: Any) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(fmt(x) for x in v) + "]"
        return repr(v)

    def emit(table: dict[str, Any], prefix: str) -> None:
        scalars = {k: v for k, v in table.items() if not isinstance(v, dict)}
        if prefix:
            lines.append(f"\n[{prefix}]")
        for k, v in scalars.items():
            lines.append(f"{k} = {fmt(v)}")
        for k, v in table.items():
            if isinstance(v, dict):
                emit(v, f"{prefix}.{k}" if prefix else k)

    emit(dumped, "")
    return "\n".join(lines).lstrip() + "\n"
