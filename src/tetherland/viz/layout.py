"""The shipped Foxglove layout: the 3D scene and the plots of the chapter's figure 6.5.

``foxglove_layout.json`` (package data) is Foxglove's layout file (``configById`` and a
split ``layout`` tree, the format of the app's *Layouts > Import from file*). Each panel's
configuration is built with the SDK's typed layout classes (:mod:`foxglove.layouts`);
:func:`build_layout` makes the file and a test checks that the shipped copy is current
and names only published topics.
"""

from __future__ import annotations

import json
from importlib.resources import files
from pathlib import Path
from typing import Any

import foxglove.layouts as fl

from tetherland.viz.series import ANGLE_NAMES

LAYOUT_FILE = "foxglove_layout.json"
_STYLE = {"desired": ("#ff7f0e", "dashed"), "nominal": ("#2ca02c", "dotted"),
          "actual": ("#1f77b4", "solid"), "estimated": ("#9467bd", "solid")}  # fmt: skip
_ROTOR_COLORS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728")
_LABELS = {"phi": "phi (link elevation) [deg]", "delta": "delta (link azimuth) [deg]",
           "theta_A": "theta_A (robot tilt) [deg]", "psi": "psi (heading) [deg]"}  # fmt: skip


def _config(obj: Any) -> dict[str, Any]:
    return json.loads(obj.to_json())


def _series(value: str, label: str, color: str, style: str, enabled: bool = True):
    return fl.PlotSeries(value=value, label=label, color=color, line_style=style,
                         timestamp_method="receiveTime", enabled=enabled)  # fmt: skip


def _plot(title: str, series: list, y_label: str) -> dict[str, Any]:
    config = _config(fl.PlotConfig(paths=series, show_legend=True, legend_display="floating",
                                   is_synced=True, y_axis_label=y_label))  # fmt: skip
    return {**config, "foxglovePanelTitle": title}


def _panels() -> dict[str, dict[str, Any]]:
    panels: dict[str, dict[str, Any]] = {}
    panels["3D!scene"] = _config(fl.ThreeDeeConfig(
        follow_tf="body", follow_mode="follow-position", fixed_frame="world",
        camera_state=fl.ThreeDeeCameraState(distance=4.0, phi=60.0, theta_offset=-60.0,
                                            perspective=True),
        topics={t: fl.BaseRendererSceneUpdateTopicSettings(visible=True)
                for t in ("/scene", "/cable")},
        scene=fl.BaseRendererSceneSettings(
            transforms=fl.BaseRendererTransforms(show_label=True, axis_size=0.15)),
    ))  # fmt: skip
    for name in ANGLE_NAMES:
        panels[f"Plot!{name}"] = _plot(_LABELS[name], [
            _series(f"/angles/{name}.{kind}", kind, *_STYLE[kind], enabled=kind != "estimated")
            for kind in ("desired", "nominal", "actual", "estimated")
        ], "deg")  # fmt: skip
    thrusts = []
    for i in range(1, 5):
        c = _ROTOR_COLORS[i - 1]
        thrusts.append(_series(f"/rotor_thrusts.actual.f{i}", f"f{i}", c, "solid"))
        thrusts.append(_series(f"/rotor_thrusts.nominal.f{i}", f"f{i} nominal", c, "dotted"))
    panels["Plot!rotor_thrusts"] = _plot("rotor thrusts f1..f4 [N] (dotted: nominal)", thrusts,
                                         "N")  # fmt: skip
    panels["Plot!tension"] = _plot("cable tension f_L [N]", [
        _series(f"/tension.{kind}", kind, *_STYLE[kind]) for kind in ("nominal", "actual",
                                                                      "estimated")
    ], "N")  # fmt: skip
    panels["StateTransitions!phase"] = {
        **_config(fl.StateTransitionsConfig(paths=[fl.StateTransitionsSeries(
            value="/mission/state.phase_name", label="phase", timestamp_method="receiveTime")],
            is_synced=True)),
        "foxglovePanelTitle": "mission phase",
    }  # fmt: skip
    panels["RosOut!events"] = {**_config(fl.LogConfig(topic_to_render="/mission/events")),
                               "foxglovePanelTitle": "phases, hook events, verdict"}  # fmt: skip
    panels["RawMessages!verdict"] = {**_config(fl.RawMessagesConfig(topic_path="/verdict")),
                                     "foxglovePanelTitle": "landing verdict"}  # fmt: skip
    return panels


def _split(first: Any, second: Any, direction: str, percent: float) -> dict[str, Any]:
    return {"first": first, "second": second, "direction": direction, "splitPercentage": percent}


def build_layout() -> dict[str, Any]:
    """The layout document (what ``foxglove_layout.json`` holds)."""
    plots = _split(
        _split(_split("Plot!phi", "Plot!delta", "row", 50),
               _split("Plot!theta_A", "Plot!psi", "row", 50), "column", 50),
        _split(_split("Plot!rotor_thrusts", "Plot!tension", "row", 50),
               "StateTransitions!phase", "column", 70),
        "column", 62,
    )  # fmt: skip
    left = _split("3D!scene", _split("RosOut!events", "RawMessages!verdict", "row", 60),
                  "column", 75)  # fmt: skip
    return {
        "configById": _panels(),
        "globalVariables": {},
        "userNodes": {},
        "playbackConfig": {"speed": 1.0},
        "layout": _split(left, plots, "row", 40),
    }


def layout_path() -> Path:
    """Path of the shipped layout file."""
    return Path(str(files("tetherland.viz").joinpath(LAYOUT_FILE)))


def layout_topics(layout: dict[str, Any]) -> set[str]:
    """Every topic the layout's panels read (for checking against the published ones)."""
    topics: set[str] = set()

    def visit(node: Any) -> None:
        if isinstance(node, dict):
            for key, value in node.items():
                if key in ("value", "topicToRender", "topicPath") and isinstance(value, str):
                    topics.add("/" + value.lstrip("/").split(".")[0])
                elif key == "topics" and isinstance(value, dict):
                    topics.update(value)
                else:
                    visit(value)
        elif isinstance(node, list):
            for item in node:
                visit(item)

    visit(layout["configById"])
    return topics


def write_layout(path: str | Path) -> Path:
    """Write :func:`build_layout` to ``path`` (used to refresh the shipped file)."""
    path = Path(path)
    path.write_text(json.dumps(build_layout(), indent=2) + "\n")
    return path


if __name__ == "__main__":  # python -m tetherland.viz.layout  (refreshes the shipped file)
    print(write_layout(Path(__file__).with_name(LAYOUT_FILE)))
