"""The one judge of every run: touchdown, crash, slip and landing conditions (1)-(5).

:func:`judge` reads only the run's log (the plant's truth at every control tick) and its
:class:`~tetherland.verdict.RunRecord`, and measures against the *true* desired landing
point of the plant's scenario; the robot may have believed otherwise. The same rules
serve every landing method (docs/theory.md section 5):

* touchdown t_L: the first logged tick of the whole run at which the landing surface
  presses a lander with a normal force above ``verdict.touchdown_force`` (the plant's
  contact sensors filtered by partner geom, peak over the physics steps: a real touch,
  not a distance; the start pad and the ground do not count), whatever the robot
  declared; t_L- is the tick before (:mod:`tetherland.verdict.touchdown`);
* (1) ||p_RL(t_L) - p*_L||, p_RL = p - h_R z_B; (2) angle(z_B(t_L), z_S);
  (3) ||p'(t_L-)||, ||omega(t_L-)||; (4) ||p''(t_L-)|| from the true specific force and
  ||omega'(t_L-)|| from the two ticks before; (1)-(4) hold only if they hold at t_L and
  at every bounce (contact lost for at least ``sim.contact_time_constant`` and regained) up to
  the contact that starts the rest;
* (5) observed on the truth: the rest is the first interval after t_L in which the true
  total rotor thrust is below the motors-off level
  (:func:`~tetherland.config.verdict.motors_off_thrust`); it must last
  ``verdict.min_rest_time`` with a lander on the surface; the slip of p_RL along the
  surface (sliding; its settling along the normal is reported apart) is measured from
  t_L until spin-up, the speed from ``verdict.rest_settle_time`` after the rest begins;
* crash: a normal force above ``verdict.crash_force`` on any part of the vehicle but the
  landers (hub, cable mount, arms, legs, rotor guards: the log's ``frame_force``, the peak
  over the physics steps), at any time of the run, whatever the robot declared; the crash
  record names the first such tick, its part, the phase the log holds there and the peak
  force of that contact (:func:`crash_of`).

What a method must achieve beyond that (which conditions, a taut cable, a takeoff and a
return) is its :class:`~tetherland.verdict.Expectations`, stored in the record.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from tetherland import GRAVITY, __version__
from tetherland.analysis.conditions import (
    ConditionResult,
    LandingTolerances,
    condition_1,
    condition_2,
    condition_3,
    condition_4,
    condition_5_observed,
)
from tetherland.config import Scenario
from tetherland.config.verdict import motors_off_thrust
from tetherland.geometry import LandingGeometry
from tetherland.rotations import quat_to_rotmat, quat_to_rotmat_many
from tetherland.sim.log import RunStatus, SimLog
from tetherland.sim.mjcf import FRAME_PARTS
from tetherland.verdict.hooking import judge_hooking
from tetherland.verdict.record import RunRecord
from tetherland.verdict.touchdown import Touchdowns, find_touchdowns


class Outcome(enum.Enum):
    """What decided a run, in the order the judge checks (the first that applies)."""

    SUCCESS = "success"
    """Every expectation of the method was met."""
    NO_RUN = "no_run"
    """The run could not start (no plan, or an input error): nothing was flown."""
    SIM_FAILED = "sim_failed"
    """The physics diverged or a component raised an error during the run."""
    CRASHED = "crashed"
    """A part of the vehicle other than the landers (hub, mount, arms, legs, rotor guards)
    touched something."""
    SAFE_STOP = "safe_stop"
    """The supervisor detected a fault and reached its defined safe state (hover held,
    landed on the start pad, or motors off on the surface), at rest and without a crash."""
    ABORTED = "aborted"
    """The supervisor moved to a safe state (an operator abort, or a fault whose safe state
    was not verified reached)."""
    NO_TOUCHDOWN = "no_touchdown"
    """No touchdown on the landing surface in the whole run."""
    LANDING_CONDITIONS = "landing_conditions"
    """Touchdown happened, but a required landing condition (1)-(5) does not hold."""
    SLACK_CABLE = "slack_cable"
    """The cable went slack where the plan needs tension."""
    NO_TAKEOFF = "no_takeoff"
    """The takeoff after the landing was not completed."""
    NO_RETURN = "no_return"
    """The return to the start pad was not completed."""
    UNFINISHED = "unfinished"
    """The run ended before the method's end state."""

    @property
    def label(self) -> str:
        """The result in a word or two, as every command prints it: ``success``,
        ``safe stop``, ``crash``, ``not flown`` or, for every other outcome, ``failure``."""
        return _LABELS.get(self.value, "failure")


