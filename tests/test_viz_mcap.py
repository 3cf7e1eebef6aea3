"""MCAP logs (issue 16, item 1): a mission written with --mcap and a saved run exported,
read back with the `mcap` reader."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader
from mcap_protobuf.decoder import DecoderFactory

from tetherland.cli import main
from tetherland.geometry import LandingGeometry
from tetherland.sim.log import SimLog
from tetherland.viz import load_run
from tetherland.viz.channels import PER_TICK, TOPICS, json_rows
from tetherland.viz.layout import build_layout, layout_path, layout_topics
from tetherland.viz.mcap import write_mcap
from tetherland.viz.scene import SLACK_TENSION, static_scene, tension_rgba


def raw(path: Path) -> dict[str, list[tuple[int, bytes]]]:
    """{topic: [(log_time, encoded message)]} of an MCAP file, nothing decoded, each topic
    in the order written."""
    out: dict[str, list] = {}
    with open(path, "rb") as f:
        for _, channel, message in make_reader(f).iter_messages(log_time_order=False):
            out.setdefault(channel.topic, []).append((message.log_time, message.data))
    return out


def summary_of(path: Path):
    """The summary section of an MCAP file (its schemas and channels)."""
    with open(path, "rb") as f:
        return make_reader(f).get_summary()


def in_time_order(messages: dict[str, list], decode=()) -> dict[str, list]:
    """``messages`` (:func:`raw`) with each topic's messages sorted by time (stable), the
    JSON messages of the topics in ``decode`` decoded; the others stay encoded (protobuf
    ones are decoded where a test needs them)."""
    out = {}
    for topic, written in messages.items():
        ordered = sorted(written, key=lambda m: m[0])
        out[topic] = [(t, json.loads(m)) for t, m in ordered] if topic in decode else ordered
    return out


def decode(message):
    """A Foxglove SDK message decoded with its own protobuf schema (the SDK's objects have
    no getters)."""
    from mcap.records import Schema

    s = type(message).get_schema()
    schema = Schema(id=1, name=s.name, encoding=s.encoding, data=s.data)
    return DecoderFactory().decoder_for("protobuf", schema)(message.encode())


def protobuf_decoder(summary, topic: str):
    """The decoder of ``topic``'s protobuf messages (encoded bytes -> message), from the
    schema the file's summary gives the topic's channel."""
    (channel,) = [c for c in summary.channels.values() if c.topic == topic]
    return DecoderFactory().decoder_for("protobuf", summary.schemas[channel.schema_id])


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    """A full slope50 mission written with --mcap (the CLI, in process)."""
    out = tmp_path_factory.mktemp("mission")
    code = main(["mission", "slope50", "--seed", "1", "--out", str(out), "--mcap", "--json"])
    assert code == 0
    return out


@pytest.fixture(scope="module")
def mission_messages(run_dir) -> dict[str, list[tuple[int, bytes]]]:
    """The messages of the mission's MCAP file (:func:`raw`), read once for the module."""
    return raw(run_dir / "run.mcap")


pytestmark = pytest.mark.slow


