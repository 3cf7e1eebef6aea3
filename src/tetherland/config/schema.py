"""The scenario schema as data: every field with its TOML key, type, unit, range, default
and meaning, read from the pydantic models (for the generated reference,
docs/reference/scenario.md, and the naming rules the tests enforce).

Naming rules (every section): fields in SI units carry no unit suffix; fields in degrees
end in ``_deg``, angular rates in degrees per second in ``_deg_s``, frequencies in hertz
in ``_hz``; no other unit suffix. Time constants end in ``_time_constant``. Every numeric
field's description ends with its unit in brackets, ``[-]`` for a plain number.
"""

from __future__ import annotations

import enum
import re
import types
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Annotated, Any, Literal, Union, get_args, get_origin

import annotated_types as at
from pydantic import BaseModel
from pydantic.fields import FieldInfo

_UNIT = re.compile(r"\s*\[([^\[\]]+)\]\.?\s*$")


@dataclass(frozen=True)
class FieldDoc:
    """One scenario field as the reference shows it.

    Attributes
    ----------
    key : str
        Dotted TOML key, e.g. ``mission.touchdown.hold_rate``.
    section : str
        Dotted TOML table the field sits in (empty for the top level).
    type : str
        What a TOML file gives: ``float``, ``int``, ``bool``, ``str``, ``"a" | "b"``,
        ``[float, float, float]``; ``or none`` when it may be left unset.
    numeric : bool
        A number or an array of numbers (it has a unit).
    unit : str or None
        The unit from the description's trailing brackets (``-`` for a plain number).
    range : str or None
        Allowed values as an interval, e.g. ``(0, 10]``; ``each in ...`` for arrays.
    default : Any
        The default value (None: unset).
    meaning : str
        The description without its unit, on one line.
    """

    key: str
    section: str
    type: str
    numeric: bool
    unit: str | None
    range: str | None
    default: Any
    meaning: str

    @property
    def name(self) -> str:
        """The field's own name (the last part of the key)."""
        return self.key.rsplit(".", 1)[-1]


def allowed_range(info: Any) -> str | None:
    """The interval of a field's (or an annotated type's) bounds, e.g. ``(0, 10]``; None
    when unbounded."""
    lo = hi = None
    lo_open = hi_open = False
    for m in getattr(info, "metadata", []):
        if isinstance(m, at.Gt):
            lo, lo_open = m.gt, True
        elif isinstance(m, at.Ge):
            lo, lo_open = m.ge, False
        elif isinstance(m, at.Lt):
            hi, hi_open = m.lt, True
        elif isinstance(m, at.Le):
            hi, hi_open = m.le, False
    if lo is None and hi is None:
        return None
    left = "(" if lo_open or lo is None else "["
    right = ")" if hi_open or hi is None else "]"
    low = "-inf" if lo is None else f"{lo:g}"
    high = "inf" if hi is None else f"{hi:g}"
    return f"{left}{low}, {high}{right}"


def split_unit(description: str) -> tuple[str, str | None]:
    """(meaning, unit) of a description ending in ``[unit]`` (unit None if it does not)."""
    text = " ".join(description.split())
    match = _UNIT.search(text)
    if match is None:
        return text, None
    meaning = text[: match.start()].rstrip()
    return (meaning if meaning.endswith((".", "?", "!")) else meaning + "."), match.group(1)


def _optional(annotation: Any) -> tuple[Any, bool]:
    if get_origin(annotation) in (Union, types.UnionType):
        args = [a for a in get_args(annotation) if a is not type(None)]
        if len(args) == 1 and len(args) < len(get_args(annotation)):
            return args[0], True
    return annotation, False


def _element(annotation: Any) -> tuple[Any, Any]:
    """(bare type, the Annotated metadata holder or None)."""
    if get_origin(annotation) is Annotated:
        base, *meta = get_args(annotation)
        return base, FieldInfo.merge_field_infos(*[m for m in meta if isinstance(m, FieldInfo)])
    return annotation, None


def _type_name(annotation: Any) -> tuple[str, bool, str | None]:
    """(type as given in TOML, numeric, element range of an array)."""
    base, meta = _element(annotation)
    if get_origin(base) is Literal:
        values = get_args(base)
        numeric = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values)
        names = " | ".join(f'"{v}"' if isinstance(v, str) else str(v) for v in values)
        return names, numeric, None
    if get_origin(base) is tuple:
        parts = [_type_name(a) for a in get_args(base)]
        ranges = {allowed_range(_element(a)[1]) for a in get_args(base)}
        element_range = ranges.pop() if len(ranges) == 1 else None
        numeric = all(p[1] for p in parts)
        return "[" + ", ".join(p[0] for p in parts) + "]", numeric, element_range
    if isinstance(base, type) and issubclass(base, enum.Enum):
        return " | ".join(f'"{m.value}"' for m in base), False, None
    if base is bool:
        return "bool", False, None
    if base in (int, float):
        return base.__name__, True, allowed_range(meta) if meta is not None else None
    return getattr(base, "__name__", str(base)), False, None


def _is_section(annotation: Any) -> bool:
    return isinstance(annotation, type) and issubclass(annotation, BaseModel)


def sections(model: type[BaseModel], prefix: str = "") -> Iterator[tuple[str, type[BaseModel]]]:
    """Every (dotted TOML table, model) below ``model``, depth first, ``model`` first."""
    yield prefix, model
    for name, info in model.model_fields.items():
        if _is_section(info.annotation):
            yield from sections(info.annotation, f"{prefix}.{name}" if prefix else name)


def fields(model: type[BaseModel], prefix: str = "") -> Iterator[FieldDoc]:
    """Every leaf field of ``model`` and its sections, in declaration order."""
    for section, sub in sections(model, prefix):
        for name, info in sub.model_fields.items():
            if _is_section(info.annotation):
                continue
            annotation, optional = _optional(info.annotation)
            type_name, numeric, element_range = _type_name(annotation)
            field_range = allowed_range(info)
            if field_range is None and element_range is not None:
                field_range = f"each in {element_range}"
            meaning, unit = split_unit(info.description or "")
            yield FieldDoc(
                key=f"{section}.{name}" if section else name,
                section=section,
                type=type_name + (" or none" if optional else ""),
                numeric=numeric,
                unit=unit,
                range=field_range,
                default=info.default,
                meaning=meaning,
            )