_LABELS = {"success": "success", "safe_stop": "safe stop", "crashed": "crash",
           "no_run": "not flown"}  # fmt: skip


@dataclass(frozen=True)
class Verdict:
    """The judged run: an outcome, every reason, and the ``summary.json`` document.

    Attributes
    ----------
    success : bool
    outcome : Outcome
        The first failing check (or SUCCESS).
    reasons : tuple of str
        Every failing check, in judging order (empty on success).
    summary : mapping
        The full JSON-ready verdict (``summary.json``): landing measures, takeoff and
        return, phases, times, switches, tolerances, timing, provenance.
    """

    success: bool
    outcome: Outcome
    reasons: tuple[str, ...]
    summary: Mapping[str, Any]

    @property
    def reason(self) -> str:
        """One line: ``"ok"`` or the reasons joined."""
        return "ok" if self.success else "; ".join(self.reasons)

    def to_dict(self) -> dict[str, Any]:
        """The ``summary.json`` document (a fresh dict)."""
        return dict(self.summary)


def tolerances_of(scenario: Scenario) -> LandingTolerances:
    """The landing tolerances of a scenario's ``[verdict]`` section (SI units)."""
    v = scenario.verdict
    return LandingTolerances(
        position=v.position_error,
        attitude=math.radians(v.attitude_error_deg),
        speed=v.touchdown_speed,
        angular_rate=v.touchdown_angular_rate,
        accel=v.touchdown_accel,
        angular_accel=v.touchdown_angular_accel,
        slip=v.rest_slip,
        rest_speed=v.rest_speed,
    )


def _z_axes(q: np.ndarray) -> np.ndarray:
    return quat_to_rotmat_many(q)[:, :, 2]


def _in(log: SimLog, record: RunRecord, names: tuple[str, ...]) -> np.ndarray:
    codes = [record.phase_codes[n] for n in names if n in record.phase_codes]
    return np.isin(log["phase"].astype(int), codes)


TOUCHDOWN_KEYS = {
    "position_error": "position_error_m",
    "attitude_error": "attitude_error_rad",
    "speed": "touchdown_speed_mps",
    "angular_rate": "touchdown_angular_rate_rps",
    "accel": "touchdown_accel_mps2",
    "angular_accel": "touchdown_angular_accel_rps2",
}
"""Summary keys of the measures of conditions (1)-(4) at a touchdown."""


def _touchdown_conditions(
    log: SimLog, k: int, p_RL: np.ndarray, z_B: np.ndarray, geo: LandingGeometry,
    tol: LandingTolerances,
) -> tuple[ConditionResult, ...]:  # fmt: skip
    """Conditions (1)-(4) at a touchdown at tick ``k``; t_L- is the tick before."""
    k_prev = max(k - 1, 0)
    t = log["t"]
    dt = float(t[1] - t[0]) if len(t) > 1 else 1.0
    R_prev = quat_to_rotmat(log["q_WB"][k_prev])
    a_W = R_prev @ log["specific_force_B"][k_prev] + np.array([0.0, 0.0, -GRAVITY])
    w = log["omega_B"]
    w_dot = (w[k_prev] - w[max(k_prev - 1, 0)]) / dt
    return (
        condition_1(p_RL[k], geo.p_L, tol),
        condition_2(z_B[k], geo.surface.z_S, tol),
        condition_3(log["v_W"][k_prev], w[k_prev], tol),
        condition_4(a_W, w_dot, tol),
    )


def _measures(conditions: tuple[ConditionResult, ...]) -> dict[str, float]:
    return {
        TOUCHDOWN_KEYS[m.name]: m.value
        for c in conditions
        for m in c.measures
        if m.name in TOUCHDOWN_KEYS
    }


