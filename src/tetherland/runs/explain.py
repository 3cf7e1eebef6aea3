"""Why a run failed: each failing check of the verdict as a record with a time, a phase and
the numbers behind it (a part and a force for a crash, a value and its limit otherwise).

:func:`explain` reads the verdict's ``summary.json`` document, the run's log (the plant's
truth) and its :class:`~tetherland.verdict.RunRecord`, nothing the robot believed. A crash
record of the judge (``summary["crash"]``: ``t``, ``phase``, ``part``, ``force_N``) is used
as it is; for a summary written before the judge gave one, the crash is the first logged
tick at which the frame's normal force exceeds ``verdict.crash_force`` (no part named).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from tetherland.config import Scenario
from tetherland.sim import SimLog
from tetherland.verdict import Outcome, RunRecord
from tetherland.verdict.judge import tolerances_of


@dataclass(frozen=True)
class Failure:
    """One failing check of a run's verdict.

    Attributes
    ----------
    outcome : str
        The :class:`~tetherland.verdict.Outcome` value of the check (``crashed``,
        ``landing_conditions``, ...).
    t : float or None
        When it happened [s] (None: not tied to a time, e.g. a run that was not flown).
    phase : str or None
        The method's phase at ``t`` (``"after_end"``: past the last phase).
    message : str
        One line a user can read.
    part : str or None
        Crash: the part that touched (None when the judge does not name it).
    force_N : float or None
        Crash: the normal force on the frame [N].
    condition : str or None
        Landing conditions: the condition, "1" to "5".
    measure : str or None
        The ``summary.json`` key of the measured value (``touchdown_speed_mps``, ...).
    value, limit : float or None
        The measured value and the limit it broke, in ``unit``.
    unit : str or None
    """

    outcome: str
    t: float | None
    phase: str | None
    message: str
    part: str | None = None
    force_N: float | None = None
    condition: str | None = None
    measure: str | None = None
    value: float | None = None
    limit: float | None = None
    unit: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready, without the fields that do not apply (None)."""
        return {k: v for k, v in asdict(self).items() if v is not None or k in ("t", "phase")}


def phase_at(phases: Sequence[Mapping[str, Any]], t: float | None) -> str:
    """The phase of a run's phase list (``summary.json``) at time ``t``; ``"all"`` for None,
    ``"after_end"`` past the end of the run."""
    if t is None:
        return "all"
    for p in phases:
        if p["start"] <= t < p["end"]:
            return str(p["name"])
    return "after_end"


def _phase_or_last(phases: Sequence[Mapping[str, Any]], t: float) -> str | None:
    """The phase at ``t``, or the last phase when ``t`` is the end of the run."""
    name = phase_at(phases, t)
    if name == "after_end" and phases and t <= phases[-1]["end"] + 1e-9:
        return str(phases[-1]["name"])
    return name if phases else None


CONDITION_MEASURES: Mapping[str, tuple[tuple[str, str, str], ...]] = {
    "1": (("position_error_m", "position", "m"),),
    "2": (("attitude_error_rad", "attitude", "rad"),),
    "3": (("touchdown_speed_mps", "speed", "m/s"),
          ("touchdown_angular_rate_rps", "angular_rate", "rad/s")),
    "4": (("touchdown_accel_mps2", "accel", "m/s^2"),
          ("touchdown_angular_accel_rps2", "angular_accel", "rad/s^2")),
    "5": (("slip_m", "slip", "m"), ("rest_speed_mps", "rest_speed", "m/s")),
}  # fmt: skip
"""Condition -> (summary key, :class:`~tetherland.analysis.LandingTolerances` field, unit);
(1)-(4) hold the judge's touchdown measures (:data:`~tetherland.verdict.judge.TOUCHDOWN_KEYS`)."""


