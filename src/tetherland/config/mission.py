"""Mission settings (chapter section 6.6, docs/theory.md section 10).

``[mission]`` holds the mission's timing; each sub-section belongs to one reader:

- ``[mission.flight]``: the free-flight transfers between the start pad and the anchor
  (:func:`tetherland.mission.plan_mission`, the supervisor's free-flight phases);
- ``[mission.hooking]``: the passes through the anchoring mechanism, hooking and
  unhooking (:mod:`tetherland.mission.hooking`);
- ``[mission.stretch]``: taking up the cable after the hooking pass until the estimated
  tension confirms the hook (the supervisor, the estimator's taut-cable flag);
- ``[mission.touchdown]``: the end of the tethered landing, its clock slowed near the
  surface and the guarded descent past the plan (:class:`~tetherland.mission.contact.SlowApproach`,
  :func:`~tetherland.mission.contact.guarded_descent`);
- ``[mission.contact]``: the multi-signal contact rule
  (:class:`~tetherland.mission.contact.ContactRule`);
- ``[mission.detection]``: every fault limit (:class:`~tetherland.mission.faults.FaultMonitor`
  and the supervisor's own fault rules).
"""

from __future__ import annotations

from pydantic import Field

from tetherland.config.base import Section
from tetherland.config.faults import FaultDetectionConfig


class FlightConfig(Section):
    """Free-flight transfers: climb from the start pad, approach, return and landing on it."""

    takeoff_height: float = Field(1.0, gt=0, le=50)
    """Climb above the start pad before the approach [m]."""
    cruise_speed: float = Field(1.5, gt=0, le=10)
    """Peak speed of free-flight transfers [m/s]."""
    cruise_accel: float = Field(1.5, gt=0, le=20)
    """Peak acceleration of free-flight transfers [m/s^2]."""
    safe_height_margin: float = Field(0.3, ge=0, le=10)
    """Transfers between the pad and the anchor fly this much above the higher of the
    hooking start and the climb height [m]."""
    waypoint_tolerance: float = Field(0.1, gt=0, le=5)
    """Distance from the end of the climb within which the takeoff counts as done [m]."""
    pad_press_depth: float = Field(0.02, ge=0, le=0.5)
    """Landing on the start pad: the reference ends this far below the pad so that the
    landers settle on it [m]."""


class HookingConfig(Section):
    """The passes through the anchoring mechanism: hooking, retries, release and unhooking."""

    speed: float = Field(0.3, gt=0, le=5)
    """Peak speed through the anchoring mechanism (hooking and unhooking passes), also of
    the release leg and of the descent onto the start pad; the bar's unhooking flies only
    its climb at it, its other legs at the take-up's speed, shaped [m/s]."""
    approach_distance: float = Field(0.3, gt=0, le=5)
    """Hook-point distance before the capture disk where the straight hooking pass starts [m]."""
    overshoot: float = Field(0.12, gt=0, le=5)
    """Hook-point distance beyond the capture disk where the hooking pass ends [m]."""
    unhook_depth: float = Field(0.04, gt=0, le=5)
    """Hook-point distance beyond the capture disk where the reverse (unhooking) pass
    begins, at most ``overshoot``: the vehicle backs off to this depth along the
    approach direction before it crosses the disk back, so the frame keeps
    ``overshoot - unhook_depth`` more clearance from the surface than at the end of the
    hooking pass (belief errors, release transient). It must exceed the anchor's belief
    error along the approach direction, so that the hook is still beyond the true disk,
    and the position error after the release [m]."""
    min_clearance: float = Field(0.02, ge=0, le=1)
    """Least distance of the frame from the surface along the hooking pass (checked before
    the mission flies) [m]."""
    start_tolerance: float = Field(0.05, gt=0, le=1)
    """Distance from the hooking start within which the hooking pass begins [m]."""
    max_attempts: int = Field(3, ge=1, le=10)
    """Hooking attempts before the mission aborts [-]."""
    release_slack: float = Field(0.25, gt=0, le=5)
    """After the tethered takeoff: how far inside the cable length the vehicle moves to
    release the tension before the unhooking pass [m]."""


