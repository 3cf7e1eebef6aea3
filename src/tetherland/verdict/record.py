"""The run record: what the judge needs of a run besides its log (``run.json``).

A run directory holds the log (``log.npz``: the plant's truth every control tick) and this
record: the landing method, the plans, the key times and phases the method reported, and
the true and believed scenarios. :func:`tetherland.verdict.judge` recomputes the verdict
from these two alone, so a saved run can be re-judged (``tetherland judge RUN_DIR``).
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from tetherland.config import Scenario, scenario_from_dict
from tetherland.errors import TetherlandError
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
        """The plant's scenario, validated."""
        return scenario_from_dict(dict(self.truth), str(self.truth.get("name", "custom")))

    def belief_scenario(self) -> Scenario:
        """The believed scenario, validated."""
        return scenario_from_dict(dict(self.belief), str(self.belief.get("name", "custom")))

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
            return cls(
                method=str(data["method"]),
                seed=int(data["seed"]),
                controller=data.get("controller"),
                truth=data["truth"],
                belief=data["belief"],
                expects=Expectations(
                    required_conditions=tuple(data["expects"]["required_conditions"]),
                    tension=bool(data["expects"]["tension"]),
                    takeoff=bool(data["expects"]["takeoff"]),
                    return_home=bool(data["expects"]["return_home"]),
                ),
                phase_codes={str(k): int(v) for k, v in data["phase_codes"].items()},
                tension_phases=tuple(data.get("tension_phases", ())),
                tethered_phases=tuple(data.get("tethered_phases", ())),
                phases=tuple(PhaseSpan(**p) for p in data.get("phases", [])),
                times={k: float(v) for k, v in data.get("times", {}).items()},
                abort_reason=data.get("abort_reason"),
                safe_state=data.get("safe_state"),
                finished=bool(data.get("finished", False)),
                takeoff_target=_tuple(data.get("takeoff_target")),
                home_pad_W=_tuple(data.get("home_pad_W")),
                hook_attempts=data.get("hook_attempts"),
                switches=tuple(
                    SwitchSpan(
                        s["t"], s["from"], s["to"], s["thrust_jump_N"],
                        s["rotor_speed_jump_radps"],
                    )
                    for s in data.get("switches", [])
                ),
                plans=data.get("plans", {}),
                wall_time_s=float(data.get("wall_time_s", 0.0)),
                provenance=data.get("provenance", {}),
            )
        except (KeyError, TypeError, ValueError) as err:
            raise RunRecordError(f"run record is incomplete or malformed: {err!r}") from None

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
            data = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError) as err:
            raise RunRecordError(f"{path}: unreadable run record ({err})") from None
        return cls.from_dict(data)


def _tuple(v: Any) -> Any:
    return None if v is None else tuple(float(x) for x in v)

