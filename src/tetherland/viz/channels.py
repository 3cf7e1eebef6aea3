"""What the viewers receive: topics, schemas and the publisher shared by file and live.

=====================  ========================  ==========================================
topic                  schema                    content (one message per control tick
                                                 unless noted)
=====================  ========================  ==========================================
``/tf``                foxglove.FrameTransforms  world -> body (truth), world ->
                                                 body_estimated (UKF), world -> anchor
``/scene``             foxglove.SceneUpdate      surface or pipe, ground, anchor, landing
                                                 point, planned paths, vehicle models (at
                                                 t = 0 and every ``SCENE_PERIOD``)
``/cable``             foxglove.SceneUpdate      the cable, coloured by its tension
``/angles/<name>``     tetherland.Angle (JSON)   phi, delta, theta_A, psi: desired, nominal,
                                                 actual, estimated [deg]
``/rotor_thrusts``     tetherland.RotorThrusts   f_1..f_4 actual, nominal, commanded [N]
``/tension``           tetherland.Tension        f_L actual, estimated, nominal [N]
``/mission/state``     tetherland.MissionState   phase code and name, control mode, hook
``/mission/events``    foxglove.Log              phase changes, hook events, aborts, the
                                                 verdict (as they happen)
``/verdict``           tetherland.Verdict        the landing verdict (once, at the end)
=====================  ========================  ==========================================

Time stamps are simulation time from 0 (log time and every header stamp, in ns). Values
that are not available at a tick (no plan, no link estimate) are left out of the message.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import foxglove
import numpy as np
from foxglove.channels import FrameTransformsChannel, LogChannel, SceneUpdateChannel
from foxglove.messages import FrameTransform, FrameTransforms, Log, LogLevel

from tetherland.config import Scenario
from tetherland.geometry import LandingGeometry
from tetherland.mission.phases import Phase
from tetherland.rotations import rotmat_to_quat
from tetherland.viz.scene import (
    ANCHOR,
    BODY,
    BODY_ESTIMATED,
    WORLD,
    cable_update,
    quaternion,
    timestamp,
    vector,
)
from tetherland.viz.series import ANGLE_NAMES, SERIES_KINDS, TickSeries

SCENE_PERIOD = 1.0
"""The static scene is republished this often, for viewers that join or seek [s]."""


def _number(doc: str) -> dict[str, str]:
    return {"type": "number", "description": doc}


def _object(title: str, properties: dict[str, Any]) -> dict[str, Any]:
    return {"title": title, "type": "object", "properties": properties}


_ROTORS = {f"f{i}": _number(f"rotor {i} thrust [N]") for i in range(1, 5)}
SCHEMAS: dict[str, dict[str, Any]] = {
    "angle": _object("tetherland.Angle", {
        "desired": _number("the supervisor's reference (superscript d) [deg]"),
        "nominal": _number("the planned trajectory (superscript n) [deg]"),
        "actual": _number("the plant's truth [deg]"),
        "estimated": _number("the state estimate [deg]"),
    }),
    "thrusts": _object("tetherland.RotorThrusts", {
        "actual": _object("tetherland.Rotors", _ROTORS),
        "nominal": _object("tetherland.Rotors", _ROTORS),
        "commanded": _object("tetherland.Rotors", _ROTORS),
    }),
    "tension": _object("tetherland.Tension", {
        "actual": _number("cable tension f_L of the plant [N]"),
        "estimated": _number("estimated tension [N]"),
        "nominal": _number("planned tension [N]"),
    }),
    "state": _object("tetherland.MissionState", {
        "phase": {"type": "integer", "description": "mission phase code"},
        "phase_name": {"type": "string"},
        "mode": {"type": "integer", "description": "0 free flight, 1 tethered, 2 motors off"},
        "hook": {"type": "integer", "description": "1 while the cable is engaged"},
    }),
    "verdict": _object("tetherland.Verdict", {
        "success": {"type": "boolean"},
        "reason": {"type": "string"},
        "conditions": {"type": "object", "description": "landing conditions (1)-(5) held"},
        "landing": {"type": "object", "description": "touchdown measures (SI units)"},
    }),
}  # fmt: skip

TOPICS: dict[str, str] = {
    "/tf": "foxglove.FrameTransforms",
    "/scene": "foxglove.SceneUpdate",
    "/cable": "foxglove.SceneUpdate",
    **{f"/angles/{name}": "tetherland.Angle" for name in ANGLE_NAMES},
    "/rotor_thrusts": "tetherland.RotorThrusts",
    "/tension": "tetherland.Tension",
    "/mission/state": "tetherland.MissionState",
    "/mission/events": "foxglove.Log",
    "/verdict": "tetherland.Verdict",
}
"""Every topic and its schema name."""
PER_TICK = ("/tf", "/cable", *(f"/angles/{n}" for n in ANGLE_NAMES), "/rotor_thrusts",
            "/tension", "/mission/state")  # fmt: skip
"""Topics with one message per control tick."""


def phase_name(code: int) -> str:
    try:
        return Phase(code).name.lower()
    except ValueError:
        return str(code)


def _ns(t: float) -> int:
    return round(t * 1e9)


def _finite(**values: float) -> dict[str, float]:
    return {k: float(v) for k, v in values.items() if math.isfinite(v)}


def _rotors(f: np.ndarray) -> dict[str, float]:
    return {f"f{i + 1}": float(x) for i, x in enumerate(f) if math.isfinite(x)}


ROTOR_KEYS = ("f1", "f2", "f3", "f4")
TENSION_KINDS = ("actual", "estimated", "nominal")


def json_rows(keys: Sequence[str], values: np.ndarray) -> list[str]:
    """``json.dumps`` of each row of ``values`` as the object {key: value} of its finite
    values (the others left out), formatted column-wise.

    The rows are grouped by which of their values are finite; each group fills one format
    string, whose ``{}`` fields print a float as ``repr`` does (as ``json.dumps`` does).

    Parameters
    ----------
    keys : sequence of str
        The k keys, in the order of the columns.
    values : (n, k) array
        Float values (any unit).
    """
    values = np.asarray(values, dtype=float)
    n, k = values.shape
    if k != len(keys):
        raise ValueError(f"{k} columns for {len(keys)} keys")
    codes = np.isfinite(values) @ (1 << np.arange(k))
    out = np.empty(n, dtype=object)
    for code in np.unique(codes).tolist():
        rows = np.flatnonzero(codes == code)
        kept = [j for j in range(k) if code >> j & 1]
        names = [json.dumps(keys[j]).replace("{", "{{").replace("}", "}}") for j in kept]
        template = "{{" + ", ".join(f"{name}: {{}}" for name in names) + "}}"
        columns = [values[rows, j].tolist() for j in kept]
        texts = list(map(template.format, *columns)) if kept else [template.format()] * len(rows)
        out[rows] = texts
    return out.tolist()


class Publisher:
    """Creates the channels in a Foxglove context and publishes a run's messages.

    Parameters
    ----------
    context : foxglove.Context
        Where the channels live (its sinks: an MCAP writer, a WebSocket server).
    scenario : Scenario
        Geometry of the anchor.
    scene : callable
        ``scene(t) -> SceneUpdate``: the static scene stamped at ``t``.
    tension_scale : float
        Tension at the top of the cable's colour map [N].
    """

    def __init__(
        self, context: foxglove.Context, scenario: Scenario, scene, tension_scale: float
    ) -> None:
        self.geometry = LandingGeometry.from_scenario(scenario)
        self._scene = scene
        self.tension_scale = tension_scale
        self._next_scene = 0.0
        self.phase_names: dict[int, str] = {}
        """Phase names by code (empty: the tethered mission's phases)."""
        c = context
        self.tf = FrameTransformsChannel("/tf", context=c)
        self.scene = SceneUpdateChannel("/scene", context=c)
        self.cable = SceneUpdateChannel("/cable", context=c)
        self.angles = [foxglove.Channel(f"/angles/{name}", schema=SCHEMAS["angle"], context=c)
                       for name in ANGLE_NAMES]  # fmt: skip
        self.thrusts = foxglove.Channel("/rotor_thrusts", schema=SCHEMAS["thrusts"], context=c)
        self.tension = foxglove.Channel("/tension", schema=SCHEMAS["tension"], context=c)
        self.state = foxglove.Channel("/mission/state", schema=SCHEMAS["state"], context=c)
        self.events = LogChannel("/mission/events", context=c)
        self.verdict = foxglove.Channel("/verdict", schema=SCHEMAS["verdict"], context=c)
        self._all = [self.tf, self.scene, self.cable, *self.angles, self.thrusts, self.tension,
                     self.state, self.events, self.verdict]  # fmt: skip
        self._anchor = FrameTransform(
            parent_frame_id=WORLD, child_frame_id=ANCHOR, translation=vector(self.geometry.p_A),
            rotation=quaternion(rotmat_to_quat(self.geometry.R_WA)),
        )  # fmt: skip

    @property
    def watched(self) -> bool:
        """Whether any sink (a recording, a subscribed viewer) takes any channel."""
        return any(channel.has_sinks() for channel in self._all)

    def close(self) -> None:
        for channel in self._all:
            channel.close()

    # ------------------------------------------------------------------ messages
    def publish_scene(self, t: float) -> None:
        self.scene.log(self._scene(t), log_time=_ns(t))

    def _scene_if_due(self, t: float) -> None:
        if t >= self._next_scene:
            self.publish_scene(t)
            self._next_scene = t + SCENE_PERIOD

    def _publish_pose(
        self, t: float, ns: int, p_W, q_WB, est_p_W, est_q_WB, estimated: bool
    ) -> None:
        """The /tf message of one tick: the true body, the estimate (if ``estimated``), the
        anchor."""
        stamp = timestamp(t)
        transforms = [
            FrameTransform(timestamp=stamp, parent_frame_id=WORLD, child_frame_id=BODY,
                           translation=vector(p_W), rotation=quaternion(q_WB)),
        ]  # fmt: skip
        if estimated:
            transforms.append(FrameTransform(
                timestamp=stamp, parent_frame_id=WORLD, child_frame_id=BODY_ESTIMATED,
                translation=vector(est_p_W), rotation=quaternion(est_q_WB),
            ))  # fmt: skip
        transforms.append(self._anchor)
        self.tf.log(FrameTransforms(transforms=transforms), log_time=ns)

    def publish_tick(self, s: TickSeries, i: int) -> None:
        """Every per-tick message of row ``i`` of ``s`` (and the scene when it is due).

        The reference encoding, one dict and ``json.dumps`` per message (the live view);
        :meth:`publish_ticks` writes the same bytes for a whole series."""
        t = float(s.t[i])
        ns = _ns(t)
        self._scene_if_due(t)
        self._publish_pose(t, ns, s.p_W[i], s.q_WB[i], s.est_p_W[i], s.est_q_WB[i],
                           bool(np.all(np.isfinite(s.est_q_WB[i]))))  # fmt: skip
        actual, estimated, nominal = s.tension[i]
        self.cable.log(
            cable_update(t, self.geometry.p_A, s.attachment_W[i], bool(s.hook[i] == 1), actual,
                         self.tension_scale),
            log_time=ns,
        )  # fmt: skip
        for channel, name in zip(self.angles, ANGLE_NAMES, strict=True):
            deg = np.degrees(s.angles[name][i])
            doc = _finite(**dict(zip(SERIES_KINDS, deg, strict=True)))
            channel.log(json.dumps(doc).encode(), log_time=ns)
        thrusts = {
            "actual": _rotors(s.thrusts_actual[i]),
            "nominal": _rotors(s.thrusts_nominal[i]),
            "commanded": _rotors(s.thrusts_commanded[i]),
        }
        self.thrusts.log(json.dumps(thrusts).encode(), log_time=ns)
        doc = _finite(actual=actual, estimated=estimated, nominal=nominal)
        self.tension.log(json.dumps(doc).encode(), log_time=ns)
        phase = int(s.phase[i])
        name = self.phase_names.get(phase) or phase_name(phase)
        state = {"phase": phase, "phase_name": name, "mode": int(s.mode[i]),
                 "hook": int(s.hook[i])}  # fmt: skip
        self.state.log(json.dumps(state).encode(), log_time=ns)

    def publish_ticks(
        self,
        s: TickSeries,
        events: Sequence[dict[str, Any]] = (),
        *,
        by_row: bool = False,
        block: int = 4096,
    ) -> None:
        """Every row of ``s`` as :meth:`publish_tick` publishes it, and ``events`` (in time
        order) each before the first tick at or after its time (the rest after the last).

        The messages, their bytes and their order are those of :meth:`publish_tick` called
        row by row (``by_row``: the reference), for a fraction of the cost: the JSON
        messages are formatted column-wise (:func:`json_rows`), ``block`` rows at a time
        (which bounds the memory).
        """
        k = 0
        for start in range(0, len(s), block):
            b = s.rows(slice(start, start + block))
            publish = partial(self.publish_tick, b) if by_row else self._block(b)
            for j, t in enumerate(b.t.tolist()):
                while k < len(events) and float(events[k]["t"]) <= t:
                    self.publish_event(events[k])
                    k += 1
                publish(j)
        for event in events[k:]:
            self.publish_event(event)

    def _block(self, s: TickSeries) -> Callable[[int], None]:
        """``publish(j)``: :meth:`publish_tick` of row ``j`` of ``s``, its JSON messages
        formatted beforehand for all rows at once."""
        times = s.t.tolist()
        p, q = s.p_W.tolist(), s.q_WB.tolist()
        est_p, est_q = s.est_p_W.tolist(), s.est_q_WB.tolist()
        estimated = np.isfinite(s.est_q_WB).all(axis=1).tolist()
        attachment, actual = s.attachment_W.tolist(), s.tension[:, 0].tolist()
        engaged = (s.hook == 1).tolist()
        p_A = self.geometry.p_A.tolist()
        channels = [*self.angles, self.thrusts, self.tension, self.state]
        texts = [*(json_rows(SERIES_KINDS, np.degrees(s.angles[name])) for name in ANGLE_NAMES),
                 self._thrust_rows(s), json_rows(TENSION_KINDS, s.tension),
                 self._state_rows(s)]  # fmt: skip
        # the messages are encoded once here; Channel.log is the SDK's public call (its
        # private bytes log would save about 0.2 s of the 2.5 s)
        logs = [(channel.log, [text.encode() for text in rows])
                for channel, rows in zip(channels, texts, strict=True)]  # fmt: skip

        def publish(j: int) -> None:
            t = times[j]
            ns = _ns(t)
            self._scene_if_due(t)
            self._publish_pose(t, ns, p[j], q[j], est_p[j], est_q[j], estimated[j])
            self.cable.log(cable_update(t, p_A, attachment[j], engaged[j], actual[j],
                                        self.tension_scale),
                           log_time=ns)  # fmt: skip
            for log, messages in logs:
                log(messages[j], log_time=ns)

        return publish

    @staticmethod
    def _thrust_rows(s: TickSeries) -> list[str]:
        rotors = [json_rows(ROTOR_KEYS, f)
                  for f in (s.thrusts_actual, s.thrusts_nominal, s.thrusts_commanded)]  # fmt: skip
        return list(map('{{"actual": {}, "nominal": {}, "commanded": {}}}'.format, *rotors))

    def _state_rows(self, s: TickSeries) -> list[str]:
        phases = [int(x) for x in s.phase.tolist()]
        names = {code: json.dumps(self.phase_names.get(code) or phase_name(code))
                 for code in set(phases)}  # fmt: skip
        template = '{{"phase": {}, "phase_name": {}, "mode": {}, "hook": {}}}'.format
        modes = [int(x) for x in s.mode.tolist()]
        hooks = [int(x) for x in s.hook.tolist()]
        return list(map(template, phases, map(names.__getitem__, phases), modes, hooks))

    def publish_event(self, event: dict[str, Any]) -> None:
        """A run event (``t``, ``source``, ``kind``, ``message``) as a Log message."""
        t = float(event["t"])
        kind = str(event.get("kind", ""))
        level = LogLevel.Warning if kind in ("abort", "MISSED") else LogLevel.Info
        text = f"{kind}: {event.get('message', '')}".rstrip(": ")
        self.events.log(
            Log(timestamp=timestamp(t), level=level, message=text,
                name=str(event.get("source", ""))),
            log_time=_ns(t),
        )  # fmt: skip

    def publish_verdict(self, t: float, summary: dict[str, Any]) -> None:
        """The verdict document and a Log line saying success or why it failed."""
        landing = summary.get("landing") or {}
        doc = {
            "success": bool(summary.get("success", False)),
            "reason": str(summary.get("reason", "")),
            "conditions": landing.get("conditions") or {},
            "landing": {k: v for k, v in landing.items() if isinstance(v, (int, float))
                        and not isinstance(v, bool) and math.isfinite(v)},
        }  # fmt: skip
        self.verdict.log(json.dumps(doc).encode(), log_time=_ns(t))
        level = LogLevel.Info if doc["success"] else LogLevel.Error
        text = "verdict: success" if doc["success"] else f"verdict: failure ({doc['reason']})"
        self.events.log(Log(timestamp=timestamp(t), level=level, message=text, name="verdict"),
                        log_time=_ns(t))  # fmt: skip


__all__ = ["PER_TICK", "SCENE_PERIOD", "SCHEMAS", "TOPICS", "Publisher", "json_rows", "phase_name"]
