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

    def publish_tick(self, s: TickSeries, i: int) -> None:
        """Every per-tick message of row ``i`` of ``s`` (and the scene when it is due)."""
        t = float(s.t[i])
        ns = _ns(t)
        if t >= self._next_scene:
            self.publish_scene(t)
            self._next_scene = t + SCENE_PERIOD
        stamp = timestamp(t)
        transforms = [
            FrameTransform(timestamp=stamp, parent_frame_id=WORLD, child_frame_id=BODY,
                           translation=vector(s.p_W[i]), rotation=quaternion(s.q_WB[i])),
        ]  # fmt: skip
        if np.all(np.isfinite(s.est_q_WB[i])):
            transforms.append(FrameTransform(
                timestamp=stamp, parent_frame_id=WORLD, child_frame_id=BODY_ESTIMATED,
                translation=vector(s.est_p_W[i]), rotation=quaternion(s.est_q_WB[i]),
            ))  # fmt: skip
        transforms.append(self._anchor)
        self.tf.log(FrameTransforms(transforms=transforms), log_time=ns)
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


__all__ = ["PER_TICK", "SCENE_PERIOD", "SCHEMAS", "TOPICS", "Publisher", "phase_name"]
