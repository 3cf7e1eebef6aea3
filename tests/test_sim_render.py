"""Watching a run: mp4 from a log and live; the viewer refuses cleanly without a display."""

from __future__ import annotations

import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.sim.baselines import ConstantSpeedController
from tetherland.sim.render import (
    RenderUnavailableError,
    SceneRenderer,
    VideoRecorder,
    render_log,
    view_log,
)
from tetherland.sim.runner import Runner


@pytest.fixture(scope="module")
def landed_log():
    sc = load_scenario("slope50")
    runner = Runner(sc, ConstantSpeedController.motors_off())
    return runner.run(0.5, initial_state=runner.plant.landed_state(), cable_engaged=True)


def _require_gl(plant):
    try:
        SceneRenderer(plant, 64, 48).close()
    except RenderUnavailableError as err:
        pytest.skip(f"offscreen rendering unavailable: {err}")


def _frames(path):
    import imageio.v2 as imageio

    reader = imageio.get_reader(path)
    try:
        return [np.asarray(f) for f in reader]
    finally:
        reader.close()


def test_render_log_writes_the_expected_frames(landed_log, tmp_path):
    from tetherland.sim.plant import Plant

    _require_gl(Plant(load_scenario("slope50")))
    info = render_log(landed_log, tmp_path / "landed.mp4", fps=20, width=320, height=240)
    frames = _frames(info.path)
    # rows at 0 .. 0.498 s: frames at 0, 0.05, ..., 0.45 s
    assert info.frames == len(frames) == 10
    assert frames[0].shape == (240, 320, 3)
    for f in frames:
        assert f.std() > 10.0  # not blank: slope, sky, vehicle
        assert len(np.unique(f.reshape(-1, 3)[::7], axis=0)) > 50
    assert not list(tmp_path.glob(".*tmp*"))  # written atomically


def test_live_recorder_renders_as_the_run_goes(tmp_path):
    sc = load_scenario("flat")
    runner = Runner(sc, ConstantSpeedController.motors_off())
    _require_gl(runner.plant)
    with VideoRecorder(runner.plant, tmp_path / "live.mp4", fps=25, width=160, height=128) as rec:
        runner.observers = (rec,)
        runner.run(0.4)
    frames = _frames(tmp_path / "live.mp4")
    assert rec.frames == len(frames) == 10
    assert all(f.std() > 5.0 for f in frames)


def test_viewer_without_display_fails_clearly(landed_log, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(RenderUnavailableError, match="no display"):
        view_log(landed_log)


def test_command_line_renders_a_saved_log(landed_log, tmp_path, capsys):
    from tetherland.sim.plant import Plant
    from tetherland.sim.render import main

    _require_gl(Plant(load_scenario("slope50")))
    path = landed_log.save(tmp_path / "run.npz")
    assert main([str(path), "--fps", "10"]) == 0
    assert (tmp_path / "run.mp4").stat().st_size > 1000
    assert "5 frames" in capsys.readouterr().out
    assert main([str(tmp_path / "missing.npz")]) == 2
