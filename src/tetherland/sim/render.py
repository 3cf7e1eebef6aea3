"""Watching a run: offscreen video (mp4) from a log or live, and the interactive viewer.

Offscreen rendering uses MuJoCo's classic OpenGL renderer; on a machine without a display
start Python with ``MUJOCO_GL=egl`` (or ``osmesa``); MuJoCo picks its GL backend when it
is first imported, so the variable must be set before. Videos are written with
imageio-ffmpeg, atomically. The camera frames the slope, the anchor, the landing point,
the start pad and the flown path, seen from the side of the slope's fall line. The
engaged cable is the tendon; a disengaged hook is drawn from the attachment point to the hook point.

A video from a log draws the logged poses at the video's frame times only (one
renderer, frames piped to ffmpeg as they are drawn). Without a GPU, OpenGL rasterises on
the CPU (Mesa llvmpipe): shadows, reflections, the skybox and multisampling would cost
4-6x the plain image, so videos leave them out unless ``detail`` is asked for; the sky
is then filled in where nothing was drawn (the pixels left at the cleared black: every
lit surface has some ambient light).
"""

from __future__ import annotations

import math
import os
import sys
from dataclasses import dataclass
from pathlib import Path

import mujoco
import numpy as np

from tetherland.config import Scenario, scenario_from_dict
from tetherland.errors import TetherlandError
from tetherland.geometry import FloatArray
from tetherland.io import atomic_path
from tetherland.sim.log import SimLog
from tetherland.sim.mjcf import SceneLayout
from tetherland.sim.plant import Plant
from tetherland.sim.video import (
    DEFAULT_FPS,
    DEFAULT_SIZE,
    FPS_RANGE,
    SIZE_RANGE,
    FrameProgress,
    VideoOptions,
)

_ENCODER_PARAMS = ["-preset", "veryfast"]
"""x264: about half the CPU of the default preset, files a few percent larger."""
CAMERA_AZIMUTH_OFFSET_DEG = 30.0
"""Camera heading: looking along y_A, turned this much to face the slope."""
CAMERA_ELEVATION_DEG = -18.0
_HOOK_RGBA = np.array([0.95, 0.85, 0.2, 1.0], dtype=np.float32)
_SKY_RGB = np.array([196, 212, 240], dtype=np.uint8)
"""Sky colour of a plain image (between the skybox's horizon and zenith colours)."""
_COSTLY_FLAGS = (
    mujoco.mjtRndFlag.mjRND_SHADOW,
    mujoco.mjtRndFlag.mjRND_REFLECTION,
    mujoco.mjtRndFlag.mjRND_SKYBOX,
)


class RenderUnavailableError(TetherlandError, RuntimeError):
    """No OpenGL context can be created (offscreen) or no display exists (viewer)."""



@dataclass(frozen=True)
class VideoInfo:
    """An mp4 written by :func:`render_log` or :class:`VideoRecorder`.

    Attributes
    ----------
    path : Path
    frames : int
    fps : float
    width, height : int [px]
    """

    path: Path
    frames: int
    fps: float
    width: int
    height: int


def framing_camera(layout: SceneLayout, path_W: FloatArray | None = None) -> mujoco.MjvCamera:
    """A free camera framing the anchor, the landing point and the flown path [m, deg]."""
    geo = layout.geometry
    pts = [geo.p_A, geo.p_L, geo.p_R_landed]
    if path_W is not None and len(path_W):
        finite = path_W[np.all(np.isfinite(path_W), axis=1)]
        if len(finite):
            pts += [finite.min(axis=0), finite.max(axis=0)]
    pts_arr = np.array(pts)
    lo, hi = pts_arr.min(axis=0), pts_arr.max(axis=0)
    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = 0.5 * (lo + hi)
    radius = 0.5 * float(np.linalg.norm(hi - lo)) + 0.3
    cam.distance = 1.15 * radius / math.tan(math.radians(45.0) / 2)
    y_A = geo.R_WA[:, 1]
    cam.azimuth = math.degrees(math.atan2(y_A[1], y_A[0])) + CAMERA_AZIMUTH_OFFSET_DEG
    cam.elevation = CAMERA_ELEVATION_DEG
    return cam