def _crash(summary: Mapping[str, Any], log: SimLog, truth: Scenario) -> Failure:
    phases = summary.get("phases", [])
    limit = truth.verdict.crash_force
    judged = summary.get("crash")
    if isinstance(judged, Mapping):  # the judge's own crash record
        t, part, force = judged.get("t"), judged.get("part"), judged.get("force_N")
        phase = judged.get("phase") or (None if t is None else _phase_or_last(phases, t))
    else:
        force_W = np.nan_to_num(np.asarray(log["frame_force"], float).reshape(len(log), -1))
        over = np.flatnonzero(force_W.max(axis=1) > limit)
        k = int(over[0]) if over.size else len(log) - 1
        t, part, force = float(log["t"][k]), None, float(force_W[k].max())
        phase = _phase_or_last(phases, t)
    where = f" ({part})" if part else ""
    return Failure(
        Outcome.CRASHED.value, t, phase,
        f"crash at t = {t:.2f} s in {phase}: the frame{where} touched with "
        f"{force:.3g} N > verdict.crash_force = {limit:g} N",
        part=part, force_N=force, value=force, limit=limit, unit="N",
    )  # fmt: skip


def _touchdowns(landing: Mapping[str, Any]) -> Iterator[Mapping[str, Any]]:
    """The judged touchdowns in time order: the first (its measures at the top level of
    ``landing``, at t_L), then the bounces."""
    yield {"t": landing.get("t_L"), **landing}
    yield from landing.get("bounces", [])


def _conditions(summary: Mapping[str, Any], truth: Scenario) -> Iterator[Failure]:
    landing = summary["landing"]
    phases = summary.get("phases", [])
    tol = tolerances_of(truth)
    notes = landing.get("condition_notes", {})
    for n in landing.get("required_conditions", []):
        if landing["conditions"].get(n, True):
            continue
        found = False
        rest = landing.get("rest_interval_s")
        for touch in [landing] if n == "5" else _touchdowns(landing):
            # (5) is measured over the rest (from its start), (1)-(4) at a touchdown
            t = (rest[0] if rest else landing.get("t_L")) if n == "5" else touch.get("t")
            for key, name, unit in CONDITION_MEASURES[n]:
                value, limit = touch.get(key), getattr(tol, name)
                if isinstance(value, (int, float)) and value > limit:
                    found = True
                    yield Failure(
                        Outcome.LANDING_CONDITIONS.value, t,
                        None if t is None else _phase_or_last(phases, t),
                        f"landing condition ({n}): {key} = {value:.3g} {unit} > {limit:.3g} "
                        f"{unit}" + (f" at t = {t:.2f} s" if t is not None else ""),
                        condition=n, measure=key, value=float(value), limit=limit, unit=unit,
                    )  # fmt: skip
            if found:
                break
        if not found:  # e.g. (5): the rest was too short, or no lander rested on the surface
            t = landing.get("t_L")
            yield Failure(
                Outcome.LANDING_CONDITIONS.value, t,
                None if t is None else _phase_or_last(phases, t),
                f"landing condition ({n}): {notes.get(n, 'not met')}", condition=n,
            )  # fmt: skip


def _slack(summary: Mapping[str, Any], log: SimLog, record: RunRecord) -> Failure:
    value = summary["landing"].get("min_tension_N")
    phases = summary.get("phases", [])
    codes = [record.phase_codes[n] for n in record.tension_phases if n in record.phase_codes]
    in_phases = np.isin(np.asarray(log["phase"]).astype(int), codes)
    ticks = np.flatnonzero(in_phases & (np.asarray(log["tension"]) == value))
    t = float(log["t"][ticks[0]]) if ticks.size and value is not None else None
    return Failure(
        Outcome.SLACK_CABLE.value, t, None if t is None else _phase_or_last(phases, t),
        f"the cable went slack where the plan needs tension: least tension {value:.3g} N"
        + (f" at t = {t:.2f} s" if t is not None else ""),
        measure="min_tension_N", value=value, limit=0.0, unit="N",
    )  # fmt: skip


