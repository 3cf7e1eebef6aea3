"""Fault injection (``[faults]``, the plant's truth) and fault detection limits
(``[mission.detection]``, what the robot's supervisor uses).

``[faults]`` says what goes wrong in the simulated world; the default is no fault. The
robot never reads it: the belief a run flies on has it reset (:mod:`tetherland.sim.faults`),
so every fault must be detected from what the robot measures
(:mod:`tetherland.mission.faults`).
"""

from __future__ import annotations

import enum
import math
from typing import Annotated

from pydantic import Field, model_validator

from tetherland.config.base import Section

Efficiency = Annotated[float, Field(gt=0, le=1)]
"""A rotor thrust factor in (0, 1]."""
AnchorError = Annotated[float, Field(ge=-0.5, le=0.5)]
"""One component of the anchor belief error, in [-0.5, 0.5] m."""


class FaultKind(enum.Enum):
    """The injectable fault kinds (campaign names)."""

    ROTOR = "rotor"
    SNAP = "snap"
    MOCAP = "mocap"
    ANCHOR = "anchor"
    JAM = "jam"


class FaultsConfig(Section):
    """What goes wrong in the plant, its sensors or the robot's belief (default: nothing)."""

    rotor_efficiency: tuple[Efficiency, Efficiency, Efficiency, Efficiency] = (1.0, 1.0, 1.0, 1.0)
    """Thrust (and drag torque) factor of each rotor from ``rotor_fault_time`` on [-]."""
    rotor_fault_time: float = Field(0.0, ge=0, le=3600)
    """Mission time from which ``rotor_efficiency`` applies [s]."""
    cable_snap_time: float | None = Field(None, ge=0, le=3600)
    """Mission time at which the cable breaks (None: never) [s]."""
    mocap_outage_start: float | None = Field(None, ge=0, le=3600)
    """Mission time at which motion capture stops delivering poses (None: no outage) [s]."""
    mocap_outage_duration: float = Field(1.0, gt=0, le=3600)
    """Length of the motion-capture outage [s]."""
    anchor_belief_error: tuple[AnchorError, AnchorError, AnchorError] = (0.0, 0.0, 0.0)
    """The robot believes the anchor at p_A + this (F_W) [m]."""
    hook_jam: bool = False
    """The hook does not release the cable (the unhooking pass leaves it engaged)."""

    @model_validator(mode="after")
    def _finite_outage(self) -> FaultsConfig:
        if self.mocap_outage_start is not None and not math.isfinite(
            self.mocap_outage_start + self.mocap_outage_duration
        ):
            raise ValueError("mocap_outage_start + mocap_outage_duration must be finite")
        return self

    @property
    def rotor_fault(self) -> bool:
        """Some rotor has a thrust factor below 1."""
        return any(e < 1.0 for e in self.rotor_efficiency)

    @property
    def anchor_error(self) -> bool:
        return any(e != 0.0 for e in self.anchor_belief_error)

    def kinds(self) -> tuple[FaultKind, ...]:
        """The fault kinds this section injects (empty: none)."""
        kinds = []
        if self.rotor_fault:
            kinds.append(FaultKind.ROTOR)
        if self.cable_snap_time is not None:
            kinds.append(FaultKind.SNAP)
        if self.mocap_outage_start is not None:
            kinds.append(FaultKind.MOCAP)
        if self.anchor_error:
            kinds.append(FaultKind.ANCHOR)
        if self.hook_jam:
            kinds.append(FaultKind.JAM)
        return tuple(kinds)

    @property
    def active(self) -> bool:
        """Some fault is injected."""
        return bool(self.kinds())


