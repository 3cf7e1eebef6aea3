"""The trajectory CSV format shared by every planned trajectory kind.

A file is ``#`` header lines, one line of column names, then one row of numbers per
sample (``.17g``: floats round-trip exactly)::

    # tetherland trajectory
    # format: 1
    # kind: ocp                     (which trajectory class; its CsvSchema)
    # scenario: slope50
    # maneuver: landing
    # version: 0.1.0                (tetherland version that wrote it)
    # meta: {...}                   (JSON: the model constants needed to rebuild it)
    t,phi_d0,...                    (the kind's columns)
    0,0.61086523819801530,...

:func:`encode` writes one, :func:`decode` reads and validates one against the schemas a
reader accepts; the trajectory classes (:mod:`.trajectory`, :mod:`.perching.trajectory`)
only say which columns they write and how they rebuild themselves from them.
"""

from __future__ import annotations

import io
import json
from collections.abc import Iterable
from dataclasses import MISSING, dataclass, fields
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike

from tetherland.errors import ConfigError
from tetherland.geometry import FloatArray

FORMAT_VERSION = 1
TITLE = "# tetherland trajectory"
T = TypeVar("T")


@dataclass(frozen=True)
class CsvSchema:
    """The columns of one trajectory kind.

    Attributes
    ----------
    kind : str
        The ``# kind:`` header value (e.g. ``ocp``, ``spline``, ``free-flight``).
    columns : tuple of str
        Column names, in order.
    """

    kind: str
    columns: tuple[str, ...]


@dataclass(frozen=True)
class CsvDocument:
    """A decoded trajectory file.

    Attributes
    ----------
    schema : CsvSchema
        The schema of its kind.
    header : dict of str
        Every ``# key: value`` header line (``scenario``, ``maneuver``, ``version``, ...).
    meta : dict
        The decoded JSON ``meta`` header.
    data : (n, len(columns)) array
    """

    schema: CsvSchema
    header: dict[str, str]
    meta: dict[str, Any]
    data: FloatArray

    @property
    def kind(self) -> str:
        return self.schema.kind

    def column(self, name: str) -> FloatArray:
        """One column by name."""
        return self.data[:, self.schema.columns.index(name)]


def encode(
    schema: CsvSchema,
    data: ArrayLike,
    meta: dict[str, Any],
    *,
    scenario: str,
    maneuver: str,
    version: str,
) -> str:
    """The CSV text of ``data`` (n, len(schema.columns)) with its header lines."""
    rows = np.atleast_2d(np.asarray(data, dtype=float))
    if rows.shape[1] != len(schema.columns):
        raise ValueError(f"{rows.shape[1]} data columns for {len(schema.columns)} names")
    head = [
        TITLE,
        f"# format: {FORMAT_VERSION}",
        f"# kind: {schema.kind}",
        f"# scenario: {scenario}",
        f"# maneuver: {maneuver}",
        f"# version: {version}",
        f"# meta: {json.dumps(meta)}",
        ",".join(schema.columns),
    ]
    body = "\n".join(",".join(format(v, ".17g") for v in row) for row in rows)
    return "\n".join(head) + "\n" + body + "\n"


def decode(text: str, schemas: Iterable[CsvSchema]) -> CsvDocument:
    """Parse ``text`` as a file of one of ``schemas``' kinds.

    Raises
    ------
    ConfigError
        One line naming what is wrong: format version, kind, column header, meta JSON.
    """
    accepted = {s.kind: s for s in schemas}
    header: dict[str, str] = {}
    lines = text.splitlines()
    i = 0
    while i < len(lines) and lines[i].startswith("#"):
        key, sep, value = lines[i][1:].partition(":")
        if sep:
            header[key.strip()] = value.strip()
        i += 1
    if header.get("format") != str(FORMAT_VERSION):
        raise ConfigError(f"trajectory CSV: unsupported format {header.get('format')!r}")
    names = tuple(lines[i].split(",")) if i < len(lines) else ()
    kind = header.get("kind")
    schema = accepted.get(kind or "")
    if schema is None and kind is not None:
        raise ConfigError(
            f"trajectory CSV: kind {kind!r} is not " + " or ".join(repr(k) for k in accepted)
        )
    if schema is None or names != schema.columns:
        raise ConfigError("trajectory CSV: missing or unexpected column header")
    try:
        meta = json.loads(header["meta"])
    except (KeyError, json.JSONDecodeError) as err:
        raise ConfigError(f"trajectory CSV: bad meta header ({err})") from None
    try:
        data = np.loadtxt(io.StringIO("\n".join(lines[i + 1 :])), delimiter=",", ndmin=2)
    except ValueError as err:
        raise ConfigError(f"trajectory CSV: bad data row ({err})") from None
    if data.shape[1:] != (len(schema.columns),):
        raise ConfigError(
            f"trajectory CSV: rows have {data.shape[1] if data.ndim == 2 else 0} values for "
            f"{len(schema.columns)} columns"
        )
    return CsvDocument(schema=schema, header=header, meta=meta, data=data)


def meta_to_json(record: Any) -> dict[str, Any]:
    """A frozen dataclass of model constants as JSON (arrays as nested lists)."""
    return {
        f.name: np.asarray(v).tolist() if isinstance(v, np.ndarray) else v
        for f in fields(record)
        for v in (getattr(record, f.name),)
    }


def meta_from_json(cls: type[T], d: dict[str, Any]) -> T:
    """The dataclass ``cls`` from :func:`meta_to_json` output (fields typed ``FloatArray``
    become float arrays). Raises KeyError for a missing field without a default (a field
    with one, added later, keeps its default when an older file lacks it)."""
    return cls(
        **{
            f.name: np.asarray(d[f.name], dtype=float) if f.type == "FloatArray" else d[f.name]
            for f in fields(cls)  # type: ignore[arg-type]
            if f.name in d or (f.default is MISSING and f.default_factory is MISSING)
        }
    )


def read_text(path: str | Path) -> str:
    """The text of a trajectory file, or a one-line :class:`ConfigError`."""
    try:
        return Path(path).read_text(encoding="utf-8")
    except OSError as err:
        raise ConfigError(f"cannot read trajectory file '{path}': {err}") from None