class StretchConfig(Section):
    """Taking up the cable after the hooking pass, until the estimated tension confirms the
    hook (then tethered control takes over)."""

    slack_out_distance: float = Field(0.15, gt=0, le=5)
    """After the hooking pass: how far inside the cable length the vehicle goes before the
    gentle pull that takes up the cable [m]."""
    take_up_speed_factor: float = Field(0.5, gt=0, le=1)
    """Speed from the end of the hooking pass to the take-up point, as a fraction of
    ``mission.flight.cruise_speed`` [-]."""
    speed: float = Field(0.15, gt=0, le=5)
    """Peak speed of the final pull that takes up the cable (gentle, no snap) [m/s]."""
    pull_margin: float = Field(0.1, ge=0, le=5)
    """Extra pull distance beyond what the planned start tension needs [m]."""
    timeout: float = Field(2.0, gt=0, le=60)
    """Time after the stretch target is reached without tension before the hook counts
    as missed (and the hooking is retried) [s]."""
    tension_threshold: float = Field(1.0, gt=0, le=1000)
    """Estimated tension above which the cable counts as taut: it ends stretching (switch
    to tethered control) and arms the anchor-belief check [N]."""
    tension_dwell: float = Field(0.2, ge=0, le=10)
    """Time the estimated tension must stay above the threshold [s]."""
    tension_tare: bool | None = None
    """Zero the tension estimate's bias on the line hanging free: over the hover at the
    first hooking start the robot fits the estimate's bias along the thrust axis (the
    believed thrust coefficient's and mass's errors) against the believed weight of what
    hangs on the line, and every later reading of the supervisor and its fault rules
    (taut, anchor belief, unhooking climb, hook jam, snap, slack) is taken less it
    (:class:`tetherland.estimation.TensionTare`; the controllers keep the estimate as it
    is). None: with the bar mechanism only (its hanging line and hook) [-]."""