def test_channels_schemas_and_one_message_per_tick(run_dir, mission_messages):
    log = SimLog.load(run_dir / "log.npz")
    summary = summary_of(run_dir / "run.mcap")
    messages = in_time_order(mission_messages, decode={"/mission/state", "/verdict"})
    schemas = {c.topic: summary.schemas[c.schema_id] for c in summary.channels.values()}
    assert {t: s.name for t, s in schemas.items()} == TOPICS
    for topic in TOPICS:
        expected = "jsonschema" if TOPICS[topic].startswith("tetherland.") else "protobuf"
        assert schemas[topic].encoding == expected
    t_ns = np.round(log["t"] * 1e9).astype(np.int64)
    for topic in PER_TICK:
        stamps = np.array([m[0] for m in messages[topic]])
        np.testing.assert_array_equal(np.sort(stamps), t_ns, err_msg=topic)
    record = json.loads((run_dir / "run.json").read_text())
    names = {m[1]["phase_name"] for m in messages["/mission/state"]}
    assert "tethered_landing" in names and names <= set(record["phase_codes"])
    for _, state in messages["/mission/state"][::500]:
        assert record["phase_codes"][state["phase_name"]] == state["phase"]
    assert len(messages["/verdict"]) == 1
    verdict = messages["/verdict"][0][1]
    doc = json.loads((run_dir / "summary.json").read_text())
    assert doc["files"]["mcap"] == str(run_dir / "run.mcap")
    assert verdict["success"] is doc["success"] is True
    assert verdict["conditions"] == doc["landing"]["conditions"]
    # every phase change and hook event of the run is a Log message
    to_log = protobuf_decoder(summary, "/mission/events")
    texts = [(t, to_log(data)) for t, data in messages["/mission/events"]]
    assert len(texts) == len(log.events) + 1  # + the verdict line
    assert sum("ENGAGED" in d.message for _, d in texts) == sum(
        e["kind"] == "ENGAGED" for e in log.events
    )


def test_replayed_pose_and_series_match_the_log(run_dir, mission_messages):
    log = SimLog.load(run_dir / "log.npz")
    # the sampled ticks' messages decoded (the tension's all)
    summary = summary_of(run_dir / "run.mcap")
    topics = ["/tf", "/tension", "/angles/phi", "/rotor_thrusts"]
    series = in_time_order({t: mission_messages[t] for t in topics}, decode={"/tension"})
    tf = series["/tf"]
    assert len(tf) == len(log)
    k = np.linspace(0, len(log) - 1, 400).astype(int)
    by_time = dict(tf)
    to_transforms = protobuf_decoder(summary, "/tf")
    for i in k:
        transforms = to_transforms(by_time[round(log["t"][i] * 1e9)]).transforms
        frames = {x.child_frame_id: x for x in transforms}
        body, est = frames["body"], frames["body_estimated"]
        p = [body.translation.x, body.translation.y, body.translation.z]
        q = [body.rotation.w, body.rotation.x, body.rotation.y, body.rotation.z]
        np.testing.assert_allclose(p, log["p_W"][i], atol=1e-12)
        np.testing.assert_allclose(q, log["q_WB"][i], atol=1e-12)
        np.testing.assert_allclose([est.translation.x, est.translation.y, est.translation.z],
                                   log["est_p_W"][i], atol=1e-12)  # fmt: skip
        anchor = frames["anchor"].translation
        geo_p_A = log.metadata["anchor_W"]
        np.testing.assert_allclose([anchor.x, anchor.y, anchor.z], geo_p_A, atol=1e-12)
    tension = dict(series["/tension"])
    encoded_phi = dict(series["/angles/phi"])
    encoded_thrusts = dict(series["/rotor_thrusts"])
    sampled = [round(log["t"][i] * 1e9) for i in k]
    phi = {ns: json.loads(encoded_phi[ns]) for ns in sampled}
    thrusts = {ns: json.loads(encoded_thrusts[ns]) for ns in sampled}
    for i in k:
        ns = round(log["t"][i] * 1e9)
        assert tension[ns]["actual"] == pytest.approx(log["tension"][i], abs=1e-12)
        assert phi[ns]["actual"] == pytest.approx(math.degrees(log["link_phi"][i]), abs=1e-9)
        if np.isfinite(log["ref_output"][i, 0]):
            assert phi[ns]["desired"] == pytest.approx(math.degrees(log["ref_output"][i, 0]))
        else:
            assert "desired" not in phi[ns]
        np.testing.assert_allclose([thrusts[ns]["actual"][f"f{j}"] for j in range(1, 5)],
                                   log["rotor_thrusts"][i], atol=1e-12)  # fmt: skip
    # the nominal tension exists exactly while a plan is flown and is positive on slope50
    doc = json.loads((run_dir / "summary.json").read_text())
    t_tethered, t_L = doc["times"]["t_tethered"], doc["times"]["t_L"]
    inside = [v["nominal"] for ns, v in tension.items() if t_tethered <= ns * 1e-9 <= t_L]
    outside = [v for ns, v in tension.items() if ns * 1e-9 < t_tethered]
    assert inside and min(inside) > 0.0
    assert all("nominal" not in v for v in outside)


