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

from tetherland.sim.baselines import ConstantReference, ConstantSpeedController, TruthEstimator
from tetherland.sim.hook import Hook, HookEvent, HookEventKind, HookState
from tetherland.sim.log import Column, RunStatus, SimLog
from tetherland.sim.mjcf import SceneLayout, build_mjcf
from tetherland.sim.plant import Plant, link_state_of
from tetherland.sim.runner import BoundObserver, ControlTick, Runner, Schedule
from tetherland.sim.sensors import Imu, Mocap

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
