"""MuJoCo simulation of the tethered quadrotor (docs/theory.md section 9, issue 4).

- :class:`Plant`: the scene built from a scenario (:func:`build_mjcf`), rotor speed
  commands through a first-order motor lag, the cable as a limited spatial tendon engaged
  and released by the :class:`Hook`, ground truth and plant sensors.
- :class:`Imu`, :class:`Mocap`: noisy sensors driven by an explicit random generator.
- :class:`Runner`: the multi-rate loop (plant 1 kHz, IMU 1 kHz, mocap 120 Hz late, control
  500 Hz) over the roles of :mod:`tetherland.interfaces`; returns a :class:`SimLog`.
- :mod:`tetherland.sim.render`: mp4 from a log or live, interactive viewer.
- :mod:`tetherland.sim.baselines`: truth estimator, constant-speed controller, constant
  reference.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

# Submodules load on first use (PEP 562), so that ``tetherland.sim.log`` (the run log,
# needed to judge a saved run) does not pull in MuJoCo.
_EXPORTS = {
    "ConstantReference": "baselines", "ConstantSpeedController": "baselines",
    "TruthEstimator": "baselines", "Hook": "hook", "HookEvent": "hook",
    "HookEventKind": "hook", "HookState": "hook", "Column": "log", "RunStatus": "log",
    "SimLog": "log", "SceneLayout": "mjcf", "build_mjcf": "mjcf", "Plant": "plant",
    "link_state_of": "plant", "Runner": "runner", "Schedule": "runner", "Imu": "sensors",
    "BoundObserver": "runner", "ControlTick": "runner",
    "Mocap": "sensors",
}  # fmt: skip

if TYPE_CHECKING:
    from tetherland.sim.baselines import ConstantReference, ConstantSpeedController, TruthEstimator
    from tetherland.sim.hook import Hook, HookEvent, HookEventKind, HookState
    from tetherland.sim.log import Column, RunStatus, SimLog
    from tetherland.sim.mjcf import SceneLayout, build_mjcf
    from tetherland.sim.plant import Plant, link_state_of
    from tetherland.sim.runner import BoundObserver, ControlTick, Runner, Schedule
    from tetherland.sim.sensors import Imu, Mocap


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'tetherland.sim' has no attribute {name!r}")
    return getattr(importlib.import_module(f"tetherland.sim.{module}"), name)


__all__ = [
    "BoundObserver",
    "Column",
    "ConstantReference",
    "ConstantSpeedController",
    "ControlTick",
    "Hook",
    "HookEvent",
    "HookEventKind",
    "HookState",
    "Imu",
    "Mocap",
    "Plant",
    "RunStatus",
    "Runner",
    "SceneLayout",
    "Schedule",
    "SimLog",
    "TruthEstimator",
    "build_mjcf",
    "link_state_of",
]