def _rest_condition(
    log: SimLog, found: Touchdowns, p_RL: np.ndarray, geo: LandingGeometry, truth: Scenario
) -> tuple[dict[str, Any], str | None]:
    """Condition (5) on the truth: the measures, and why it fails (None if it holds).

    The slip and the settle are measured from the touchdown until spin-up, the rest speed
    from ``verdict.rest_settle_time`` after the rest begins; the rest must last
    ``verdict.min_rest_time`` with a lander on the surface.
    """
    cfg = truth.verdict
    rest, k_L = found.rest, found.first
    assert k_L is not None
    if rest is None:
        none = {"slip_m": None, "settle_m": None, "rest_speed_mps": None}
        return none | {"rest_interval_s": None}, (
            "no rest: the true rotor thrust never went below the motors-off level "
            f"({motors_off_thrust(truth.vehicle):.3g} N) after the touchdown"
        )
    t = log["t"]
    ticks = np.arange(rest.start, rest.end)
    settled = ticks[t[ticks] >= rest.t_start + cfg.rest_settle_time]
    result = condition_5_observed(
        p_RL[k_L : max(rest.end, k_L + 1)], log["v_W"][settled], tolerances_of(truth),
        geo.surface.z_S,
    )  # fmt: skip
    m = {x.name: x.value for x in result.measures}
    out = {
        "slip_m": m["slip"],
        "settle_m": m["settle"],
        "rest_speed_mps": m["rest_speed"] if settled.size else None,
        "rest_interval_s": [rest.t_start, rest.t_end],
    }
    if rest.duration < cfg.min_rest_time:
        return out, (
            f"the rest lasted {rest.duration:.3g} s < verdict.min_rest_time = "
            f"{cfg.min_rest_time:g} s (true thrust below the motors-off level)"
        )
    if found.rest_contact is None:
        return out, "no lander on the landing surface during the rest"
    if not result.holds:
        failed = [x for x in result.measures if not x.ok]
        return out, ", ".join(f"{x.name} {x.value:.3g} {x.unit} > {x.limit:g}" for x in failed)
    return out, None


def _landing(log: SimLog, record: RunRecord, truth: Scenario) -> dict[str, Any]:
    cfg = truth.verdict
    tol = tolerances_of(truth)
    geo = LandingGeometry.from_scenario(truth)
    found = find_touchdowns(
        log, cfg.touchdown_force, motors_off_thrust(truth.vehicle), truth.sim.contact_time_constant
    )
    z_B = _z_axes(log["q_WB"])
    p_RL = log["p_W"] - geo.h_R * z_B
    if found.first is None:
        return {"reached": False, "min_clearance_m": _min_clearance(p_RL, geo, truth)}
    k = found.first
    t = log["t"]
    judged = {j: _touchdown_conditions(log, j, p_RL, z_B, geo, tol) for j in found.judged}
    bounces = [
        {"t": float(t[j]), **_measures(c), "conditions": {str(x.number): x.holds for x in c}}
        for j, c in judged.items()
        if j != k
    ]
    rest, why_5 = _rest_condition(log, found, p_RL, geo, truth)
    notes: dict[str, str] = {}
    conditions = {}
    for n in (1, 2, 3, 4):
        missed = [j for j, c in judged.items() if not c[n - 1].holds]
        conditions[str(n)] = not missed
        if missed and missed[0] != k:
            notes[str(n)] = f"missed at the bounce at t = {t[missed[0]]:.3f} s"
    conditions["5"] = why_5 is None
    if why_5 is not None:
        notes["5"] = why_5
    required = record.expects.required_conditions
    return {
        "reached": True,
        "t_L": float(t[k]),
        **_measures(judged[k]),
        "bounces": bounces,
        "rest_contact_t": None if found.rest_contact is None else float(t[found.rest_contact]),
        **rest,
        **_tension(log, record, cfg.touchdown_force),
        "conditions": conditions,
        "condition_notes": notes,
        "required_conditions": [str(n) for n in required],
        "all_conditions": all(conditions[str(n)] for n in required),
    }


