"""The live view (issue 16, item 2): a Foxglove WebSocket client receives the channels."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest

from foxglove_client import Client
from tetherland.config import load_scenario
from tetherland.control import FreeFlightController
from tetherland.errors import ConfigError
from tetherland.interfaces import Reference
from tetherland.models.quadrotor import RotorModel
from tetherland.sim import Plant, Runner
from tetherland.state import RigidBodyState
from tetherland.viz.channels import PER_TICK, TOPICS
from tetherland.viz.live import LiveView


class Hold:
    def __init__(self, p):
        self.p = np.array([p, np.zeros(3), np.zeros(3)])

    def reference(self, t, est):
        return Reference(t=t, p_W=self.p)


@pytest.fixture(scope="module")
def hover():
    sc = load_scenario("slope50")
    plant = Plant(sc)
    target = plant.start_state().p_W + np.array([0.0, 0.0, 1.0])
    x0 = RigidBodyState.at_rest(target + np.array([0.03, 0.0, 0.0]))
    w0 = RotorModel.from_config(sc.vehicle).speed(np.full(4, sc.vehicle.mass * 9.81 / 4))

    def run(observers=(), duration=1.0):
        runner = Runner(sc, FreeFlightController(sc), reference=Hold(target), seed=2, plant=plant,
                        observers=observers)  # fmt: skip
        return runner.run(duration, initial_state=x0, rotor_speeds=w0)

    return sc, run


def test_a_client_receives_the_advertised_channels_and_messages(hover):
    sc, run = hover
    with LiveView(sc, port=0, speed=0.0, rate_hz=sc.controller.rate_hz) as view:
        client = Client(view.url, duration=30.0).start()
        assert client.subscribed.wait(10)
        deadline = time.monotonic() + 10
        while not view.publisher.watched and time.monotonic() < deadline:
            time.sleep(0.01)
        log = run([view])
        view.finish({"success": True, "reason": "ok", "landing": {}})
        time.sleep(0.5)
    client.join()
    assert client.subprotocol in ("foxglove.sdk.v1", "foxglove.websocket.v1")
    advertised = {c["topic"]: c["schemaName"] for c in client.channels.values()}
    assert advertised == TOPICS
    for topic in (*PER_TICK, "/scene", "/verdict"):
        assert client.messages[topic], f"nothing received on {topic}"
    # what arrives is the log row of that tick
    t_ns = {round(t * 1e9): i for i, t in enumerate(log["t"])}
    tension = client.messages["/tension"]
    assert len(tension) > len(log) // 2  # the client keeps up (drops are allowed, not most)
    for stamp, payload in tension[:: max(len(tension) // 50, 1)]:
        i = t_ns[stamp]
        assert json.loads(payload)["actual"] == pytest.approx(log["tension"][i], abs=1e-12)
    thrusts = client.messages["/rotor_thrusts"]
    for stamp, payload in thrusts[:: max(len(thrusts) // 50, 1)]:
        doc = json.loads(payload)["actual"]
        np.testing.assert_allclose([doc[f"f{j}"] for j in range(1, 5)],
                                   log["rotor_thrusts"][t_ns[stamp]], atol=1e-12)  # fmt: skip
    assert json.loads(client.messages["/verdict"][0][1])["success"] is True


def test_without_a_viewer_the_run_is_unchanged_and_paced(hover):
    sc, run = hover
    reference = run(duration=0.4)
    with LiveView(sc, port=0, speed=1.0) as view:
        t0 = time.perf_counter()
        log = run([view], duration=0.4)
        wall = time.perf_counter() - t0
    np.testing.assert_array_equal(log.matrix, reference.matrix)
    assert wall >= 0.4 * 0.95  # paced to real time (simulation alone is several times faster)


def test_bad_live_settings_are_rejected(hover):
    sc, _ = hover
    with pytest.raises(ConfigError, match="--live-speed"):
        LiveView(sc, port=0, speed=-1.0)
    with pytest.raises(ConfigError, match="--live-port"):
        LiveView(sc, port=70000)
    with pytest.raises(ConfigError, match="--live-rate"):
        LiveView(sc, port=0, rate_hz=0.0)


def test_the_publishing_rate_is_limited(hover):
    """At 50 Hz a viewer gets every 10th control tick of the 500 Hz loop."""
    sc, run = hover
    with LiveView(sc, port=0, speed=0.0, rate_hz=50.0) as view:
        client = Client(view.url, duration=20.0).start()
        assert client.subscribed.wait(10)
        deadline = time.monotonic() + 10
        while not view.publisher.watched and time.monotonic() < deadline:
            time.sleep(0.01)
        log = run([view], duration=1.0)
        time.sleep(0.5)
    client.join()
    stamps = np.array([s for s, _ in client.messages["/tension"]])
    expected = np.round(log["t"][::10] * 1e9).astype(np.int64)
    np.testing.assert_array_equal(stamps, expected)


def test_a_busy_port_is_one_clear_error(hover):
    sc, _ = hover
    with LiveView(sc, port=0, speed=0.0) as first:
        with pytest.raises(ConfigError, match=f"--live-port {first.port}"):
            LiveView(sc, port=first.port)
