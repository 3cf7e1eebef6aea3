"""Loading scenarios: built-in names or TOML files, ``--set`` overrides, clear errors."""

from __future__ import annotations

import tomllib
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ValidationError

from tetherland.config.renames import check_renames
from tetherland.config.scenario import Scenario
from tetherland.config.schema import allowed_range as _allowed_range
from tetherland.errors import ConfigError

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
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except tomllib.TOMLDecodeError as err:
        raise ConfigError(f"scenario file '{path}' is not valid TOML: {err}") from None
    except (OSError, UnicodeDecodeError) as err:
        raise ConfigError(f"scenario file '{path}' cannot be read: {err}") from None
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
    return keys, value


def apply_overrides(data: dict[str, Any], overrides: Sequence[str]) -> dict[str, Any]:
    """Return a copy of ``data`` with every ``section.key=value`` override applied."""
    import copy

    out = copy.deepcopy(data)
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


def format_validation_error(err: ValidationError, model: type[BaseModel] = Scenario) -> str:
    """One line naming the first bad field, what is wrong and the allowed range."""
    errors = err.errors(include_url=False)
    first = errors[0]
    loc = list(first["loc"])
    name = ""
    for part in loc:
        name += f"[{part}]" if isinstance(part, int) else (f".{part}" if name else str(part))
    msg = str(first["msg"]).removeprefix("Value error, ")
    if first["type"] == "extra_forbidden":
        parent = _field_info(model, loc[:-1])
        parent_model = parent.annotation if parent is not None else model
        allowed = sorted(getattr(parent_model, "model_fields", {}))
        text = f"{name}: unknown key (allowed keys: {', '.join(allowed)})"
    else:
        text = f"{name}: {msg}" if name else msg
        section = _field_info(model, loc)
        section_model = section.annotation if section is not None else None
        first_word = msg.split(" ", 1)[0]
        if first["type"] == "value_error" and first_word in getattr(
            section_model, "model_fields", {}
        ):
            text = f"{name}.{msg}"  # a section-level check that names its field first
        if "input" in first and first["type"] not in ("value_error", "assertion_error"):
            value = first["input"]
            if not isinstance(value, dict):
                text += f" (got {value!r})"
        rng = _allowed_range(_field_info(model, loc))
        if rng and first["type"] not in ("value_error",):
            text += f"; allowed range {rng}"
    if len(errors) > 1:
        text += f" (and {len(errors) - 1} more error{'s' if len(errors) > 2 else ''})"
    return text


def scenario_from_dict(data: dict[str, Any], default_name: str = "custom") -> Scenario:
    """Validate a nested dict (TOML layout) into a :class:`Scenario` (old field names are
    refused with their new name, :mod:`tetherland.config.renames`)."""
    check_renames(data)
    data = dict(data)
    data.setdefault("name", default_name)
    try:
        return Scenario.model_validate(data)
    except ValidationError as err:
        raise ConfigError(format_validation_error(err)) from None


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