def _tension(log: SimLog, record: RunRecord, contact_force: float) -> dict[str, float | None]:
    """Least true tension where the plan needs it while airborne, and over every tethered
    phase [N] (None: no such tick)."""
    if not record.tension_phases:
        return {"min_tension_N": None, "min_tension_all_N": None}
    # the cable must be taut during the tethered maneuvers wherever the vehicle flies on
    # a plan that needs tension: not while the landers carry it (on a gentle slope
    # friction alone may hold it and the cable slackens), nor where the plan itself is
    # slack (flat ground)
    min_tension = record.belief_scenario().planner.min_tension
    airborne = np.nan_to_num(log["lander_forces"]).max(axis=1) <= contact_force
    planned = _in(log, record, record.tension_phases) & airborne
    if "diag.ff_tension" in log:
        planned &= np.nan_to_num(log["diag.ff_tension"]) >= min_tension
    tethered = _in(log, record, record.tethered_phases)
    return {
        "min_tension_N": float(log["tension"][planned].min()) if planned.any() else None,
        "min_tension_all_N": float(log["tension"][tethered].min()) if tethered.any() else None,
    }


def _min_clearance(p_RL: np.ndarray, geo: LandingGeometry, truth: Scenario) -> float | None:
    """Least height of p_RL above the surface plane over the ticks above the simulated
    patch (the start pad and the ground lie outside it) [m]; None if never above it."""
    d = p_RL - geo.surface.origin
    over = (np.abs(d @ geo.surface.x_S) <= truth.surface.extent) & (
        np.abs(d @ geo.surface.y_S) <= truth.surface.extent
    )
    return float((d[over] @ geo.surface.z_S).min()) if over.any() else None


def crash_of(log: SimLog, record: RunRecord, crash_force: float) -> dict[str, Any] | None:
    """The run's first crash from the plant's truth, or None.

    The crash starts at the first logged tick whose ``frame_force`` (the largest normal
    force on any part but the landers over the physics steps since the tick before)
    exceeds ``crash_force``; it lasts while the following ticks do. Returns ``t`` (that
    tick [s]: the contact began within the control period ending there), ``phase`` (the
    name of the phase code the log holds at that tick, for naming only; None if the method
    has no such code), ``part`` (the geom the force acted on, from the log's
    ``frame_part`` and its metadata ``frame_parts``; None for a log without them) and
    ``force_N`` (the peak of ``frame_force`` over the contact [N]).
    """
    if not len(log):
        return None
    force = np.nan_to_num(np.asarray(log["frame_force"], dtype=float))
    over = force > crash_force
    if not over.any():
        return None
    k = int(np.argmax(over))
    end = k + int(np.argmin(over[k:])) if not over[k:].all() else len(log)
    names = {code: name for name, code in record.phase_codes.items()}
    code = log["phase"][k]
    part = None
    if "frame_part" in log:
        parts = log.metadata.get("frame_parts", FRAME_PARTS)
        j = log["frame_part"][k]
        if np.isfinite(j) and 0 <= int(j) < len(parts):
            part = str(parts[int(j)])
    return {
        "t": float(log["t"][k]),
        "phase": names.get(int(code)) if np.isfinite(code) else None,
        "part": part,
        "force_N": float(force[k:end].max()),
    }


def _takeoff(log: SimLog, record: RunRecord, geo: LandingGeometry) -> dict[str, Any]:
    if not record.expects.takeoff:
        return {"required": False}
    t_released = record.times.get("t_released")
    if t_released is None or record.takeoff_target is None:
        return {"required": True, "completed": False}
    target = record.takeoff_target
    k = min(int(np.searchsorted(log["t"], t_released)), len(log) - 1)
    phi = float(log["link_phi"][k]) if "link_phi" in log else math.nan
    z_A = geo.R_WA.T @ _z_axes(log["q_WB"][k : k + 1])[0]
    theta = math.atan2(z_A[0], z_A[2])
    during = _in(log, record, ("tethered_takeoff",))
    return {
        "required": True,
        "completed": True,
        "phi_error_rad": abs(phi - target[0]),
        "theta_A_error_rad": abs(theta - target[2]),
        "min_tension_N": float(log["tension"][during].min()) if during.any() else None,
    }