class FaultDetectionConfig(Section):
    """Every fault limit of the supervisor (docs/faults.md); every signal is one the robot
    measures: commanded torque, estimated tension, link geometry, the estimator's
    covariance and the mission's own clock."""

    slack_tension: float = Field(0.1, ge=0, le=100)
    """Slack cable: estimated tension below this in a tethered phase (tethered landing,
    tethered takeoff) [N]."""
    slack_dwell: float = Field(0.3, gt=0, le=10)
    """... for this long [s]."""
    tracking_error_deg: float = Field(15.0, gt=0, le=90)
    """Tracking: link elevation error to the reference in a tethered phase [deg]."""
    tethered_takeoff_delay: float = Field(0.5, ge=0, le=10)
    """Tethered takeoff: the slack-cable and tracking rules apply from this long after the
    takeoff trajectory starts (the cable takes up the load) [s]."""
    leg_timeout: float = Field(5.0, gt=0, le=120)
    """Free-flight legs (climb, approach): time past the planned arrival before a fault [s]."""
    no_contact_grace: float = Field(1.0, ge=0, le=60)
    """Guarded descent: time past the full search depth
    (``mission.touchdown.search_depth_deg``) before "no contact" is a fault [s]."""

    rotor_torque: float = Field(0.1, gt=0, le=10)
    """Rotor fault: low-passed roll/pitch torque the controller commands beyond the
    estimated cable torque [N m]."""
    rotor_torque_time_constant: float = Field(0.3, gt=0, le=10)
    """Time constant of that low-pass [s]."""
    rotor_suspect: float = Field(0.7, ge=0, le=1)
    """Near the anchoring mechanism (hooking, release, unhooking) the pass holds still
    while the low-passed torque is above this fraction of ``rotor_torque``, before the
    fault is confirmed (a weak rotor sinks and drifts the vehicle by centimetres in the
    0.3 s the rule needs; the pass keeps only ``mission.hooking.min_clearance``); 1:
    never [-]."""
    rotor_suspect_max_time: float = Field(2.0, ge=0, le=60)
    """... for at most this long in total over the mission [s]."""
    rotor_dwell: float = Field(0.15, ge=0, le=10)
    """How long the torque must stay beyond ``rotor_torque`` [s]."""
    airborne_delay: float = Field(1.5, ge=0, le=60)
    """The torque check starts this long after the takeoff from the pad, the
    motion-capture check this long into the mission [s]."""
    tethered_airborne_delay: float = Field(0.5, ge=0, le=60)
    """The torque check starts this long into a tethered takeoff, the landers off the
    surface. In healthy takeoffs the low-passed torque stays below a third of
    ``rotor_torque`` from the start (at most 0.032 N m: nominal slope50, pipe60, steep70,
    wall90, overhang93 and 25 perturbed draws each of slope50 and of wall90 with the
    magnet); a rotor weakened while landed tilts the vehicle toward a wall within 1.5 s
    (wall90 with the magnet, fault run rotor-00007: found after 1.5 s its propeller
    touched the wall 32 ms later; found after 0.5 s it is a safe stop) [s]."""
    anchor_length_error: float = Field(0.04, gt=0, le=1)
    """Anchor belief error: the taut cable's estimated length (believed anchor to the
    estimated attachment point, less the stretch) differs from the cable length by more
    than this [m]."""
    anchor_dwell: float = Field(0.2, ge=0, le=10)
    """... for this long [s]."""
    position_std: float = Field(0.0016, gt=0, le=1)
    """Motion-capture loss: the estimator's position standard deviation (largest axis)
    exceeds this, from ``airborne_delay`` into the mission (the filter has converged from
    its initial covariance). The default is passed after about 0.7 s without a pose
    (slope50 sensors; 0.2 s dropouts at 1/s stay below 1.2 mm); shorter outages are
    bridged by the IMU [m]."""
    snap_tension: float = Field(0.1, ge=0, le=100)
    """Cable snap: estimated tension below this in tethered flight [N]."""
    snap_fraction: float = Field(0.3, ge=0, lt=1)
    """... or below this fraction of the plan's tension where the plan is known (tethered
    landing and takeoff: the estimate of a lost cable stays within about 0.15 N of zero,
    but under belief errors its bias reaches about 1 N, so a relative threshold catches
    a snap under a 6 N plan at once) [-]."""
    snap_dwell: float = Field(0.04, ge=0, le=10)
    """... for this long (much shorter than the slack rule: without the cable, inclined
    hovering accelerates the vehicle at f_L/m) [s]."""
    jam_tension: float = Field(2.5, gt=0, le=1000)
    """Hook jam: estimated tension above this after the unhooking pass. Well above the
    free-flight estimate's bias under belief errors (mass and thrust coefficient 5 % off:
    about 1 N, as measured in the 70 deg campaign); a jammed hook pulls with the position
    controller's full authority once the cable is taut [N]."""
    jam_dwell: float = Field(0.2, ge=0, le=10)
    """... for this long [s]."""
    jam_slack: float = Field(0.1, ge=0, le=10)
    """... and only while the estimated attachment point is at least the cable length less
    this from the believed anchor (a cable that could be slack cannot be pulling: an
    estimated tension there is a disturbance, e.g. a gust) [m]."""
    landed_distance: float = Field(0.04, gt=0, le=10)
    """Cable lost while landed: the estimated position of the landed vehicle moved this
    far from where it was at the confirmed contact (in the spin-down) or, once the motors
    are off (motors off, spinning up), from where it was when they went off. On a slope
    steeper than the landers' friction angle only the cable holds the vehicle: without it
    the vehicle slides or falls off (from rest it falls 4 cm in 0.09 s). When the motors
    go off the vehicle settles by up to about 2 cm onto its cable and landers (walls),
    which this must exceed [m]."""
    away_distance: float = Field(0.3, ge=0, le=5)
    """Snapped cable, a fault near the mechanism, or any fault in free flight with the
    estimated landers closer than this to the believed surface: the safe hover is this far
    from the surface along z_S beyond where the fault was detected (a weak rotor near the
    surface: the reference steps there at once) [m]."""
