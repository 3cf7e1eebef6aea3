"""Fault injection (issue 15): what ``[faults]`` does to the plant, its sensors and the belief.

* rotor efficiency: from ``rotor_fault_time`` the rotors push ``eff_i c_f w_i^2`` (the
  MuJoCo actuator gear, :meth:`~tetherland.sim.plant.Plant.set_rotor_efficiency`);
* cable snap: at ``cable_snap_time`` the cable is detached and can never engage again
  (:meth:`~tetherland.sim.plant.Plant.snap_cable`);
* hook jam: the hook does not release the cable (:attr:`~tetherland.sim.hook.Hook.jammed`);
* motion-capture outage: no pose is delivered for measurement times in
  [start, start + duration) (:func:`mocap_outage`, given to :class:`~tetherland.sim.Mocap`);
* anchor belief error: the robot's belief puts the anchor at p_A + e (:func:`faulty_belief`).

The plant-side faults act through :class:`FaultInjector`, an observer the runner binds to
every run of a scenario whose ``[faults]`` is active; times are applied at the control
tick at or after them (2 ms at 500 Hz). The belief never carries ``[faults]``.
"""

from __future__ import annotations

import numpy as np

from tetherland.config import FaultsConfig, Scenario, scenario_from_dict
from tetherland.errors import ConfigError
from tetherland.geometry import LandingGeometry
from tetherland.sim.log import LogWriter
from tetherland.sim.plant import Plant


def mocap_outage(faults: FaultsConfig) -> tuple[float, float] | None:
    """The outage window [start, end) of ``faults`` [s], or None."""
    if faults.mocap_outage_start is None:
        return None
    return (faults.mocap_outage_start, faults.mocap_outage_start + faults.mocap_outage_duration)


class FaultInjector:
    """Runner observer applying the plant-side faults of a ``[faults]`` section.

    Parameters
    ----------
    faults : FaultsConfig

    Attributes
    ----------
    applied : dict of str to float
        When each fault took effect in the current run [s] (``rotor``, ``snap``).
    """

    def __init__(self, faults: FaultsConfig) -> None:
        self.faults = faults
        self.applied: dict[str, float] = {}
        self._plant: Plant | None = None

    def bind(self, runner: object, writer: LogWriter) -> None:
        """A run starts (the plant was just reset): arm the faults."""
        plant = runner.plant  # type: ignore[attr-defined]
        self._plant = plant
        self.applied = {}
        plant.hook.jammed = self.faults.hook_jam
        self(0.0, plant)

    def __call__(self, t: float, plant: Plant) -> None:
        f = self.faults
        if f.rotor_fault and "rotor" not in self.applied and t >= f.rotor_fault_time:
            plant.set_rotor_efficiency(f.rotor_efficiency)
            self.applied["rotor"] = t
        snap = f.cable_snap_time
        if snap is not None and "snap" not in self.applied and t >= snap:
            plant.snap_cable()
            self.applied["snap"] = t


def faulty_belief(belief: Scenario, faults: FaultsConfig) -> Scenario:
    """The belief the robot flies on: ``belief`` without ``[faults]`` and with the anchor
    displaced by ``faults.anchor_belief_error`` (its height h_A above the believed surface
    follows the displacement's normal component: with the bar as its believed standoff,
    with the magnet as its believed plate's thickness,
    :meth:`~tetherland.config.MechanismConfig.anchor_height_fields`).

    Raises
    ------
    ConfigError
        If the displaced anchor would lie below the believed surface.
    """
    data = belief.model_dump(mode="python")
    data.pop("faults", None)
    if faults.anchor_error:
        geo = LandingGeometry.from_scenario(belief)
        e = np.asarray(faults.anchor_belief_error, dtype=float)
        p_A = geo.p_A + e
        h_A = belief.anchor.h_A + float(geo.surface.z_S @ e)
        if h_A < 0.0:
            raise ConfigError(
                f"faults.anchor_belief_error = {faults.anchor_belief_error} m puts the believed "
                f"anchor {-h_A:.3g} m below the surface (its normal component must be >= "
                f"-anchor.h_A = {-belief.anchor.h_A:g} m)"
            )
        # the bar's believed standoff or the magnet's believed plate gives that height
        held, fields = belief.mechanism.anchor_height_fields(h_A)
        if abs(held - h_A) > 1e-9:
            raise ConfigError(
                f"faults.anchor_belief_error = {faults.anchor_belief_error} m puts the believed "
                f"anchor {h_A:.3g} m above the surface, where mechanism.kind = "
                f'"{belief.mechanism.kind}" cannot hold it (at least {held:.3g} m)'
            )
        data["mechanism"].update(fields)
        data["anchor"] = {"position": tuple(float(x) for x in p_A), "landing_point": None,
                          "h_A": h_A}  # fmt: skip
    return scenario_from_dict(data, belief.name)


__all__ = ["FaultInjector", "faulty_belief", "mocap_outage"]