def _return(log: SimLog, record: RunRecord, truth: Scenario) -> dict[str, Any]:
    if not record.expects.return_home:
        return {"required": False}
    if "t_done" not in record.times or record.home_pad_W is None:
        return {"required": True, "completed": False}
    h_R = truth.vehicle.h_R
    z_B = _z_axes(log["q_WB"][-1:])[0]
    p_RL = log["p_W"][-1] - h_R * z_B
    pad = np.asarray(record.home_pad_W) - h_R * np.array([0.0, 0.0, 1.0])
    error = float(np.linalg.norm(p_RL - pad))
    unhooked = not bool(log["hook"][-1]) if "hook" in log else True
    return {
        "required": True,
        "completed": unhooked and error <= truth.verdict.return_position_error,
        "unhooked": unhooked,
        "position_error_m": error,
        "speed_mps": float(np.linalg.norm(log["v_W"][-1])),
    }


def judge(log: SimLog, record: RunRecord) -> Verdict:
    """Judge one run from its log and record (see the module docstring).

    Parameters
    ----------
    log : SimLog
        The run's log (plant truth, every control tick).
    record : RunRecord
        What the method reported and expects.

    Returns
    -------
    Verdict
        Its ``summary`` is the run's ``summary.json``.
    """
    truth = record.truth_scenario()
    geo = LandingGeometry.from_scenario(truth)
    tol = tolerances_of(truth)
    status = RunStatus(log.metadata.get("status", RunStatus.COMPLETED.value))
    landing = _landing(log, record, truth) if len(log) else {"reached": False}
    takeoff = _takeoff(log, record, geo)
    ret = _return(log, record, truth)
    crash = crash_of(log, record, truth.verdict.crash_force)
    crashed = crash is not None
    sim_time = float(log["t"][-1]) if len(log) else 0.0
    checks: list[tuple[Outcome, str]] = []
    if status in (RunStatus.DIVERGED, RunStatus.FAILED):
        message = log.metadata.get("message", "")
        checks.append((Outcome.SIM_FAILED, f"run {status.value}: {message}"))
    if crash is not None:
        checks.append((Outcome.CRASHED,
                       f"crash: the {crash['part'] or 'frame'} touched something at t = "
                       f"{crash['t']:.3f} s ({crash['force_N']:.3g} N)"))  # fmt: skip
    if not landing.get("reached", False):
        checks.append((Outcome.NO_TOUCHDOWN, "no touchdown on the landing surface"))
    elif not landing["all_conditions"]:
        checks.append((Outcome.LANDING_CONDITIONS, _conditions_reason(landing)))
    if record.expects.tension and not (
        landing.get("min_tension_N") is None or landing["min_tension_N"] > 0.0
    ):
        checks.append((Outcome.SLACK_CABLE, "cable went slack where the plan needs tension"))
    safe_stop = _safe_stop(log, record, truth)
    if safe_stop["reached"]:
        checks.append((Outcome.SAFE_STOP,
                       f"safe stop ({record.safe_state}): {record.abort_reason}"))  # fmt: skip
    elif record.abort_reason is not None:
        why = f"; {safe_stop['why']}" if safe_stop.get("why") else ""
        checks.append((Outcome.ABORTED, f"aborted: {record.abort_reason}{why}"))
    if landing.get("reached") and takeoff.get("required") and not takeoff.get("completed"):
        checks.append((Outcome.NO_TAKEOFF, "takeoff not completed"))
    if takeoff.get("completed") and ret.get("required") and not ret.get("completed"):
        if not ret.get("unhooked", True):
            why = "the cable is still hooked at the end"
        elif "position_error_m" in ret:
            why = (
                f"ended {ret['position_error_m']:.3g} m from the start pad (tolerance "
                f"{truth.verdict.return_position_error:g} m)"
            )
        else:
            why = "not flown to the end"
        checks.append((Outcome.NO_RETURN, f"return not completed: {why}"))
    if not record.finished and not checks:
        checks.append((Outcome.UNFINISHED, f"the run did not finish ({status.value})"))
    order = list(Outcome)
    checks.sort(key=lambda c: order.index(c[0]))
    success = not checks
    outcome = Outcome.SUCCESS if success else checks[0][0]
    reasons = tuple(r for _, r in checks)
    summary = {
        "success": success,
        "outcome": outcome.value,
        "reason": "ok" if success else "; ".join(reasons),
        "method": record.method,
        "scenario": truth.name,
        "controller": record.controller,
        "seed": record.seed,
        "status": status.value,
        "aborted": record.abort_reason is not None,
        "abort_reason": record.abort_reason,
        "safe_stop": safe_stop,
        "crashed": crashed,
        "crash": crash,
        "phases": [p.to_dict() for p in record.phases],
        "times": dict(record.times),
        "hook": _hook(log, record),
        "hooking": (
            None if record.hook_attempts is None or "hook_p_W" not in log
            else judge_hooking(log, record, truth).to_dict()
        ),
        "landing": landing,
        "takeoff": takeoff,
        "return": ret,
        "switches": [s.to_dict() for s in record.switches],
        "tolerances": {
            "position_m": tol.position,
            "attitude_rad": tol.attitude,
            "speed_mps": tol.speed,
            "angular_rate_rps": tol.angular_rate,
            "accel_mps2": tol.accel,
            "slip_m": tol.slip,
        },
        "sim_time_s": sim_time,
        "wall_time_s": record.wall_time_s,
        "real_time_factor": sim_time / record.wall_time_s if record.wall_time_s > 0 else None,
        "version": __version__,
        "provenance": dict(record.provenance),
    }
    return Verdict(success=success, outcome=outcome, reasons=reasons, summary=summary)