class TouchdownConfig(Section):
    """The end of the tethered landing: the plan's clock slowed near the surface, the rate
    hold, the lateral release and the guarded descent past the plan."""

    approach_speed: float = Field(0.03, ge=0, le=5)
    """Slow approach: within reach of the believed surface the planned landing's clock is
    slowed so that the link reference approaches the surface no faster than this plus
    ``approach_gain`` times the estimated lander clearance (0: no slowing) [m/s]."""
    approach_gain: float = Field(2.0, ge=0, le=100)
    """Slow approach: the allowed approach speed grows by this per metre of clearance [1/s]."""
    hold_rate: float = Field(0.15, ge=0, le=50)
    """Rate hold: within ``hold_clearance`` of the believed surface the planned landing's
    clock stops while the estimated roll-pitch rate |(omega_x, omega_y)| is above this, so
    the landers do not meet the surface while the frame still rotates, e.g. from a gust
    (condition (3); 0: no hold) [rad/s]."""
    hold_lateral_speed: float = Field(0.0, ge=0, le=5)
    """Rate hold on the swing: within ``hold_clearance`` the clock runs backwards (as for
    ``hold_rate``) while the estimated sideways speed of the link l |delta'| is above
    this, so the landers do not meet the surface while the vehicle swings along it (a
    gust's push on the lateral release); once the landers are sensed on the surface (the
    preload's start) it only stands still: the slip counts from the first touch, and a
    vehicle that has touched must not leave to land elsewhere. On a wall the rotors carry a
    quarter of the weight and the released azimuth swings like a pendulum of the cable's
    length: a 0.5 N gust sets it swinging at 3-5 cm/s, and landers that meet the wall
    mid-swing slide along it until the preload holds them (condition (5); ``wall90``,
    ``overhang93``: 0.015 m/s; 0: off, the default: on slopes the frame's rate hold
    suffices) [m/s]."""
    hold_clearance: float = Field(0.03, ge=0, le=1)
    """Rate hold: the estimated lander clearance below which it acts [m]."""
    hold_max_time: float = Field(1.5, ge=0, le=60)
    """Rate hold: the longest total time the landing's clock may stand still [s]."""
    hold_retreat: float = Field(1.0, ge=0, le=5)
    """Rate hold: while held, the landing's clock runs backwards at this rate, so the
    reference backs away from the surface along the plan instead of only stopping (a
    vehicle approaching at a few cm/s does not stop within the last centimetre; 0: the
    clock stands still) [-]."""
    lateral_clearance: float | None = Field(None, ge=0, le=1)
    """Lateral release: within this estimated lander clearance of the believed surface, and
    through the guarded descent, the link azimuth is let hang where gravity puts it
    (``Reference.lateral_free``): the hierarchical law's sideways force is then a fraction
    of its damping alone (``controller.tethered.lateral_damping``). Held at the believed
    delta = 0 instead, a vehicle whose true plumb plane is delta off (an anchor belief
    error sideways, an azimuth error) needs a sideways thrust m g sin(phi) sin(delta): a
    tilt of about 3.7 delta on a wall, where the rotors carry only a quarter of the
    weight, 2.5 delta at 70 deg (condition (2)); hanging free it also lands nearer the
    true landing point, which lies in the true plumb plane; it ends at the first sign of
    contact with ``lateral_lock`` (0: off). None: 0.05 m, and off with the bar mechanism
    (:func:`tetherland.mission.contact.lateral_release_clearance`): the hook seats on the
    anchoring cable wherever the line crosses it, and slides along it after the vehicle
    in the swing and the stretch, which the vehicle flies in its believed plane; the
    true pivot is then beside the anchor by about the believed plane's error there (the
    azimuth error over the cable's length), and hanging free swung the vehicle on into
    that pivot's plumb plane, 1.1-1.2 cm farther from the landing point (35 deg bar sweep,
    draws 00037 and 00038: 3.0 and 3.4 cm, condition (1)) [m]."""
    lean_limit_deg: float | None = Field(None, ge=0, le=30)
    """Lean limit: through the tethered landing and the touchdown, the desired thrust axis
    leans at most this far out of the link plane (``Reference.lean_limit``: the sideways
    force is cut, the vehicle then drifts towards its true plumb plane only as far as the
    limit needs). Held at the believed delta = 0, a vehicle whose true plumb plane is off
    (an anchor belief error sideways) needs a sideways thrust that tilts it, the more the
    larger the cable's pull against the rotors' (the bar at 70 deg with the line at the
    centre of mass: 9.3 N against 0.75 N per rotor, 2.4-3.1 deg out of the plane in the last
    0.5 s of two campaign draws, condition (2)); the lateral release (``lateral_clearance``)
    lets the azimuth hang for good instead, and lands in the true plumb plane, farther from
    the landing point. The hierarchical law only. None: 2.5 deg with the bar mechanism,
    whose lateral release is off (docs/mechanism.md, *The lean limit*), no limit
    otherwise (:func:`tetherland.mission.contact.lean_limit`); 0: no limit [deg]."""
    lateral_lock: bool = True
    """Lateral lock: end the lateral release at the first sign of contact (the landers
    within ``contact.clearance`` of the believed surface and the surface force or an impact
    sensed) and hold the link azimuth where it is: on a slope a vehicle on barely loaded
    landers that still hangs free slides sideways along the surface wherever a gust or a
    tilted thrust pushes it (slip, condition (5)). Off on walls (``wall90``,
    ``overhang93``): pressed on a wall the vehicle creeps sideways on its own, the held
    azimuth's pull winds up against it, and when the touchdown hold lifts the landers it
    swings away (wall90 campaign run 375278728: 15 mm, 0.48 rad/s)."""
    preload: float = Field(0.3, ge=0, lt=1)
    """Preload: once the landers have stopped on the surface (the first sign of contact,
    as for ``lateral_lock``, and the estimated link no longer descending faster than
    ``contact.stall_rate_deg_s``), up to this fraction of the commanded total thrust is
    taken off every rotor equally (as the measured surface push allows, ``preload_lead``),
    ramped in at ``preload_rate`` (``Reference.thrust_shed``; the torques are kept), so the
    landers carry part of the weight, and friction holds the vehicle against a sideways
    gust (condition (5)), through the second or two the contact confirmation takes; the
    spin-down then scales what is left to zero. A first sign alone may come while the
    landers are still a centimetre off the surface (an approach fakes the push): shedding
    from it brought two sweep runs down rocking (condition (3)), hence the stall
    (docs/results.md) (0: off) [-]."""
    preload_rate: float = Field(0.5, gt=0, le=100)
    """Preload: the rate at which the thrust fraction is shed from its start; slow, so that
    the landers take the load without a jolt (a fixed shed at 1/s made a sweep run drop
    onto the surface, condition (4)) [1/s]."""
    preload_lead: float = Field(0.2, ge=0, le=100)
    """Preload: the shed thrust follows the estimated surface push (the contact rule's,
    ``contact.surface_force``) plus this lead, up to ``preload``: only as much load as the
    landers are measured to take, so a start that comes before the true touch sheds just
    the lead [N]."""
    press_descent: bool = True
    """Press descent: once the landers have stopped on the surface (the start of the
    preload), the link elevation reference is kept no higher than a guarded descent from
    the estimated elevation there, at ``descent_rate_deg_s``. The slowed plan's reference
    lags the vehicle near the surface (0.3-1.3 deg above the link when the landers stop,
    at 60-70 deg) and its end lies above the true surface wherever the belief does: held
    up by it, the landers carried next to nothing (and left the surface for a second)
    until the contact was confirmed 1.2-2.4 s later, and a 0.4-0.5 N gust slid the vehicle
    11-15 mm (condition (5), docs/results.md). Pressed, the landers take the load and
    the contact rule's link lag grows at once, so the contact is confirmed within about
    (``contact.link_lag_deg`` / ``descent_rate_deg_s`` + ``contact.dwell``). On walls too:
    a vehicle whose link ran 2-4 deg ahead of the plan touched early, and the lagging
    reference then pulled it off the wall while the preload shed thrust; it came back a
    second later, and the wandering in between slid it 11-22 mm (condition (5), eleven
    failures of the six wall campaigns, docs/walls.md)."""
    spin_down_time: float = Field(1.0, ge=0, le=10)
    """Spin-down: from the confirmed contact (t_L) every rotor thrust is ramped linearly to
    zero over this time (``Reference.thrust_scale``), and the motors go off at its end (or
    after ``settle_time`` if longer), so the landers take the load while the vehicle is still
    controlled: the friction that holds it against a gust grows from the contact on, and
    the vehicle does not hover on barely loaded landers to drop onto them at motors-off. A
    contact lost during the ramp is regained with at most the thrust shed meanwhile as
    acceleration (condition (4)), hence the slow ramp (0: the motors go off at once after
    ``settle_time``) [s]."""
    descent_rate_deg_s: float = Field(2.0, gt=0, le=45)
    """Guarded descent: after the planned landing, the link elevation reference keeps
    descending at this rate until contact is detected (surface closer or farther than
    believed) [deg/s]."""
    search_depth_deg: float = Field(6.0, gt=0, le=45)
    """Guarded descent: how far beyond the planned phi* the search goes [deg]."""


