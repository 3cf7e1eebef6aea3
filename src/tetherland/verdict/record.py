"""The run record: what the judge needs of a run besides its log (``run.json``).

A run directory holds the log (``log.npz``: the plant's truth every control tick) and this
record: the landing method, the plans, the key times and phases the method reported, and
the true and believed scenarios. :func:`tetherland.verdict.judge` recomputes the verdict
from these two alone, so a saved run can be re-judged (``tetherland judge RUN_DIR``).
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from tetherland.config import Scenario, scenario_from_dict
from tetherland.errors import ConfigError, TetherlandError
from tetherland.io import atomic_write_json

RECORD_FORMAT = "tetherland-run"
"""Value of the ``format`` key of every ``run.json``."""
RECORD_VERSION = 1
"""Version of the ``run.json`` layout; a reader refuses other versions."""
RECORD_FILE = "run.json"
"""File name of the run record in a run directory."""


class RunRecordError(TetherlandError):
    """A run directory has no readable run record (one-line message)."""


@dataclass(frozen=True)
class PhaseSpan:
    """One phase of the run: its name, when it started and ended [s], and why it ended."""

    name: str
    start: float
    end: float
    exit_reason: str

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class SwitchSpan:
    """One controller switch (6.6.3) with its command jump."""

    t: float
    from_mode: str
    to_mode: str
    thrust_jump_N: float
    rotor_speed_jump_radps: float

    def to_dict(self) -> dict[str, Any]:
        return {
            "t": self.t,
            "from": self.from_mode,
            "to": self.to_mode,
            "thrust_jump_N": self.thrust_jump_N,
            "rotor_speed_jump_radps": self.rotor_speed_jump_radps,
        }


@dataclass(frozen=True)
class Expectations:
    """What a landing method promises, and so what the judge requires of its run.

    Attributes
    ----------
    required_conditions : tuple of int
        Landing conditions (1)-(5) that must hold for a success. The contact-free method
        cannot meet (4) on a slope (it touches down accelerating, Table 6.1), so it
        requires (1), (2), (3), (5); the tethered method requires all five.
    tension : bool
        The cable must stay taut where the plan needs tension while airborne.
    takeoff : bool
        The run must take off again after the landing.
    return_home : bool
        The run must end landed on its start pad.
    """

    required_conditions: tuple[int, ...] = (1, 2, 3, 4, 5)
    tension: bool = False
    takeoff: bool = False
    return_home: bool = False


@dataclass(frozen=True)
class RunRecord:
    """Everything about a run that its log does not hold (see the module docstring).

    Attributes
    ----------
    method : str
        Registered landing-method name (``"tethered"``, ``"free-flight"``).
    seed : int
        Seed of the sensor noise and disturbances.
    controller : str or None
        Controller used (tethered: ``"hierarchical"`` or ``"dfl"``).
    truth, belief : mapping
        The scenario the plant simulated and the one the robot believed (``model_dump``).
    expects : Expectations
        What the judge requires of this method.
    phase_codes : mapping of str to int
        The method's phase names and the codes its log's ``phase`` column holds.
    tension_phases : tuple of str
        Airborne tethered maneuvers in which the cable must be taut where the plan needs
        tension (landing and takeoff tracking).
    tethered_phases : tuple of str
        Every phase under tethered control (for the informative least tension).
    phases : tuple of PhaseSpan
        The method's phases in time order.
    times : mapping of str to float
        Key instants the method reported (t_tethered, t_L, t_G, t_T, t_released, t_done,
        t_maneuver, t_motors_off, ...) [s].
    abort_reason : str or None
        Why the supervisor went to a safe state, if it did.
    safe_state : str or None
        The safe state the supervisor reached after an abort: ``"hover"`` (safe hover
        held), ``"landed"`` (landed in free flight on the start pad) or ``"motors_off"``
        (stayed put on the surface with the motors off).
    finished : bool
        The method reached its planned end state.
    takeoff_target : (4,) tuple or None
        Planned final output [phi, delta, theta_A, psi] of the takeoff [rad].
    home_pad_W : (3,) tuple or None
        Start-pad position of the centre of mass, F_W [m] (return check).
    hook_attempts : int or None
        Hooking passes flown.
    switches : tuple of SwitchSpan
    plans : mapping
        Summaries of the plans the method flew (status, cost, duration, attempts).
    wall_time_s : float
        Wall-clock time of the closed loop [s].
    provenance : mapping
        How the run was produced (version, commit, command, scenario, seed).
    """

    method: str
    seed: int
    truth: Mapping[str, Any]
    belief: Mapping[str, Any]
    expects: Expectations
    controller: str | None = None
    phase_codes: Mapping[str, int] = field(default_factory=dict)
    tension_phases: tuple[str, ...] = ()
    tethered_phases: tuple[str, ...] = ()
    phases: tuple[PhaseSpan, ...] = ()
    times: Mapping[str, float] = field(default_factory=dict)
    abort_reason: str | None = None
    safe_state: str | None = None
    finished: bool = False
    takeoff_target: tuple[float, ...] | None = None
    home_pad_W: tuple[float, float, float] | None = None
    hook_attempts: int | None = None
    switches: tuple[SwitchSpan, ...] = ()
    plans: Mapping[str, Any] = field(default_factory=dict)
    wall_time_s: float = 0.0
    provenance: Mapping[str, Any] = field(default_factory=dict)

    def truth_scenario(self) -> Scenario:
        """The plant's scenario, validated (:class:`RunRecordError` naming ``truth``)."""
        return _scenario(self.truth, "truth")

    def belief_scenario(self) -> Scenario:
        """The believed scenario, validated (:class:`RunRecordError` naming ``belief``)."""
        return _scenario(self.belief, "belief")

    # ------------------------------------------------------------------ JSON
    def to_dict(self) -> dict[str, Any]:
        """JSON-ready, with the format tag and version."""
        return {
            "format": RECORD_FORMAT,
            "version": RECORD_VERSION,
            "method": self.method,
            "seed": self.seed,
            "controller": self.controller,
            "expects": asdict(self.expects),
            "phase_codes": {k: int(v) for k, v in self.phase_codes.items()},
            "tension_phases": list(self.tension_phases),
            "tethered_phases": list(self.tethered_phases),
            "phases": [p.to_dict() for p in self.phases],
            "times": {k: float(v) for k, v in self.times.items()},
            "abort_reason": self.abort_reason,
            "safe_state": self.safe_state,
            "finished": self.finished,
            "takeoff_target": None if self.takeoff_target is None else list(self.takeoff_target),
            "home_pad_W": None if self.home_pad_W is None else list(self.home_pad_W),
            "hook_attempts": self.hook_attempts,
            "switches": [s.to_dict() for s in self.switches],
            "plans": dict(self.plans),
            "wall_time_s": self.wall_time_s,
            "provenance": dict(self.provenance),
            "truth": dict(self.truth),
            "belief": dict(self.belief),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> RunRecord:
        """Inverse of :meth:`to_dict` (raises :class:`RunRecordError` on another format)."""
        if data.get("format") != RECORD_FORMAT:
            raise RunRecordError("not a tetherland run record (no 'format': 'tetherland-run')")
        if data.get("version") != RECORD_VERSION:
            raise RunRecordError(
                f"run record version {data.get('version')!r} is not supported "
                f"(this tetherland reads version {RECORD_VERSION})"
            )
        try:
            record = cls(
                method=_text(data["method"], "method"),
                seed=_seed(data["seed"]),
                controller=data.get("controller"),
                truth=_mapping(data["truth"], "truth"),
                belief=_mapping(data["belief"], "belief"),
                expects=Expectations(
                    required_conditions=tuple(
                        _condition(c) for c in data["expects"]["required_conditions"]
                    ),
                    tension=_flag(data["expects"]["tension"], "expects.tension"),
                    takeoff=_flag(data["expects"]["takeoff"], "expects.takeoff"),
                    return_home=_flag(data["expects"]["return_home"], "expects.return_home"),
                ),
                phase_codes={
                    str(k): _integer(v, "phase_codes") for k, v in data["phase_codes"].items()
                },
                tension_phases=tuple(data.get("tension_phases", ())),
                tethered_phases=tuple(data.get("tethered_phases", ())),
                phases=tuple(
                    PhaseSpan(
                        str(p["name"]),
                        _number(p["start"], "phases.start"),
                        _number(p["end"], "phases.end"),
                        str(p["exit_reason"]),
                    )
                    for p in data.get("phases", [])
                ),
                times={str(k): _number(v, f"times.{k}") for k, v in data.get("times", {}).items()},
                abort_reason=data.get("abort_reason"),
                safe_state=data.get("safe_state"),
                finished=_flag(data.get("finished", False), "finished"),
                takeoff_target=_vector(data.get("takeoff_target"), "takeoff_target", 4),
                home_pad_W=_vector(data.get("home_pad_W"), "home_pad_W", 3),
                hook_attempts=None
                if data.get("hook_attempts") is None
                else _integer(data["hook_attempts"], "hook_attempts"),
                switches=tuple(
                    SwitchSpan(
                        _number(s["t"], "switches.t"),
                        str(s["from"]),
                        str(s["to"]),
                        _number(s["thrust_jump_N"], "switches.thrust_jump_N", None),
                        _number(s["rotor_speed_jump_radps"], "switches.rotor_speed_jump", None),
                    )
                    for s in data.get("switches", [])
                ),
                plans=_mapping(data.get("plans", {}), "plans"),
                wall_time_s=_number(data.get("wall_time_s", 0.0), "wall_time_s"),
                provenance=_mapping(data.get("provenance", {}), "provenance"),
            )
        except (KeyError, TypeError, ValueError, AttributeError) as err:
            raise RunRecordError(f"run record is incomplete or malformed: {err!r}") from None
        return record

    def save(self, directory: str | Path) -> Path:
        """Write ``run.json`` into ``directory`` atomically."""
        return atomic_write_json(Path(directory) / RECORD_FILE, self.to_dict())

    @classmethod
    def load(cls, directory: str | Path) -> RunRecord:
        """Read ``run.json`` from a run directory (one-line :class:`RunRecordError` if absent)."""
        path = Path(directory) / RECORD_FILE
        if not path.is_file():
            raise RunRecordError(
                f"{directory}: no {RECORD_FILE} (runs written before tetherland kept run "
                "records cannot be re-judged; run the mission again)"
            )
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as err:  # JSON and UTF-8 decoding errors are ValueErrors
            raise RunRecordError(f"{path}: unreadable run record ({err})") from None
        except RecursionError:
            raise RunRecordError(f"{path}: unreadable run record (nested too deeply)") from None
        return cls.from_dict(data)


def _scenario(data: Mapping[str, Any], what: str) -> Scenario:
    try:
        return scenario_from_dict(dict(data), str(data.get("name", "custom")))
    except ConfigError as err:
        raise RunRecordError(f"run record: {what}: {err}") from None


def _number(value: Any, what: str, low: float | None = 0.0, high: float = math.inf) -> float:
    """A finite number in [low, high] (no boolean), else :class:`RunRecordError`."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise RunRecordError(f"run record: {what} must be a number (got {value!r:.40})")
    x = float(value)
    if not math.isfinite(x) or (low is not None and x < low) or x > high:
        span = f"[{low:g}, {high:g}]" if low is not None else "finite"
        raise RunRecordError(f"run record: {what} = {x!r} is out of range ({span})")
    return x


def _integer(value: Any, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise RunRecordError(f"run record: {what} must be an integer >= 0 (got {value!r:.40})")
    return value


def _condition(value: Any) -> int:
    if _integer(value, "expects.required_conditions") not in (1, 2, 3, 4, 5):
        raise RunRecordError(f"run record: landing condition {value} is not one of 1-5")
    return value


def _seed(value: Any) -> int:
    return _integer(value, "seed")


def _flag(value: Any, what: str) -> bool:
    if not isinstance(value, bool):
        raise RunRecordError(f"run record: {what} must be true or false (got {value!r:.40})")
    return value


def _text(value: Any, what: str) -> str:
    if not isinstance(value, str):
        raise RunRecordError(f"run record: {what} must be text (got {value!r:.40})")
    return value


def _mapping(value: Any, what: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        raise RunRecordError(f"run record: {what} must be a table (got {value!r:.40})")
    return value


def _vector(value: Any, what: str, n: int) -> tuple[float, ...] | None:
    if value is None:
        return None
    if not isinstance(value, list) or len(value) != n:
        raise RunRecordError(f"run record: {what} must be {n} numbers (got {value!r:.40})")
    return tuple(_number(x, what, None) for x in value)