def test_export_of_the_saved_run_matches_the_mission_file(run_dir, mission_messages, tmp_path):
    """`tetherland export RUN_DIR --mcap` (from disk) gives the messages the mission wrote
    from memory (the plans round-trip through their CSV files)."""
    target = tmp_path / "exported.mcap"
    assert main(["export", str(run_dir), "--mcap", "--out", str(target), "--json"]) == 0
    a, b = mission_messages, raw(target)
    assert a.keys() == b.keys()
    for topic in a:
        assert len(a[topic]) == len(b[topic]), topic
        assert [t for t, _ in a[topic]] == [t for t, _ in b[topic]], topic
        differ = [(x, y) for (_, x), (_, y) in zip(a[topic], b[topic], strict=True) if x != y]
        if topic.startswith("/angles") or topic in ("/tension", "/rotor_thrusts"):
            # the nominal values come back from the plans' CSV files: equal to 1e-9
            for x, y in map(lambda m: (json.loads(m[0]), json.loads(m[1])), differ):
                assert x.keys() == y.keys()
                for key in x:
                    if isinstance(x[key], dict):
                        assert x[key].keys() == y[key].keys()
                        np.testing.assert_allclose(list(x[key].values()),
                                                   list(y[key].values()), atol=1e-9)  # fmt: skip
                    else:
                        assert x[key] == pytest.approx(y[key], abs=1e-9)
        elif topic != "/scene":
            assert not differ, topic  # the same bytes


def records(path: Path) -> tuple[list, list]:
    """The channel and schema records of an MCAP file, and every message as (topic,
    log_time, publish_time, sequence, bytes), in the order written."""
    with open(path, "rb") as f:
        reader = make_reader(f)
        messages = [(c.topic, m.log_time, m.publish_time, m.sequence, m.data)
                    for _, c, m in reader.iter_messages(log_time_order=False)]  # fmt: skip
        summary = reader.get_summary()
    channels = sorted(
        (c.topic, c.message_encoding, sorted(c.metadata.items()), s.name, s.encoding, s.data)
        for c in summary.channels.values() for s in [summary.schemas[c.schema_id]]
    )  # fmt: skip
    return channels, messages


def test_column_wise_messages_equal_the_row_by_row_reference(run_dir, tmp_path):
    """The export formats the per-tick messages column-wise; the reference (``by_row``:
    a dict and ``json.dumps`` per message, as the live view) writes the same records.

    A short real run: every 20th tick of the mission (each phase, the plans' ends, the
    cable slack and engaged), the events and the verdict as they were."""
    run = load_run(run_dir)
    log = run.log
    short = dataclasses.replace(run, log=SimLog(log.columns, log.matrix[::20].copy(),
                                                log.metadata))  # fmt: skip
    fast, reference = tmp_path / "fast.mcap", tmp_path / "reference.mcap"
    assert write_mcap(short, fast).ticks == write_mcap(short, reference, by_row=True).ticks
    channels, messages = records(fast)
    assert (channels, messages) == records(reference)
    assert {c[0] for c in channels} == set(TOPICS)
    per_tick = [m for m in messages if m[0] == "/tension"]
    assert len(per_tick) == len(short.log)
    # the reference leaves values out and in: the comparison covers both
    tension = [json.loads(m[-1]) for m in per_tick]
    assert any("nominal" in x for x in tension) and any("nominal" not in x for x in tension)
    thrusts = [json.loads(m[-1]) for m in messages if m[0] == "/rotor_thrusts"]
    assert any(x["nominal"] == {} for x in thrusts) and any(x["nominal"] for x in thrusts)