class ContactConfig(Section):
    """The multi-signal contact rule of the guarded touchdown (docs/theory.md section 10.2),
    on the robot's estimate and belief."""

    window: float = Field(0.25, ge=0, le=1)
    """Fraction of the landing duration, at its end, in which early contact is detected [-]."""
    gate_deg: float = Field(2.0, gt=0, le=45)
    """Early contact is believed only when the estimated link elevation is within this of
    the believed phi* (the surface cannot be much higher than believed); farther up, a
    lagging link is a tracking error, not the surface [deg]."""
    clearance: float = Field(0.015, gt=0, le=1)
    """Signal "clearance": the lowest lander tip of the estimated pose is less than this
    above the believed surface [m]."""
    link_lag_deg: float = Field(0.8, gt=0, le=45)
    """Signal "link stall": the estimated link elevation stays this far above the
    descending reference (the surface stops the vehicle) [deg]."""
    stall_rate_deg_s: float = Field(0.5, gt=0, le=45)
    """Signal "link stall": ... while the estimated link elevation descends slower than
    this (a link that still descends lags its reference; a stopped one is held) [deg/s]."""
    creep_rate_deg_s: float = Field(1.5, gt=0, le=45)
    """Signal "link stall": ... and rises slower than this: a vehicle pressed on a wall
    creeps up it slowly while the reference descends (the surface holds it); a bounce or
    a gust moves the link faster [deg/s]."""
    surface_force: float = Field(0.15, ge=0, le=100)
    """Signal "surface force": the estimated external force across the cable, on the
    believed surface normal and low-passed, exceeds this (the robot's estimate of the
    surface's push; the judge's truth is ``verdict.touchdown_force``) [N]."""
    surface_force_time_constant: float = Field(0.05, ge=0, le=5)
    """Time constant of the low-pass of the estimated surface force [s]."""
    tare_time_constant: float = Field(0.0, ge=0, le=5)
    """Tare of the estimated surface force: while the lowest lander tip is estimated more
    than ``clearance`` above the believed surface (no contact is possible), the estimate is
    low-passed with this time constant, and from the first tick within ``clearance`` that
    baseline (the estimate's own bias: thrust coefficient, mass and ground-effect belief
    errors, about -0.2 N on perturbed 50 deg landings) is held and subtracted from the
    estimate the rule and the preload read (0, the default: no tare; 0.2 is the value
    measured in docs/aero.md) [s]."""
    impact_force: float = Field(1.5, gt=0, le=1000)
    """Signal "surface force": ... or one unfiltered sample of it exceeded this within
    twice the dwell (an impact) [N]."""
    dwell: float = Field(0.3, ge=0, le=5)
    """Contact is confirmed when every signal has held for this long (longer than a gust
    stalls the link) [s]."""
    press_deg: float = Field(0.3, ge=0, le=10)
    """After contact the link reference is held this far below the contact elevation, so
    that the landers stay loaded until the motors go off [deg]."""