def _conditions_reason(landing: Mapping[str, Any]) -> str:
    """``landing condition(s) 1, 5 not met`` with the judge's notes, e.g. why (5) failed."""
    failed = [n for n in landing["required_conditions"] if not landing["conditions"][n]]
    notes = landing.get("condition_notes", {})
    why = "; ".join(f"({n}) {notes[n]}" for n in failed if n in notes)
    return f"landing condition(s) {', '.join(failed)} not met" + (f": {why}" if why else "")


OPERATOR_ABORT = "operator abort"
"""Prefix of the abort reason of an operator abort (never a safe stop: nothing failed)."""


def _safe_stop(log: SimLog, record: RunRecord, truth: Scenario) -> dict[str, Any]:
    """Did a fault abort end in the supervisor's safe state, at rest, without a crash?"""
    reason = record.abort_reason
    if reason is None or reason.startswith(OPERATOR_ABORT):
        return {"reached": False}
    if record.safe_state is None:
        return {"reached": False, "why": "no safe state reached by the end of the run"}
    speed = float(np.linalg.norm(log["v_W"][-1])) if len(log) else math.nan
    crashed = crash_of(log, record, truth.verdict.crash_force) is not None
    limit = truth.verdict.safe_stop_speed
    out: dict[str, Any] = {"state": record.safe_state, "final_speed_mps": speed}
    if crashed:
        return out | {"reached": False, "why": "crashed"}
    if not speed <= limit:
        return out | {"reached": False, "why": f"final speed {speed:.3g} m/s > {limit:g} m/s"}
    return out | {"reached": True}


def _hook(log: SimLog, record: RunRecord) -> dict[str, Any] | None:
    if record.hook_attempts is None:
        return None
    events = [e for e in log.metadata.get("events", []) if e.get("source") == "hook"]
    return {
        "attempts": record.hook_attempts,
        "events": [{"t": e["t"], "kind": e["kind"]} for e in events],
    }


def not_flown(record: RunRecord, reason: str) -> Verdict:
    """The verdict of a run that could not start (no plan): nothing to measure."""
    summary = {
        "success": False,
        "outcome": Outcome.NO_RUN.value,
        "reason": reason,
        "method": record.method,
        "scenario": str(record.truth.get("name", "custom")),
        "controller": record.controller,
        "seed": record.seed,
        "status": None,
        "aborted": False,
        "abort_reason": None,
        "safe_stop": {"reached": False},
        "crashed": False,
        "crash": None,
        "landing": {"reached": False},
        "takeoff": {"required": record.expects.takeoff},
        "return": {"required": record.expects.return_home},
        "sim_time_s": 0.0,
        "wall_time_s": record.wall_time_s,
        "real_time_factor": None,
        "version": __version__,
        "provenance": dict(record.provenance),
    }
    return Verdict(success=False, outcome=Outcome.NO_RUN, reasons=(reason,), summary=summary)