def _abort(summary: Mapping[str, Any], outcome: Outcome) -> Failure:
    """The phase the supervisor left to abort (its exit reason starts with ``abort``)."""
    phases = summary.get("phases", [])
    left = next((p for p in phases if str(p.get("exit_reason", "")).startswith("abort")), None)
    t = None if left is None else float(left["end"])
    reason = summary.get("abort_reason")
    why = (summary.get("safe_stop") or {}).get("why")
    text = "safe stop" if outcome is Outcome.SAFE_STOP else "aborted"
    return Failure(
        outcome.value, t, None if left is None else str(left["name"]),
        f"{text}" + (f" at t = {t:.2f} s in {left['name']}" if left is not None else "")
        + f": {reason}" + (f"; {why}" if why and outcome is Outcome.ABORTED else ""),
    )  # fmt: skip


def explain(summary: Mapping[str, Any], log: SimLog | None, record: RunRecord) -> list[Failure]:
    """Every failing check of a verdict, in the judge's order, so the first is the one that
    decided the outcome (empty for a success).

    Parameters
    ----------
    summary : mapping
        The verdict's ``summary.json`` document.
    log : SimLog or None
        The run's log (None: the run was not flown).
    record : RunRecord
        The run's record (the true scenario gives the limits).
    """
    if summary["success"]:
        return []
    if summary["outcome"] == Outcome.NO_RUN.value or log is None or not len(log):
        return [Failure(summary["outcome"], None, None, str(summary["reason"]))]
    truth = record.truth_scenario()
    phases = summary.get("phases", [])
    end = float(summary["sim_time_s"])
    at_end = _phase_or_last(phases, end)
    landing, takeoff, ret = summary["landing"], summary["takeoff"], summary["return"]
    out: list[Failure] = []
    if summary["status"] in ("diverged", "failed"):
        out.append(Failure(Outcome.SIM_FAILED.value, end, at_end,
                           f"the simulation {summary['status']} at t = {end:.2f} s"))  # fmt: skip
    if summary["crashed"]:
        out.append(_crash(summary, log, truth))
    if not landing.get("reached", False):
        clearance = landing.get("min_clearance_m")
        out.append(Failure(
            Outcome.NO_TOUCHDOWN.value, end, at_end,
            "no touchdown on the landing surface" + (
                "" if clearance is None else f"; closest approach {clearance:.3g} m"),
            measure="min_clearance_m", value=clearance, limit=0.0 if clearance else None,
            unit="m" if clearance is not None else None,
        ))  # fmt: skip
    elif not landing["all_conditions"]:
        out.extend(_conditions(summary, truth))
    tension = landing.get("min_tension_N")
    if record.expects.tension and tension is not None and not tension > 0.0:
        out.append(_slack(summary, log, record))
    if (summary.get("safe_stop") or {}).get("reached"):
        out.append(_abort(summary, Outcome.SAFE_STOP))
    elif summary.get("abort_reason") is not None:
        out.append(_abort(summary, Outcome.ABORTED))
    if landing.get("reached") and takeoff.get("required") and not takeoff.get("completed"):
        out.append(Failure(Outcome.NO_TAKEOFF.value, end, at_end,
                           f"takeoff not completed by the end of the run (t = {end:.2f} s)"))
    if takeoff.get("completed") and ret.get("required") and not ret.get("completed"):
        error = ret.get("position_error_m")
        limit = truth.verdict.return_position_error
        out.append(Failure(
            Outcome.NO_RETURN.value, end, at_end,
            "return not completed: " + ("the cable is still hooked at the end"
            if not ret.get("unhooked", True) else "not flown to the end" if error is None
            else f"ended {error:.3g} m from the start pad > {limit:g} m"),
            measure=None if error is None else "return.position_error_m", value=error,
            limit=None if error is None else limit, unit=None if error is None else "m",
        ))  # fmt: skip
    if not out:
        out.append(Failure(summary["outcome"], end, at_end, str(summary["reason"])))
    order = [o.value for o in Outcome]  # the judge's order: the first decides the outcome
    return sorted(out, key=lambda f: order.index(f.outcome) if f.outcome in order else len(order))
