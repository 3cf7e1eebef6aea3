"""The columnar run log: one row per control tick, named columns, saved atomically as .npz.

A :class:`SimLog` holds one float64 matrix (rows = control ticks) and a schema of named
column groups; ``log["p_W"]`` is an ``(n, 3)`` view. Integer-valued columns (phase, mode,
hook state, mocap validity) are floats in memory and integers on disk (unless they hold NaN).
``NaN`` marks a value that was not available (e.g. no bias estimate, no mocap sample yet).

On disk (``.npz``): one member per column group, plus ``__metadata__``, a JSON document
with provenance, rates, the schema (units, meaning, precision and stored dtype of every
column), events (hook, runner) and the run status. Each column is stored at its
:class:`~tetherland.sim.log_codec.Precision` (:attr:`Column.storage`: time in float64,
the plant's truth in float32, the robot's side rounded to 16 significant bits, integer
codes as small integers) and encoded losslessly (:mod:`tetherland.sim.log_codec`): an
80 s mission takes about 6 MB, written in about 0.1 s. :meth:`SimLog.at_storage_precision`
(a copy; :meth:`SimLog.round_to_storage` in place) gives the log exactly as it reads
back; runs are judged on it, so the verdict recomputed
from the file equals the one the run reported. Logs of format 1 (every column a plain
float64 or int64 array) still load.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from enum import StrEnum
from pathlib import Path
from typing import Any

import numpy as np

from tetherland.geometry import FloatArray
from tetherland.io import atomic_write_with, to_jsonable
from tetherland.sim.log_codec import Precision, decode, encode, rounded, to_storage

FORMAT_VERSION = 2
READABLE_VERSIONS = (1, 2)
"""Format 1: plain float64/int64 arrays; format 2: columns at their precision, encoded."""
METADATA_KEY = "__metadata__"


class RunStatus(StrEnum):
    """How a run ended."""

    COMPLETED = "completed"
    """The requested duration was simulated."""
    TERMINATED = "terminated"
    """The reference source asked to stop (mission finished)."""
    DIVERGED = "diverged"
    """The physics diverged (:class:`tetherland.errors.SimulationError`)."""
    FAILED = "failed"
    """A controller, estimator or supervisor raised a tetherland error (e.g. a singularity)."""


@dataclass(frozen=True)
class Column:
    """A named group of columns.

    Attributes
    ----------
    name : str
    width : int
        Number of matrix columns (3 for a vector, 1 for a scalar).
    unit : str
    doc : str
    integer : bool
        Holds integer codes (stored as integers, exactly).
    precision : Precision or None
        Storage precision; None: the default rule of :attr:`storage`.
    """

    name: str
    width: int
    unit: str
    doc: str
    integer: bool = False
    precision: Precision | None = None

    @property
    def storage(self) -> Precision:
        """The storage precision: :attr:`precision` if set, otherwise integer codes exact,
        times (unit ``s``) in float64 and every other column in float32."""
        if self.precision is not None:
            return self.precision
        if self.integer:
            return Precision.INTEGER
        return Precision.FLOAT64 if self.unit == "s" else Precision.FLOAT32


def _c(name: str, width: int, unit: str, doc: str, integer: bool = False,
       precision: Precision | None = None) -> Column:  # fmt: skip
    return Column(name, width, unit, doc, integer, precision)


def _robot_side(columns: tuple[Column, ...]) -> tuple[Column, ...]:
    """``columns`` (what the robot measured, believed, wanted) stored rounded to 16
    significant bits, unless integer codes or times: far finer than sensor noise and
    estimation error, and they are never judged."""
    return tuple(
        c if c.integer or c.unit == "s" else replace(c, precision=Precision.ROUNDED16)
        for c in columns
    )


# Row layout, in matrix order: sim/log_row.py (LogRow) checks the groups it fills as one.
SCALARS: tuple[Column, ...] = (
    _c("t", 1, "s", "time of the control tick"),
    _c("phase", 1, "-", "mission phase code from the reference", True),
    _c("mode", 1, "-", "ControlMode of the reference", True),
    _c("hook", 1, "-", "HookState of the plant (1 = cable engaged)", True),
    _c("mocap_t", 1, "s", "measurement time of the last delivered mocap sample"),
    _c("mocap_valid", 1, "-", "last delivered mocap sample was valid", True),
    *_robot_side((
        _c("est_tension", 1, "N", "estimated cable tension"),
        _c("ref_yaw", 1, "rad", "reference heading"),
        _c("cmd_thrust", 1, "N", "total thrust the controller wanted"),
    )),
)
TRUTH: tuple[Column, ...] = (
    _c("p_W", 3, "m", "true position of the centre of mass"),
    _c("q_WB", 4, "-", "true attitude (w, x, y, z)"),
    _c("v_W", 3, "m/s", "true velocity"),
    _c("omega_B", 3, "rad/s", "true body rate"),
    _c("specific_force_B", 3, "m/s^2", "true specific force (a - g) in F_B"),
    _c("tension", 1, "N", "cable tension (tendonlimitfrc)"),
    _c("cable_length", 1, "m", "anchor-to-attachment distance"),
    _c("lander_forces", 4, "N", "normal force on each lander"),
    _c("rotor_speeds", 4, "rad/s", "rotor speeds"),
    _c("rotor_thrusts", 4, "N", "acting rotor thrusts (surface factors included)"),
    _c("ground_effect", 4, "-", "surface factor T/T_OGE of each rotor (ground, ceiling)"),
    _c("drag_force_W", 3, "N", "rotor drag (and wall pull) at the centre of mass, F_W"),
    _c("lander_surface_forces", 4, "N", "largest normal force of the landing surface on "
       "each lander over the physics steps since the previous control tick"),
    _c("lander_ground_forces", 4, "N", "largest normal force of the ground (start pad) on "
       "each lander over the physics steps since the previous control tick"),
    _c("frame_force", 1, "N", "largest normal force on any part but the landers (hub, "
       "mount, arms, legs, rotor guards; a crash if > 0) over the physics steps since the "
       "previous control tick"),
    _c("frame_part", 1, "-", "index in sim.mjcf.FRAME_PARTS (metadata 'frame_parts') of "
       "the part that frame_force acted on, -1 when none", True),
    _c("penetration", 1, "m", "deepest penetration of any vehicle geom into anything "
       "(MuJoCo's contact distance) over the physics steps since the previous control tick"),
    _c("hook_p_W", 3, "m", "true hook position: the hook body's crown (bar mechanism), "
       "else the capture-disk model's hook point"),
)
MEASUREMENTS: tuple[Column, ...] = _robot_side((
    _c("imu_specific_force_B", 3, "m/s^2", "last IMU specific force"),
    _c("imu_omega_B", 3, "rad/s", "last IMU angular rate"),
    _c("imu_bias", 6, "m/s^2, rad/s", "true IMU biases [accel, gyro] of that sample"),
    _c("mocap_p_W", 3, "m", "last delivered mocap position"),
    _c("mocap_q_WB", 4, "-", "last delivered mocap attitude"),
))
ESTIMATE: tuple[Column, ...] = _robot_side((
    _c("est_p_W", 3, "m", "estimated position"),
    _c("est_v_W", 3, "m/s", "estimated velocity"),
    _c("est_q_WB", 4, "-", "estimated attitude"),
    _c("est_omega_B", 3, "rad/s", "estimated body rate"),
    _c("est_accel_bias_B", 3, "m/s^2", "estimated accelerometer bias"),
    _c("est_gyro_bias_B", 3, "rad/s", "estimated gyro bias"),
    _c("est_link", 4, "rad, rad/s", "estimated [phi, delta, phi', delta']"),
))
REFERENCE_COMMAND: tuple[Column, ...] = _robot_side((
    _c("ref_p_W", 3, "m", "reference position"),
    _c("ref_output", 4, "rad", "reference output y^b = [phi, delta, theta_A, psi]"),
    _c("cmd_rotor_speeds", 4, "rad/s", "commanded rotor speeds (before plant clamping)"),
    _c("cmd_torque_B", 3, "N m", "body torque the controller wanted"),
))
DERIVED: tuple[Column, ...] = (
    _c("link_phi", 1, "rad", "true elevation of the attachment point around the anchor"),
    _c("link_delta", 1, "rad", "true azimuth of the attachment point around the anchor"),
)
BASE_COLUMNS: tuple[Column, ...] = SCALARS + TRUTH + MEASUREMENTS + ESTIMATE + REFERENCE_COMMAND


EXACT_DIAGNOSTICS = frozenset({"ff_tension"})
"""Diagnostics the judge compares with a bound the plan may meet exactly (the planned
tension against ``planner.min_tension``): stored in float64."""


def diagnostic_columns(keys: Iterable[str]) -> tuple[Column, ...]:
    """Columns ``diag.<key>`` for the controller diagnostics to record."""
    return tuple(
        _c(f"diag.{k}", 1, "-", f"controller diagnostic '{k}'", precision=Precision.FLOAT64)
        if k in EXACT_DIAGNOSTICS
        else _robot_side((_c(f"diag.{k}", 1, "-", f"controller diagnostic '{k}'"),))[0]
        for k in keys
    )


def _slices(columns: tuple[Column, ...]) -> dict[str, slice]:
    out, i = {}, 0
    for col in columns:
        if col.name in out:
            raise ValueError(f"duplicate log column '{col.name}'")
        out[col.name] = slice(i, i + col.width)
        i += col.width
    return out


def row_width(columns: tuple[Column, ...]) -> int:
    return sum(c.width for c in columns)


@dataclass(frozen=True)
class SimLog:
    """A run log: named columns over control ticks, metadata and events.

    Attributes
    ----------
    columns : tuple of Column
        Schema, in matrix order.
    matrix : (n, width) array
        All values; prefer named access ``log[name]``.
    metadata : dict
        JSON-compatible: provenance, rates, status, events, schema.
    """

    columns: tuple[Column, ...]
    matrix: FloatArray
    metadata: dict[str, Any] = field(default_factory=dict)
    _slices: dict[str, slice] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_slices", _slices(self.columns))
        if self.matrix.ndim != 2 or self.matrix.shape[1] != row_width(self.columns):
            raise ValueError(
                f"log matrix has shape {self.matrix.shape}, "
                f"schema needs (n, {row_width(self.columns)})"
            )

    def __len__(self) -> int:
        return self.matrix.shape[0]

    def __contains__(self, name: object) -> bool:
        return name in self._slices

    def __getitem__(self, name: str) -> FloatArray:
        """Column group ``name``: (n,) for a scalar, (n, width) otherwise (a view)."""
        try:
            s = self._slices[name]
        except KeyError:
            raise KeyError(f"no log column '{name}' (have: {', '.join(self.names)})") from None
        return self.matrix[:, s.start] if s.stop - s.start == 1 else self.matrix[:, s]

    @property
    def names(self) -> list[str]:
        return [c.name for c in self.columns]

    @property
    def t(self) -> FloatArray:
        return self["t"]

    @property
    def status(self) -> RunStatus:
        return RunStatus(self.metadata.get("status", RunStatus.COMPLETED.value))

    @property
    def events(self) -> list[dict[str, Any]]:
        return list(self.metadata.get("events", []))

    def at_storage_precision(self) -> SimLog:
        """This log with every column rounded to its :attr:`Column.storage` precision:
        exactly what :meth:`save` then :meth:`load` give back (a copy)."""
        return SimLog(self.columns, self.matrix.copy(), dict(self.metadata)).round_to_storage()

    def round_to_storage(self) -> SimLog:
        """Round every column to its :attr:`Column.storage` precision in place (what
        :meth:`save` then :meth:`load` give back) and return this log: for the owner of a
        log nobody else holds, e.g. the run's own (a copy's fresh memory costs more than
        the rounding: about 0.1 s for an 80 s mission)."""
        matrix = self.matrix
        for c in self.columns:
            s = self._slices[c.name]
            matrix[:, s] = rounded(matrix[:, s], c.storage)
        return self

    def save(self, path: str | Path) -> Path:
        """Write ``path`` (.npz) atomically, each column at its precision, encoded
        (:mod:`tetherland.sim.log_codec`)."""
        path = Path(path)
        if path.suffix != ".npz":
            raise ValueError(f"log files end in .npz, got '{path.name}'")
        components = np.ascontiguousarray(self.matrix.T)  # each row one time series
        arrays: dict[str, np.ndarray] = {}
        schema = []
        for c in self.columns:
            stored = to_storage(components[self._slices[c.name]], c.storage)
            arrays[c.name] = encode(stored)
            schema.append({"name": c.name, "width": c.width, "unit": c.unit, "doc": c.doc,
                           "integer": c.integer, "precision": c.storage.value,
                           "dtype": stored.dtype.name})  # fmt: skip
        meta = dict(self.metadata)
        meta["format_version"] = FORMAT_VERSION
        meta["rows"] = len(self)
        meta["schema"] = schema
        arrays[METADATA_KEY] = np.array(json.dumps(to_jsonable(meta), allow_nan=False))
        return atomic_write_with(path, lambda tmp: np.savez(tmp, **arrays))

    @classmethod
    def load(cls, path: str | Path) -> SimLog:
        """Read a log written by :meth:`save` (format 2) or by an earlier version (1).

        Raises
        ------
        ValueError
            For an unknown format or damaged column data (``np.load`` raises its own
            errors for a file that is no .npz).
        """
        with np.load(Path(path), allow_pickle=False) as npz:
            meta = json.loads(str(npz[METADATA_KEY]))
            version = meta.get("format_version")
            if version not in READABLE_VERSIONS:
                raise ValueError(
                    f"'{path}': log format {version} is not one of {READABLE_VERSIONS}"
                )
            schema = meta.pop("schema")
            columns = tuple(
                Column(c["name"], c["width"], c["unit"], c["doc"], c["integer"],
                       Precision(c["precision"]) if "precision" in c else None)
                for c in schema
            )  # fmt: skip
            n = int(meta.pop("rows")) if version >= 2 else int(npz[columns[0].name].shape[0])
            matrix = np.empty((n, row_width(columns)))
            log = cls(columns, matrix, meta)
            for c, entry in zip(columns, schema, strict=True):
                s = log._slices[c.name]
                if version >= 2:
                    matrix[:, s] = decode(npz[c.name], entry["dtype"], n, c.width)
                else:
                    matrix[:, s] = np.asarray(npz[c.name], dtype=float).reshape(n, c.width)
        return log


class LogWriter:
    """Preallocated row storage for a run (grows by doubling if a run outlives it).

    Rows are written whole, so the storage is left uninitialised (no NaN fill of the
    rows a run may never reach).

    Parameters
    ----------
    columns : tuple of Column
        Schema; rows are written whole, in this order, by :meth:`write`.
    capacity : int
        Rows to preallocate.
    """

    def __init__(self, columns: tuple[Column, ...], capacity: int) -> None:
        self.columns = columns
        self._width = row_width(columns)
        # the derived columns' room at the end of every row, so that :meth:`finish` hands
        # out the rows written without copying them (a copy cost about 0.1 s per 80 s
        # mission, 3 % of its CPU); rows go into the schema's part (``_rows``)
        self._matrix = np.empty((max(int(capacity), 1), self._width + row_width(DERIVED)))
        self._rows = self._matrix[:, : self._width]
        self._n = 0

    def __len__(self) -> int:
        return self._n

    @property
    def last_row(self) -> FloatArray:
        """The row written last, in schema order (a read-only view; empty before any)."""
        row = self._rows[self._n - 1] if self._n else self._rows[0, :0]
        view = row.view()
        view.setflags(write=False)
        return view

    def write(self, row: FloatArray) -> None:
        """Append one row (a copy of ``row``, the schema's width, in schema order)."""
        n = self._n
        if n == self._matrix.shape[0]:
            grown = np.empty((2 * n, self._matrix.shape[1]))
            grown[:n] = self._matrix
            self._matrix, self._rows = grown, grown[:, : self._width]
        self._rows[n] = row
        self._n = n + 1

    def finish(self, metadata: Mapping[str, Any], derived: bool = True, **geometry: Any) -> SimLog:
        """The log of the rows written so far (derived link angles added if ``derived``).

        Parameters
        ----------
        geometry
            ``p_A`` (3,), ``R_WA`` (3, 3) and ``r_att_B`` (3,) for the derived columns.
        """
        n = self._n
        if not derived:
            return SimLog(self.columns, self._rows[:n].copy(), dict(metadata))
        # the rows written, not copied: the writer never writes a row it has written again
        # (a grown buffer is a new one), so the log keeps its rows as they are
        matrix = self._matrix[:n]
        base = SimLog(self.columns, matrix[:, : self._width], dict(metadata))
        matrix[:, self._width], matrix[:, self._width + 1] = link_angles_from_log(
            base, **geometry
        )
        return SimLog(self.columns + DERIVED, matrix, base.metadata)


def link_angles_from_log(
    log: SimLog, *, p_A: FloatArray, R_WA: FloatArray, r_att_B: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """True (phi, delta) of the attachment point around the anchor for every row [rad]."""
    q = log["q_WB"]
    if len(log) == 0:
        return np.empty(0), np.empty(0)
    w, x, y, z = q.T
    r = np.asarray(r_att_B, dtype=float)
    # R_WB r for every row (quaternion rotation, vectorised)
    R = np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )
    rel = log["p_W"] + R @ r - np.asarray(p_A, dtype=float)
    d_A = rel @ np.asarray(R_WA, dtype=float)  # rows: R_WA^T rel
    phi = np.arctan2(d_A[:, 2], d_A[:, 0])
    delta = np.arctan2(-d_A[:, 1], np.hypot(d_A[:, 0], d_A[:, 2]))
    return phi, delta