def test_json_rows_are_json_dumps_of_the_finite_values():
    """Every pattern of missing values, and floats whose repr is awkward (subnormal,
    exponents, -0.0, integers): the text of ``json.dumps`` of the row's dict."""
    rng = np.random.default_rng(16)
    values = rng.normal(size=(400, 3)) * 10.0 ** rng.integers(-30, 30, size=(400, 3))
    values[::7, 0] = np.nan
    values[::5, 1] = np.inf
    values[::3, 2] = -np.inf
    values[::11] = np.nan
    values[1] = [5e-324, -0.0, 1e22]
    values[2] = [3.0, 0.1, -1.7976931348623157e308]
    keys = ("a", "b\"quoted\"", "{c}")
    rows = json_rows(keys, values)
    expected = [json.dumps({k: float(v) for k, v in zip(keys, row, strict=True)
                            if math.isfinite(v)}) for row in values]  # fmt: skip
    assert rows == expected
    assert "{}" in rows and len(set(map(len, map(json.loads, rows)))) == 4
    assert json_rows(keys, np.zeros((0, 3))) == []
    with pytest.raises(ValueError, match="3 columns for 2 keys"):
        json_rows(keys[:2], values)


def test_export_rejects_bad_input(tmp_path, capsys):
    assert main(["export", str(tmp_path / "missing"), "--mcap"]) == 2
    assert main(["export", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert "not a run directory" in err and "--mcap" in err
    assert not list(tmp_path.iterdir())  # nothing half-written


def test_shipped_layout_is_current_and_reads_published_topics():
    shipped = json.loads(layout_path().read_text())
    assert shipped == build_layout()
    assert layout_topics(shipped) <= set(TOPICS)
    plots = [k for k in shipped["configById"] if k.startswith("Plot!")]
    assert {p.split("!")[1] for p in plots} == {"phi", "delta", "theta_A", "psi",
                                                "rotor_thrusts", "tension"}  # fmt: skip
    phi = shipped["configById"]["Plot!phi"]["paths"]
    assert {p["label"] for p in phi} >= {"desired", "nominal", "actual"}


def test_scene_is_the_plants_mujoco_scene(pipe60):
    """The pipe is a cylinder of the pipe's radius along the fall line x_S."""
    from tetherland.rotations import quat_to_rotmat
    from tetherland.viz.mcap import scene_model

    geo = LandingGeometry.from_scenario(pipe60)
    update = decode(static_scene(scene_model(pipe60), geo, [], np.zeros(3)))
    scene = next(e for e in update.entities if e.id == "scene")
    pipes = [c for c in scene.cylinders if c.size.x > 0.3]
    assert len(pipes) == 1
    pipe = pipes[0]
    assert pipe.size.x == pytest.approx(2 * pipe60.surface.pipe_radius)
    o = pipe.pose.orientation
    axis = quat_to_rotmat([o.w, o.x, o.y, o.z])[:, 2]
    assert abs(axis @ geo.surface.x_S) == pytest.approx(1.0, abs=1e-9)
    centre = [pipe.pose.position.x, pipe.pose.position.y, pipe.pose.position.z]
    # the top line of the pipe passes through the surface origin
    top = np.asarray(centre) + pipe60.surface.pipe_radius * geo.surface.z_S
    np.testing.assert_allclose(np.cross(top - geo.surface.origin, geo.surface.x_S), 0, atol=1e-9)
    vehicle = next(e for e in update.entities if e.id == "vehicle")
    assert vehicle.frame_id == "body" and vehicle.frame_locked
    assert len(vehicle.spheres) == 5  # the landers and the cable's mount


def test_cable_colour_follows_the_tension():
    assert tension_rgba(0.5 * SLACK_TENSION, 10.0) == tension_rgba(math.nan, 10.0)  # grey
    # plasma: blue falls and red rises with the tension
    colours = [tension_rgba(f, 10.0) for f in (0.5, 3.0, 6.0, 9.5)]
    reds = [c[0] for c in colours]
    assert reds == sorted(reds) and reds[0] < reds[-1]
    assert tension_rgba(50.0, 10.0) == tension_rgba(10.0, 10.0)  # saturates at the scale
