"""Mission settings (chapter section 6.6, docs/theory.md section 10)."""

from __future__ import annotations

from pydantic import Field

from tetherland.config.base import Section
from tetherland.config.faults import FaultDetectionConfig


class MissionConfig(Section):
    """Supervisor thresholds, speeds, timing and fault limits of the full mission."""

    tension_threshold: float = Field(1.0, gt=0, le=1000)
    """Estimated tension that ends cable stretching (switch to tethered control) [N]."""
    tension_dwell: float = Field(0.2, ge=0, le=10)
    """Time the estimated tension must stay above the threshold [s]."""
    deploy_time: float = Field(2.0, ge=0, le=600)
    """Time on the surface with motors off, t_T - t_G [s]."""
    takeoff_height: float = Field(1.0, gt=0, le=50)
    """Climb above the start pad before the approach [m]."""
    cruise_speed: float = Field(1.5, gt=0, le=10)
    """Peak speed of free-flight transfers [m/s]."""
    cruise_accel: float = Field(1.5, gt=0, le=20)
    """Peak acceleration of free-flight transfers [m/s^2]."""
    hook_speed: float = Field(0.3, gt=0, le=5)
    """Peak speed through the anchoring mechanism (hooking and unhooking) [m/s]."""
    approach_distance: float = Field(0.3, gt=0, le=5)
    """Hook-point distance before the capture disk where the straight hooking pass starts [m]."""
    hook_overshoot: float = Field(0.12, gt=0, le=5)
    """Hook-point distance beyond the capture disk where the hooking pass ends [m]."""
    unhook_depth: float = Field(0.04, gt=0, le=5)
    """Hook-point distance beyond the capture disk where the reverse (unhooking) pass
    begins, at most ``hook_overshoot``: the vehicle backs off to this depth along the
    approach direction before it crosses the disk back, so the frame keeps
    ``hook_overshoot - unhook_depth`` more clearance from the surface than at the end of
    the hooking pass (belief errors, release transient); more than the anchor's belief
    error along the approach direction, so the hook is still beyond the true disk; and more
    than the position error after the release (chosen when the release's hand-over still
    left up to 5 cm of it, since removed: 2.5 cm and hooks that lagged outwards crossed
    the plane off the disk and never released; 5 cm, the hooking pass's end, and two
    runs touched the wall) [m]."""
    stretch_speed: float = Field(0.15, gt=0, le=5)
    """Peak speed of the final pull that takes up the cable (gentle, no snap) [m/s]."""
    stretch_margin: float = Field(0.1, ge=0, le=5)
    """Extra pull distance beyond what the planned start tension needs (stretching) [m]."""
    stretch_timeout: float = Field(2.0, gt=0, le=60)
    """Time after the stretch target is reached without tension before the hook counts
    as missed [s]."""
    max_hook_attempts: int = Field(3, ge=1, le=10)
    """Hooking attempts before the mission aborts [-]."""
    blend_time: float = Field(1.0, gt=0, le=10)
    """Bumpless transfer: time over which the reference moves from the current output onto
    the planned trajectory [s]."""
    settle_time: float = Field(0.5, ge=0, le=10)
    """Hold after a planned tethered maneuver or a transfer before the next phase [s]."""
    touchdown_rate_deg: float = Field(2.0, gt=0, le=45)
    """Guarded touchdown: after the planned landing, the link elevation reference keeps
    descending at this rate until contact is detected (surface closer or farther than
    believed) [deg/s]."""
    touchdown_approach_speed: float = Field(0.03, ge=0, le=5)
    """Slow approach: within reach of the believed surface the planned landing's clock is
    slowed so that the link reference approaches the surface no faster than this plus
    ``touchdown_approach_gain`` times the estimated lander clearance (0: no slowing) [m/s]."""
    touchdown_approach_gain: float = Field(2.0, ge=0, le=100)
    """... the allowed approach speed grows by this per metre of clearance [1/s]."""
    touchdown_hold_rate: float = Field(0.15, ge=0, le=50)
    """Rate hold: within ``touchdown_hold_clearance`` of the believed surface the planned
    landing's clock stops while the estimated roll-pitch rate |(omega_x, omega_y)| is above
    this, so the landers do not meet the surface while the frame still rotates, e.g. from
    a gust (condition (3); 0: no hold) [rad/s]."""
    touchdown_hold_clearance: float = Field(0.03, ge=0, le=1)
    """Rate hold: the estimated lander clearance below which it acts [m]."""
    touchdown_hold_max: float = Field(1.5, ge=0, le=60)
    """Rate hold: the longest total time the landing's clock may stand still [s]."""
    touchdown_hold_retreat: float = Field(1.0, ge=0, le=5)
    """Rate hold: while held, the landing's clock runs backwards at this rate, so the
    reference backs away from the surface along the plan instead of only stopping (a
    vehicle approaching at a few cm/s does not stop within the last centimetre; 0: the
    clock stands still) [-]."""
    touchdown_lateral_clearance: float = Field(0.05, ge=0, le=1)
    """Lateral release: within this estimated lander clearance of the believed surface, and
    through the guarded descent, the link azimuth is let hang where gravity puts it
    (``Reference.lateral_free``): the hierarchical law's sideways force is then a fraction
    of its damping alone (``controller.tethered.lateral_damping``). Held at the believed
    delta = 0 instead, a vehicle whose true plumb
    plane is delta off (an anchor belief error sideways, an azimuth error) needs a
    sideways thrust m g sin(phi) sin(delta): a tilt of about 3.7 delta on a wall, where
    the rotors carry only a quarter of the weight, 2.5 delta at 70 deg (condition (2));
    hanging free it also lands nearer the true landing point, which lies in the true
    plumb plane (0: off) [m]."""
    touchdown_search_deg: float = Field(6.0, gt=0, le=45)
    """Guarded touchdown: how far beyond the planned phi* the search goes [deg]."""
    contact_error_deg: float = Field(0.8, gt=0, le=45)
    """Contact signal "link stall": the estimated link elevation stays this far above the
    descending reference (the surface stops the vehicle) [deg]."""
    contact_stall_rate_deg: float = Field(0.5, gt=0, le=45)
    """... while the estimated link elevation descends slower than this (a link that still
    descends lags its reference; a stopped one is held) [deg/s]."""
    contact_creep_rate_deg: float = Field(1.5, gt=0, le=45)
    """... and rises slower than this: a vehicle pressed on a wall creeps up it slowly
    while the reference descends (the surface holds it); a bounce or a gust moves the
    link faster [deg/s]."""
    contact_clearance: float = Field(0.015, gt=0, le=1)
    """Contact signal "clearance": the lowest lander tip of the estimated pose is less than
    this above the believed surface [m]."""
    contact_force: float = Field(0.15, ge=0, le=100)
    """Contact signal "surface force": the estimated external force across the cable,
    on the believed surface normal and low-passed, exceeds this [N]."""
    ground_effect_belief: bool = True
    """The estimator multiplies the predicted rotor thrusts by the ground-effect factor of
    the believed surface at the estimated pose (the surface force and tension estimates
    then do not read the ground effect as a push); false: the estimators and the
    controllers' integrals absorb it [-]."""
    contact_force_time_constant: float = Field(0.05, ge=0, le=5)
    """Low-pass time constant of the estimated surface force [s]."""
    contact_impact_force: float = Field(1.5, gt=0, le=1000)
    """... or one unfiltered sample of it exceeded this within twice the dwell (impact) [N]."""
    contact_dwell: float = Field(0.3, ge=0, le=5)
    """Contact is confirmed when every contact signal has held for this long (longer than
    a gust stalls the link) [s]."""
    contact_press_deg: float = Field(0.3, ge=0, le=10)
    """After contact the link reference is held this far below the contact elevation, so
    that the landers stay loaded until the motors go off [deg]."""
    contact_window: float = Field(0.25, ge=0, le=1)
    """Fraction of the landing duration, at its end, in which early contact is detected [-]."""
    contact_gate_deg: float = Field(2.0, gt=0, le=45)
    """Early contact is believed only when the estimated link elevation is within this of
    the believed phi* (the surface cannot be much higher than believed); farther up, a
    lagging link is a tracking error, not the surface [deg]."""
    spinup_time: float = Field(0.5, ge=0, le=10)
    """Motors back on, holding the landed output, before the tethered takeoff [s]."""
    release_slack: float = Field(0.25, gt=0, le=5)
    """How far inside the cable length the vehicle moves to release the tension [m]."""
    abort_time: float | None = Field(None, ge=0, le=3600)
    """Operator abort at this mission time (None: no abort) [s]."""
    safe_hover_time: float = Field(2.0, gt=0, le=60)
    """Time the safe hover is held after an abort before the run ends [s]."""
    fault_min_tension: float = Field(0.1, ge=0, le=100)
    """Tethered phases: estimated tension below this counts as a slack cable [N]."""
    fault_slack_time: float = Field(0.3, gt=0, le=10)
    """How long the cable may look slack in a tethered phase before a fault [s]."""
    fault_tracking_deg: float = Field(15.0, gt=0, le=90)
    """Tethered phases: link-angle tracking error that counts as a fault [deg]."""
    waypoint_tolerance: float = Field(0.1, gt=0, le=5)
    """Distance from the end of the climb within which the takeoff counts as done [m]."""
    hook_start_tolerance: float = Field(0.05, gt=0, le=1)
    """Distance from the hooking start within which the hooking pass begins [m]."""
    phase_timeout: float = Field(5.0, gt=0, le=120)
    """Free-flight legs (climb, approach): time past the planned arrival before a fault [s]."""
    hooking_clearance: float = Field(0.02, ge=0, le=1)
    """Least distance of the frame from the surface along the hooking pass (checked before
    the mission flies) [m]."""
    slack_out_distance: float = Field(0.15, gt=0, le=5)
    """After the hooking pass: how far inside the cable length the vehicle goes before the
    gentle pull that takes up the cable [m]."""
    take_up_speed_factor: float = Field(0.5, gt=0, le=1)
    """Speed from the end of the hooking pass to the take-up point, as a fraction of
    ``cruise_speed`` [-]."""
    safe_height_margin: float = Field(0.3, ge=0, le=10)
    """Transfers between the pad and the anchor fly this much above the higher of the
    hooking start and the climb height [m]."""
    takeoff_fault_delay: float = Field(0.5, ge=0, le=10)
    """Tethered takeoff: slack-cable and tracking faults are checked from this long after
    the takeoff trajectory starts (the cable takes up the load) [s]."""
    touchdown_search_grace: float = Field(1.0, ge=0, le=60)
    """Guarded touchdown: time past the full search depth before 'no contact' is a fault [s]."""
    pad_press_depth: float = Field(0.02, ge=0, le=0.5)
    """Landing on the start pad: the reference ends this far below the pad so that the
    landers settle on it [m]."""
    done_hold_time: float = Field(0.5, ge=0, le=10)
    """Simulated time with the motors off on the pad before the run ends [s]."""
    max_duration: float = Field(180.0, gt=0, le=3600)
    """The run ends (failed) if the mission has not finished by then [s]."""
    detection: FaultDetectionConfig = FaultDetectionConfig()
    """Limits of the fault monitor (rotor, anchor belief, motion capture, hook jam)."""
