"""Flights in the robotics viewers: MCAP logs and a live WebSocket view (Foxglove, Rerun).

Both sinks publish the same channels (:mod:`tetherland.viz.channels`) with Foxglove's own
schemas: FrameTransforms for the true and estimated body and the anchor, SceneUpdates for
the surface, the anchor, the planned paths and the cable (coloured by its tension), Log
messages for the supervisor's phases and the hook events, and JSON time series for the
link angles, the rotor thrusts and the tension (desired, nominal, actual) and the verdict.

- :func:`tetherland.viz.mcap.write_mcap` writes a run (:class:`RunData`) to ``run.mcap``;
- :class:`tetherland.viz.live.LiveView` streams a mission while it runs;
- :func:`tetherland.viz.layout.layout_path` is the shipped Foxglove layout (figure 6.5).

Needs the ``viz`` extra (``foxglove-sdk``, ``mcap``); importing this package without it
raises :class:`~tetherland.errors.MissingDependencyError` with the install command.
"""

from __future__ import annotations

from tetherland.optional import require

require("foxglove", package="foxglove-sdk", extra="viz", feature="the Foxglove/MCAP view")

from tetherland.viz.run import PlanSpan, RunData, load_run, run_data_from_result  # noqa: E402

__all__ = ["PlanSpan", "RunData", "load_run", "run_data_from_result"]