class SceneRenderer:
    """Offscreen renderer of one scene (a :class:`Plant`'s model, or a replay copy).

    Parameters
    ----------
    plant : Plant
        Provides the model, data and layout; rendering reads them, never steps.
    width, height : int
        Image size [px].
    camera : mujoco.MjvCamera, optional
        Default: :func:`framing_camera`.
    detail : bool
        Draw shadows, reflections, the skybox and multisampled edges (several times the
        cost of the plain image without a GPU).

    Raises
    ------
    RenderUnavailableError
        If no GL context can be created (e.g. no ``MUJOCO_GL=egl`` on a headless machine).
    """

    def __init__(
        self,
        plant: Plant,
        width: int = DEFAULT_SIZE[0],
        height: int = DEFAULT_SIZE[1],
        camera: mujoco.MjvCamera | None = None,
        detail: bool = False,
    ) -> None:
        self.plant = plant
        self.camera = framing_camera(plant.layout) if camera is None else camera
        self.detail = detail
        _check_offscreen_backend()
        quality = plant.model.vis.quality
        samples = quality.offsamples
        quality.offsamples = samples if detail else 0  # read when the context is made
        try:
            self._renderer = mujoco.Renderer(plant.model, height=height, width=width, max_geom=500)
        except Exception as err:  # GL backends raise a variety of types
            gl = os.environ.get("MUJOCO_GL", "<unset>")
            raise RenderUnavailableError(
                f"cannot create an offscreen OpenGL context (MUJOCO_GL={gl}): {err}. On a "
                "machine without a display, start Python with MUJOCO_GL=egl (or osmesa)"
            ) from None
        finally:
            quality.offsamples = samples
        self._opt = mujoco.MjvOption()
        self._opt.geomgroup[:] = [1, 1, 1, 0, 0, 0]  # collision-only (3) and sites hidden
        self._opt.sitegroup[:] = [1, 0, 0, 0, 0, 0]
        self._opt.tendongroup[:] = [1, 1, 1, 0, 0, 0]  # a disengaged cable sits in group 5
        self._att_site = mujoco.mj_name2id(plant.model, mujoco.mjtObj.mjOBJ_SITE, "attachment")

    def close(self) -> None:
        self._renderer.close()

    def __enter__(self) -> SceneRenderer:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def render(self) -> np.ndarray:
        """RGB image (height, width, 3) uint8 of the plant's current kinematics (a copy)."""
        plant = self.plant
        r = self._renderer
        r.update_scene(plant.data, camera=self.camera, scene_option=self._opt)
        if not self.detail:
            flags = r.scene.flags
            for flag in _COSTLY_FLAGS:
                flags[flag] = 0
        if not plant.cable_engaged:
            self._draw_hook()
        image = r.render().copy()
        if not self.detail:
            image[~image.any(axis=2)] = _SKY_RGB
        return image

    def _draw_hook(self) -> None:
        scene = self._renderer.scene
        drop = self.plant.scenario.tether.hook_drop
        if drop <= 0 or scene.ngeom >= scene.maxgeom:
            return
        top = self.plant.data.site_xpos[self._att_site]
        bottom = self.plant.hook.hook_point(top)  # hook_drop along the approach direction
        geom = scene.geoms[scene.ngeom]
        mujoco.mjv_initGeom(
            geom,
            mujoco.mjtGeom.mjGEOM_CAPSULE,
            np.zeros(3),
            np.zeros(3),
            np.eye(3).ravel(),
            _HOOK_RGBA,
        )
        mujoco.mjv_connector(geom, mujoco.mjtGeom.mjGEOM_CAPSULE, 0.003, top.copy(), bottom)
        scene.ngeom += 1


