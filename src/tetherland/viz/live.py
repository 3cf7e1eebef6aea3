"""Watch a mission live: the channels of the MCAP export over the SDK's WebSocket server.

:class:`LiveView` is a :class:`~tetherland.sim.BoundObserver` of the runner: at each control
tick it reads the log row just written and publishes it (``tetherland mission --live``).
With no viewer subscribed it only checks that and paces the loop, so the mission runs
essentially as fast as without it; ``speed`` paces simulated time to ``speed`` x wall time
(0: as fast as possible), and ``rate_hz`` limits the publishing rate. Connect Foxglove to
``ws://HOST:PORT`` (Open connection > Foxglove WebSocket).
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from enum import IntEnum
from typing import Any

import foxglove
import numpy as np

from tetherland.config import Scenario
from tetherland.errors import ConfigError
from tetherland.geometry import LandingGeometry
from tetherland.planning.trajectory import Trajectory
from tetherland.sim.log import SimLog, row_width
from tetherland.viz.mcap import make_publisher
from tetherland.viz.run import PlanSpan, plan_spans
from tetherland.viz.series import NominalPlan, NominalValues, tick_series


class LiveView:
    """Streams a run while it is simulated (bound observer of :class:`tetherland.sim.Runner`).

    Parameters
    ----------
    scenario : Scenario
        The scenario the plant simulates (scene and geometry).
    host : str
        Interface to serve on (``127.0.0.1``: this machine only).
    port : int
        TCP port (0: any free port, see :attr:`port`).
    speed : float
        Simulated seconds per wall-clock second (1: real time; 0: unpaced) [-].
    rate_hz : float
        Publishing rate [Hz] in [1, 10000]; at most one message per topic per control tick
        (a viewer draws at display rate: 100 Hz keeps the mission real time with a viewer
        connected; the control rate sends every tick, like the MCAP file).
    """

    def __init__(
        self,
        scenario: Scenario,
        *,
        host: str = "127.0.0.1",
        port: int = 8765,
        speed: float = 1.0,
        rate_hz: float = 100.0,
    ) -> None:
        if not (speed >= 0 and math.isfinite(speed)):
            raise ConfigError(f"--live-speed must be a number >= 0 (got {speed})")
        if not 1 <= rate_hz <= 10_000:
            raise ConfigError(f"--live-rate must be in [1, 10000] Hz (got {rate_hz})")
        self.period = 1.0 / rate_hz
        if not 0 <= port <= 65535:
            raise ConfigError(f"--live-port must be in 0..65535 (got {port})")
        self.scenario = scenario
        self.speed = float(speed)
        self.context = foxglove.Context()
        self._plans: list[Trajectory] = []
        self._geometry = LandingGeometry.from_scenario(scenario)
        self.publisher = make_publisher(self.context, scenario, lambda: self._plans)
        try:
            self.server = foxglove.start_server(
                name=f"tetherland {scenario.name}", host=host, port=port, context=self.context
            )
        except RuntimeError as err:
            raise ConfigError(f"--live-port {port}: cannot serve on {host}: {err}") from err
        self._runner: Any = None
        self._writer: Any = None
        self._grids: dict[tuple[str, float], tuple[float, NominalValues]] = {}
        self._published = {"hook": 0, "mission": 0}
        self._wall0 = 0.0
        self._t_last = 0.0

    @property
    def port(self) -> int:
        """The TCP port the server listens on."""
        return int(self.server.port)

    @property
    def url(self) -> str:
        return f"ws://127.0.0.1:{self.port}"

    # ---------------------------------------------------------------- BoundObserver
    def bind(self, runner: Any, writer: Any) -> None:
        """A run starts: remember its writer, its reference (plans) and the wall clock."""
        self._runner, self._writer = runner, writer
        self._row = SimLog(writer.columns, np.empty((1, row_width(writer.columns))))
        self._grids.clear()
        self._published = {"hook": 0, "mission": 0}
        ref = runner.reference
        plans = (getattr(ref, "landing_traj", None), getattr(ref, "takeoff_traj", None))
        self._plans = [p for p in plans if p is not None]
        phase = getattr(ref, "phase", None)  # the reference's phase enum names its codes
        if isinstance(phase, IntEnum):
            self.publisher.phase_names = {int(p): p.name.lower() for p in type(phase)}
        self._wall0 = time.perf_counter()
        self._next_publish = 0.0

    def __call__(self, t: float, plant: Any) -> None:
        self._t_last = t
        if self.speed > 0:
            ahead = self._wall0 + t / self.speed - time.perf_counter()
            if ahead > 1e-3:
                time.sleep(ahead)
        if t < self._next_publish - 1e-9 or not self.publisher.watched:
            return
        self._next_publish = t + self.period
        row = self._row
        row.matrix[0] = self._writer.last_row
        series = tick_series(row, self.scenario, self._nominal(t), self._geometry)
        self._events(plant)
        self.publisher.publish_tick(series, 0)

    # ---------------------------------------------------------------- helpers
    def _nominal(self, t: float) -> NominalValues | None:
        """Nominal values at ``t`` from the plan grid of the span being flown (if any)."""
        ref = self._runner.reference
        times = getattr(ref, "times", None)
        if not times:
            return None
        cfg = getattr(ref, "cfg", None)
        spinup = cfg.spinup_time if cfg is not None else 0.0
        spans = plan_spans(times, getattr(ref, "landing_traj", None),
                           getattr(ref, "takeoff_traj", None), spinup)  # fmt: skip
        for span in spans:
            if not span.t0 <= t <= span.t1:
                continue
            key = (span.name, span.t0)
            if key not in self._grids:
                dt = 1.0 / self.scenario.controller.rate_hz
                grid = span.t0 + np.arange(math.ceil(span.trajectory.duration / dt) + 2) * dt
                open_span = [PlanSpan(span.name, span.trajectory, span.t0)]
                self._grids[key] = (dt, NominalPlan(self.scenario, open_span).evaluate(grid))
            dt, values = self._grids[key]
            j = min(round((t - span.t0) / dt), len(values.phi) - 1)
            return NominalValues(values.phi[j : j + 1], values.theta_A[j : j + 1],
                                 values.psi[j : j + 1], values.tension[j : j + 1],
                                 values.rotor_thrusts[j : j + 1])  # fmt: skip
        return None

    def _events(self, plant: Any) -> None:
        """Publish the hook and supervisor events that are new since the last tick."""
        hook = plant.hook.events
        for e in hook[self._published["hook"] :]:
            self.publisher.publish_event(dict(e.as_dict(), source="hook"))
        self._published["hook"] = len(hook)
        mission: Sequence[Any] = getattr(self._runner.reference, "events", ())
        for e in mission[self._published["mission"] :]:
            self.publisher.publish_event(e.as_dict())
        self._published["mission"] = len(mission)

    # ---------------------------------------------------------------- end
    def finish(self, summary: dict[str, Any]) -> None:
        """Publish the verdict of the run that just ended."""
        self.publisher.publish_verdict(self._t_last, summary)

    def close(self) -> None:
        """Stop the server (viewers keep what they received)."""
        self.publisher.close()
        self.server.stop()

    def __enter__(self) -> LiveView:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
