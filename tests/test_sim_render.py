"""Watching a run: mp4 from a log and live; the viewer refuses cleanly without a display."""

from __future__ import annotations

import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.sim import SimLog
from tetherland.sim.baselines import ConstantSpeedController
from tetherland.sim.render import (
    RenderUnavailableError,
    SceneRenderer,
    VideoOptions,
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


def _meta(path):
    import imageio.v2 as imageio

    reader = imageio.get_reader(path)
    try:
        return reader.get_meta_data()
    finally:
        reader.close()


@pytest.mark.parametrize(("fps", "speed", "size", "n"), [
    (20, 1.0, (320, 240), 10),  # rows at 0 .. 0.498 s: frames at 0, 0.05, ..., 0.45 s
    (12, 1.0, (160, 120), 6),  # 0, 1/12, ..., 5/12 s
    (20, 2.0, (256, 144), 5),  # 0.1 s of flight per frame
])  # fmt: skip
def test_the_video_has_the_frames_rate_and_size_asked_for(landed_log, tmp_path, fps, speed,
                                                          size, n):  # fmt: skip
    from tetherland.sim.plant import Plant

    _require_gl(Plant(load_scenario("slope50")))
    options = VideoOptions(fps=fps, width=size[0], height=size[1], speed=speed)
    calls = []
    info = render_log(landed_log, tmp_path / "landed.mp4", options=options,
                      progress=lambda done, total: calls.append((done, total)))  # fmt: skip
    frames = _frames(info.path)
    assert info.frames == len(frames) == n
    assert calls == [(k, n) for k in range(1, n + 1)]  # the progress bar sees every frame
    meta = _meta(info.path)
    assert meta["fps"] == pytest.approx(fps) and meta["size"] == size
    assert meta["duration"] == pytest.approx(n / fps, abs=1.01 / fps)
    assert frames[0].shape == (size[1], size[0], 3)
    for f in frames:
        assert f.std() > 10.0  # not blank: slope, sky, vehicle
        assert len(np.unique(f.reshape(-1, 3)[::7], axis=0)) > 30
    assert not list(tmp_path.glob(".*tmp*"))  # written atomically


def test_bad_video_options_are_one_line_naming_the_field():
    with pytest.raises(ValueError, match=r"fps must be in \[1, 60\]"):
        VideoOptions(fps=0)
    with pytest.raises(ValueError, match="width must be even"):
        VideoOptions(width=641)
    with pytest.raises(ValueError, match="height must be even"):
        VideoOptions(height=4000)
    with pytest.raises(ValueError, match="WIDTHxHEIGHT"):
        VideoOptions.parse_size("640-480")
    assert VideoOptions.parse_size("1280X720") == (1280, 720)


def _pixel_of(model, data, camera, p_W, width, height):
    """Where the offscreen image shows world point p_W [px] (col, row): MuJoCo's OpenGL
    camera of the scene, a perspective projection onto its near plane."""
    import mujoco

    scene = mujoco.MjvScene(model, maxgeom=200)
    mujoco.mjv_updateScene(model, data, mujoco.MjvOption(), None, camera,
                           mujoco.mjtCatBit.mjCAT_ALL, scene)  # fmt: skip
    cam = scene.camera[0]
    forward, up = np.array(cam.forward), np.array(cam.up)
    right = np.cross(forward, up)
    rel = np.asarray(p_W) - np.array(cam.pos)
    depth = rel @ forward
    u = rel @ right / depth * cam.frustum_near
    v = rel @ up / depth * cam.frustum_near
    half_h = 0.5 * (cam.frustum_top - cam.frustum_bottom)
    half_w = half_h * width / height
    col = (u - (cam.frustum_center - half_w)) / (2 * half_w) * width
    row = (cam.frustum_top - v) / (2 * half_h) * height
    return np.array([col, row])


def test_the_video_shows_the_vehicle_where_the_log_says(landed_log, tmp_path):
    """The vehicle jumps from one logged position to another at t = 0.25 s: the frames
    before show it at the first (they do not change), those after at the second, and the
    pixels that change lie around the projections of the two logged positions."""
    from tetherland.sim.plant import Plant
    from tetherland.sim.render import framing_camera

    sc = load_scenario("slope50", ["tether.hook_drop=0"])  # the vehicle alone moves
    plant = Plant(sc)
    _require_gl(plant)
    matrix = landed_log.matrix.copy()
    log = SimLog(landed_log.columns, matrix, landed_log.metadata)
    p0 = plant.layout.geometry.p_A + np.array([0.0, 0.0, 1.0])
    p1 = p0 + np.array([0.0, 1.5, 0.8])
    switch = log.t >= 0.25
    log["p_W"][:] = np.where(switch[:, None], p1, p0)
    log["q_WB"][:] = [1.0, 0.0, 0.0, 0.0]
    log["hook"][:] = 0.0  # the cable is not drawn
    w, h = 320, 240
    info = render_log(log, tmp_path / "jump.mp4", scenario=sc,
                      options=VideoOptions(fps=20, width=w, height=h))  # fmt: skip
    frames = [f.astype(int) for f in _frames(info.path)]
    assert len(frames) == 10
    change = [np.abs(f - frames[0]).max(axis=2) > 60 for f in frames]
    assert [c.sum() > 20 for c in change] == [False] * 5 + [True] * 5  # t = 0.25 s: frame 5
    camera = framing_camera(plant.layout, log["p_W"])
    plant.show_pose(np.concatenate((p0, [1.0, 0, 0, 0])), False)
    px0 = _pixel_of(plant.model, plant.data, camera, p0, w, h)
    px1 = _pixel_of(plant.model, plant.data, camera, p1, w, h)
    radius = 30  # [px] more than the vehicle's half span seen at this distance
    assert np.linalg.norm(px1 - px0) > 2 * radius  # two places apart in the image
    rows, cols = np.nonzero(change[-1])
    changed = np.column_stack((cols, rows)).astype(float)
    near0 = np.linalg.norm(changed - px0, axis=1) < radius
    near1 = np.linalg.norm(changed - px1, axis=1) < radius
    assert near0.sum() > 10 and near1.sum() > 10  # the vehicle left p0 and appears at p1
    assert np.mean(near0 | near1) > 0.99  # and nothing else changed
    for px, near in ((px0, near0), (px1, near1)):  # each blob is centred on its position
        assert np.linalg.norm(changed[near].mean(axis=0) - px) < 8


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