def _check_offscreen_backend() -> None:
    """Refuse early when MuJoCo would try a windowing backend without a display (GLFW
    then fails, and a second attempt can abort the interpreter)."""
    gl = os.environ.get("MUJOCO_GL", "").lower().strip()
    if sys.platform.startswith("linux") and gl in ("", "glfw", "glx") and not has_display():
        raise RenderUnavailableError(
            f"MUJOCO_GL={gl or '<unset>'} needs a display and none is set; for offscreen "
            "rendering start Python with MUJOCO_GL=egl (or osmesa)"
        )


def scenario_of_log(log: SimLog) -> Scenario:
    """The scenario recorded in a log's provenance."""
    try:
        data = log.metadata["provenance"]["scenario"]
    except KeyError:
        raise ValueError("the log has no scenario in its provenance; pass scenario=") from None
    return scenario_from_dict(data)


def _frame_rows(t: FloatArray, fps: float, speed: float) -> FloatArray:
    """Row index shown at each video frame (the last row at or before the frame time)."""
    if len(t) == 0:
        return np.zeros(0, dtype=int)
    n = math.floor(float(t[-1] - t[0]) * fps / speed + 1e-9) + 1
    times = t[0] + np.arange(n) * speed / fps
    return np.clip(np.searchsorted(t, times + 1e-9, side="right") - 1, 0, len(t) - 1)


def _video_writer(path: str | Path, fps: float):
    import imageio.v2 as imageio

    return imageio.get_writer(
        path, format="FFMPEG", fps=fps, codec="libx264", quality=7, macro_block_size=2,
        ffmpeg_params=_ENCODER_PARAMS,
    )  # fmt: skip


def render_log(
    log: SimLog,
    path: str | Path,
    *,
    scenario: Scenario | None = None,
    options: VideoOptions | None = None,
    progress: FrameProgress | None = None,
    detail: bool = False,
) -> VideoInfo:
    """Replay a log into an mp4: the logged pose at each frame time (one frame per
    1/fps of video, ``options.speed`` x real time), never the ticks in between.

    Parameters
    ----------
    log
        A run log (its truth pose and hook columns are replayed).
    path
        Output ``.mp4`` file, written atomically.
    scenario
        Default: the scenario recorded in the log.
    options
        Frame rate, size and speed (default :class:`VideoOptions`).
    progress
        Called after each frame with (frames done, frames in all).
    detail
        See :class:`SceneRenderer`.
    """
    opts = VideoOptions() if options is None else options
    scenario = scenario_of_log(log) if scenario is None else scenario
    plant = Plant(scenario)
    rows = _frame_rows(log.t, opts.fps, opts.speed)
    qpos = np.column_stack((log["p_W"], log["q_WB"]))
    hook = log["hook"]
    camera = framing_camera(plant.layout, log["p_W"])
    with (
        SceneRenderer(plant, opts.width, opts.height, camera, detail) as renderer,
        atomic_path(path) as tmp,
    ):
        writer = _video_writer(tmp, opts.fps)
        try:
            for done, i in enumerate(rows, start=1):
                plant.show_pose(qpos[i], bool(hook[i] == 1))
                writer.append_data(renderer.render())
                if progress is not None:
                    progress(done, len(rows))
        finally:
            writer.close()
    return VideoInfo(Path(path), len(rows), opts.fps, opts.width, opts.height)