class MissionConfig(Section):
    """The full mission: phase timing at the top, one sub-section per reader."""

    settle_time: float = Field(0.5, ge=0, le=10)
    """Hold after a planned tethered maneuver, a transfer or a touchdown before the next
    phase [s]."""
    blend_time: float = Field(1.0, gt=0, le=10)
    """Bumpless transfer: time over which the reference moves from the current output onto
    the planned tethered trajectory [s]."""
    deploy_time: float = Field(2.0, ge=0, le=600)
    """Time on the surface with motors off, t_T - t_G [s]."""
    spinup_time: float = Field(0.5, ge=0, le=10)
    """Motors back on, holding the landed output, before the tethered takeoff [s]."""
    abort_time: float | None = Field(None, ge=0, le=3600)
    """Operator abort at this mission time (None: no abort) [s]."""
    safe_hover_time: float = Field(2.0, gt=0, le=60)
    """Time the safe hover is held after an abort; the run ends after it once the vehicle
    is still (``safe_hover_settle_speed``) [s]."""
    safe_hover_settle_speed: float = Field(0.1, gt=0, le=5)
    """After ``safe_hover_time`` the safe hover is held until the estimated speed has stayed
    below this for ``settle_time`` (a vehicle recovering from a lost cable or a fault is
    not yet in its safe state while it still moves) [m/s]."""
    safe_hover_max_time: float = Field(10.0, ge=0, le=600)
    """Longest time the safe hover is held beyond ``safe_hover_time`` waiting for the
    vehicle to be still; the run then ends as it is [s]."""
    done_hold_time: float = Field(0.5, ge=0, le=10)
    """Simulated time with the motors off on the pad before the run ends [s]."""
    time_limit: float = Field(300.0, gt=0, le=3600)
    """The run ends (failed) if the mission has not finished by this mission time, about
    a flight battery's endurance. The bar mechanism's mission takes about 150 s and each
    further hooking attempt about 60 s more (the retry, the hooking pass and the
    stretch), so ``hooking.max_attempts`` = 3 needs about 270 s; at 180 s a 35 deg
    campaign draw caught on its second attempt, landed and took off, and was cut off
    in the unhooking (``no_return``) [s]."""
    flight: FlightConfig = FlightConfig()
    """Free-flight transfers between the start pad and the anchor."""
    hooking: HookingConfig = HookingConfig()
    """The passes through the anchoring mechanism."""
    stretch: StretchConfig = StretchConfig()
    """Taking up the cable after the hooking pass."""
    touchdown: TouchdownConfig = TouchdownConfig()
    """The end of the tethered landing and the guarded descent."""
    contact: ContactConfig = ContactConfig()
    """The multi-signal contact rule."""
    detection: FaultDetectionConfig = FaultDetectionConfig()
    """Every fault limit: cable slack and snap, tracking, timeouts, rotor, anchor belief,
    motion capture, hook jam."""