class VideoRecorder:
    """Live video of a run: pass it as a :class:`~tetherland.sim.runner.Runner` observer.

    Renders the plant every 1/fps of simulated time (times ``speed``); call :meth:`close`
    (or use it as a context manager) to finish the file.
    """

    def __init__(
        self,
        plant: Plant,
        path: str | Path,
        *,
        fps: float = DEFAULT_FPS,
        speed: float = 1.0,
        width: int = DEFAULT_SIZE[0],
        height: int = DEFAULT_SIZE[1],
        camera: mujoco.MjvCamera | None = None,
    ) -> None:
        self.path = Path(path)
        self.fps, self._period = fps, speed / fps
        self._renderer = SceneRenderer(plant, width, height, camera)
        self._tmp_ctx = atomic_path(self.path)
        self._tmp = self._tmp_ctx.__enter__()
        self._writer = _video_writer(self._tmp, fps)
        self._next = 0.0
        self.frames = 0
        self._size = (width, height)

    def __call__(self, t: float, plant: Plant) -> None:
        if t + 1e-9 < self._next:
            return
        mujoco.mj_kinematics(plant.model, plant.data)  # pose at the current time
        mujoco.mj_tendon(plant.model, plant.data)
        self._writer.append_data(self._renderer.render())
        self.frames += 1
        self._next += self._period

    def close(self) -> VideoInfo:
        """Finish and move the file into place."""
        self._writer.close()
        self._renderer.close()
        self._tmp_ctx.__exit__(None, None, None)
        return VideoInfo(self.path, self.frames, self.fps, *self._size)

    def __enter__(self) -> VideoRecorder:
        return self

    def __exit__(self, exc_type: object, exc: object, tb: object) -> None:
        if exc is None:
            self.close()
        else:
            self._writer.close()
            self._renderer.close()
            self._tmp_ctx.__exit__(exc_type, exc, tb)  # removes the temporary file


def has_display() -> bool:
    """Whether an interactive window can be opened (X11 or Wayland on Linux)."""
    if not sys.platform.startswith("linux"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def view_log(log: SimLog, *, scenario: Scenario | None = None, speed: float = 1.0) -> None:
    """Replay a log in MuJoCo's interactive viewer, in (``speed`` x) real time.

    Raises
    ------
    RenderUnavailableError
        Without a display.
    """
    if not has_display():
        raise RenderUnavailableError(
            "no display for the interactive viewer (DISPLAY/WAYLAND_DISPLAY unset); "
            "use render_log() to write an mp4 instead"
        )
    import time

    import mujoco.viewer

    scenario = scenario_of_log(log) if scenario is None else scenario
    plant = Plant(scenario)
    qpos = np.column_stack((log["p_W"], log["q_WB"]))
    t, hook = log.t, log["hook"]
    with mujoco.viewer.launch_passive(plant.model, plant.data) as viewer:
        wall0 = time.perf_counter()
        i = 0
        while viewer.is_running() and i < len(t):
            target = t[0] + (time.perf_counter() - wall0) * speed
            i = int(np.searchsorted(t, target, side="right")) - 1
            plant.show_pose(qpos[max(i, 0)], bool(hook[max(i, 0)] == 1))
            viewer.sync()
            time.sleep(1.0 / 60.0)
            if i >= len(t) - 1:
                break


def main(argv: list[str] | None = None) -> int:
    """``python -m tetherland.sim.render RUN.npz [-o OUT.mp4] [--fps F] [--speed S] [--view]``."""
    import argparse

    parser = argparse.ArgumentParser(
        prog="python -m tetherland.sim.render", description="Watch a saved run log."
    )
    parser.add_argument("log", type=Path, help="run log (.npz) written by SimLog.save")
    parser.add_argument("-o", "--output", type=Path, help="mp4 to write (default: LOG.mp4)")
    parser.add_argument("--fps", type=float, default=DEFAULT_FPS)
    parser.add_argument("--speed", type=float, default=1.0, help="playback speed factor")
    parser.add_argument("--view", action="store_true", help="interactive viewer instead")
    args = parser.parse_args(argv)
    try:
        log = SimLog.load(args.log)
        if args.view:
            view_log(log, speed=args.speed)
            return 0
        out = args.output or args.log.with_suffix(".mp4")
        info = render_log(log, out, options=VideoOptions(fps=args.fps, speed=args.speed))
    except (TetherlandError, OSError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(f"wrote {info.path} ({info.frames} frames at {info.fps:g} fps)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())


__all__ = [
    "DEFAULT_FPS",
    "DEFAULT_SIZE",
    "FPS_RANGE",
    "SIZE_RANGE",
    "FrameProgress",
    "RenderUnavailableError",
    "SceneRenderer",
    "VideoInfo",
    "VideoOptions",
    "VideoRecorder",
    "framing_camera",
    "has_display",
    "main",
    "render_log",
    "scenario_of_log",
    "view_log",
]
