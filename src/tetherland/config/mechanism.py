"""The hook and the anchoring mechanism (docs/mechanism.md)."""

from __future__ import annotations

import math
from typing import Literal

from pydantic import Field, model_validator

from tetherland.config.base import Section

BAR_STANDOFF_MARGIN = 1e-3
"""Least believed clearance of the bar beyond ``bar_radius + 2 hook_radius`` [m]."""
MAGNET_PLATE_MIN = 1e-3
"""Thinnest believed plate of the magnet mechanism (the field's lower bound) [m]."""


class MechanismConfig(Section):
    """How the vehicle's cable engages the anchor (docs/mechanism.md).

    ``kind = "disk"`` (default): the hook is a point (``tether.hook_drop`` along the
    approach direction) and the cable engages when it crosses the capture disk at p_A.

    ``kind = "bar"``: the chapter's mechanism as bodies in contact. The vehicle's cable
    hangs from the attachment point as a chain of ``line_segments`` capsules ending in a
    three-tip hook (a shank, three arms at 120 deg, each with a tip pointing up); the
    anchoring mechanism is a horizontal capsule (the anchoring cable) of length
    ``bar_length`` whose axis passes through p_A, held by two posts from the surface.
    The hook catches and releases through contact and friction alone; the anchor height
    ``anchor.h_A`` is the bar's ``standoff`` (an ``anchor.h_A`` of 0, "on the surface",
    is replaced by it).

    ``kind = "magnet"``: for walls and overhangs, an electro-permanent magnet (EPM) body
    clipped to the tip of a folding boom on the vehicle is pressed on a steel plate at the
    anchor, switched on by the robot (its pull through its face on the plate only), let out of its
    clip by the latch the robot opens, and tied to the vehicle by the elastic cable;
    switched off, it lets go and hangs on the cable. The anchor height ``anchor.h_A`` is
    the cable's eye on the held magnet, ``plate_thickness + magnet_thickness`` (0 is
    replaced by it).
    """

    kind: Literal["disk", "bar", "magnet"] = "disk"
    """Mechanism: ``disk`` (a point hook and a capture disk), ``bar`` (a hook body on a
    hanging chain, caught by an anchoring cable in contact) or ``magnet`` (an
    electro-permanent magnet on a folding boom, held by a steel plate at the anchor) [-]."""
    hook_mass: float = Field(0.02, ge=0.002, le=0.5)
    """Mass of the hook body [kg]."""
    hook_shank: float = Field(0.04, ge=0.01, le=0.3)
    """Length of the hook's shank, from the eye (where the line ties on) to the crown [m]."""
    hook_reach: float = Field(0.025, ge=0.01, le=0.2)
    """Horizontal reach of each of the three arms from the shank's axis [m]."""
    hook_tip_length: float = Field(0.02, ge=0.005, le=0.2)
    """Length of each tip, pointing up from the end of its arm [m]."""
    hook_tip_angle_deg: float = Field(0.0, ge=0, le=80)
    """Angle of each tip from the shank's axis, leaning outward: 0 points it straight back
    up along the shank (a closed crook), larger opens the crook [deg]."""
    hook_arm_rise_deg: float = Field(25.0, ge=0, le=60)
    """Rise of each arm toward the shank, from the horizontal of the hanging hook: each arm
    falls from the crown to its tip by hook_reach tan(rise), so that the crook's one low
    point is the corner between the arm and the tip; 0 keeps the arms flat (the crook has
    no low point, and the bar seats anywhere along the arm that friction holds it). A bar
    pulled into the crook slides to the corner when the arm turns the push out of the
    friction cone at every contact, rise > atan(bar_friction) = atan(0.3) = 16.7 deg for
    the defaults; the validator refuses a rise whose seat (hook_radius + bar_radius) /
    tan((90 deg - rise) / 2) from the corner lies beyond the tip, above 90 deg - 2
    atan(6 mm / 20 mm) = 56.6 deg. The default 25 deg is 8.3 deg above the friction
    angle (the cone's edge turned by a friction coefficient up to tan 25 deg = 0.47) and
    31.6 deg below the limit; the bar pilot's 40 draws, replayed with it, all landed
    (flat arm: 38 of 40; docs/mechanism.md, *One seat: rising arms*) [deg]."""
    hook_radius: float = Field(0.002, ge=0.0005, le=0.02)
    """Radius of the hook's capsules (shank, arms, tips) [m]."""
    line_segments: int = Field(20, ge=4, le=60)
    """Number of capsule links of the hanging line [-]."""
    line_radius: float = Field(0.0015, ge=0.0005, le=0.01)
    """Radius of the hanging line's capsules (a 1-3 mm line) [m]."""
    line_density: float = Field(6.0e-4, gt=0, le=1)
    """Mass per length of the hanging line [kg/m]."""
    bar_length: float = Field(0.4, ge=0.05, le=5)
    """Length of the anchoring cable between its posts [m]."""
    bar_radius: float = Field(0.004, ge=0.001, le=0.05)
    """Radius of the anchoring cable (a taut cable or a rod) [m]."""
    bar_friction: float = Field(0.3, ge=0.0, le=2)
    """Friction coefficient between the anchoring cable (and posts) and the hanging line
    and hook: whether the line slides to the hook or sticks [-]."""
    standoff: float = Field(0.15, ge=0.03, le=1)
    """Height of the anchoring cable's axis above the surface, the anchor height h_A of
    this mechanism (the height of its posts) [m]."""
    pass_offset: float = Field(0.05, ge=0.01, le=0.5)
    """Horizontal distance of the hook's vertical hooking pass from the bar's axis, on the
    side away from the landing point (the line then drapes over the bar) [m]."""
    pass_depth: float = Field(0.03, ge=0.005, le=0.5)
    """Depth of the hook's crown below the bar's axis where the hooking pass ends, less
    ``pass_margin`` (with it, replaces ``mission.hooking.overshoot`` for the bar); also the
    take-up's climb: at this depth the hook's eye must be above the
    bar (hook_shank - pass_depth > bar_radius + line_radius: the line meets the bar when
    the vehicle flies toward the landing point) and the tips under it (pass_depth >
    hook_tip_length + hook_radius + bar_radius: an arm passes under the bar) [m]."""
    pass_margin: float = Field(0.03, ge=0, le=0.5)
    """Extra depth of the hooking pass below the believed bar, for the error of the bar's
    believed height (the campaign's default belief errors, a 1 deg slope error about the
    surface origin 1.2 m from the anchor and 1 cm of anchor height, reach about 3 cm):
    the pass ends with the crown ``pass_depth + pass_margin`` below the believed axis, so
    that the tips pass under a bar up to ``pass_margin`` lower than believed; a bar where
    believed meets the line just above the eye, and the take-up drags the hook up into
    it. The hook's bottom stays above the surface (pass_depth + pass_margin +
    hook_radius < standoff - pass_offset) [m]."""
    reverse_climb_offset: float = Field(0.2, ge=0.02, le=1)
    """Horizontal distance from the bar's axis, on the landing side, of the second climb
    after a reverse pass under the bar: when the climb from the pass's entry draws the line
    taut (the hook, out of its crook, hung on the bar's landing side with its line over
    the bar, and that climb lifted it into the bar), the vehicle goes back down to the
    entry, over the bar at the entry's depth (the line leaves the bar) and climbs here,
    beyond the hook's reach and its swing, to the hooking start's height. Must exceed the
    hook's outer reach + hook_radius + bar_radius, as ``pass_offset`` [m]."""
    swing_periods: float = Field(2.0, ge=0, le=10)
    """Shortest free-flight leg of the mission, in swing periods of the hanging hook
    (2 pi sqrt(L/g)): a smooth rest-to-rest leg that long leaves the hook almost still
    (the bar mechanism; not the take-up after the hooking pass, whose legs are shaped at
    that period and as short as the speed limits allow) [-]."""
    lift_margin: float = Field(0.3, ge=0, le=5)
    """The mission's takeoff point is at least this far above the hanging hook's depth
    below the vehicle (the hook leaves the ground during the climb) [m]."""
    lift_speed: float = Field(0.05, gt=0, le=5)
    """Peak climb speed of the takeoff while the hanging hook leaves the ground (within
    ``lift_band`` of the height where the line comes taut): a hook snatched off the
    ground at the climb speed bounces on the line, and that energy ends in its swing [m/s]."""
    lift_band: float = Field(0.1, ge=0, le=1)
    """Half-height of the slow part of the takeoff (``lift_speed``) around the height
    where the hanging line comes taut [m]."""
    release_depth: float = Field(0.10, gt=0, le=5)
    """Depth of the hanging hook below the bar where the unhooking pass begins (replaces
    ``mission.hooking.unhook_depth`` for the bar): flown back over the bar with that much
    slack the line slides back and the hook drops out of its crook [m]."""
    catch_threshold: float = Field(5.0, ge=1.0, le=1000)
    """The plant records the hook as caught (log column ``hook``, hook events) once the
    bar pushes on it with more than this many times its weight (the line pulls it into
    the bar), and as released once it has not touched the bar for 0.2 s; the robot never
    reads it [-]."""

    magnet_mass: float = Field(0.03, ge=0.005, le=0.5)
    """Mass of the magnet body (an EPM of the OpenGrab v3 class weighs about 30 g) [kg]."""
    magnet_radius: float = Field(0.02, ge=0.005, le=0.1)
    """Half the side of the magnet's square face (the magnet is a short square block, as
    an OpenGrab EPM v3's 40 mm housing; a box meets the plate in a face, not a point) [m]."""
    magnet_thickness: float = Field(0.015, ge=0.003, le=0.1)
    """Thickness of the magnet along its axis, face to the cable's eye on its back [m]."""
    magnet_force: float = Field(150.0, gt=0, le=2000)
    """Holding force of the energised magnet with its face flat on the plate (the plant's
    pull on the face falls with each part's gap, :mod:`tetherland.sim.epm`). An OpenGrab
    EPM v3 holds 200 N at least, 300 N typically, on thick mild steel (Zubax's data
    sheet); a plate thinner than its flux path saturates and holds less (assumed in
    proportion to the thickness below 1 cm): 150 N for the default 5 mm plate [N]."""
    epm_on_time: float = Field(0.75, ge=0.1, le=10)
    """Time the EPM takes to switch on after the command (three charge and discharge
    cycles; OpenGrab EPM v3: 0.75 s): the plant's pull builds up linearly over it, so a
    face pressed on one edge turns flat while the pull is small (switched on within a few
    physics steps, a face tilted 1 deg slammed flat and went through a 3 mm plate) [s]."""
    epm_off_time: float = Field(1.2, ge=0, le=10)
    """Time the EPM takes to switch off after the command (a decaying degauss; OpenGrab
    EPM v3: 1.2 s): the plant's holding force goes off then [s]."""
    magnet_friction: float = Field(0.25, ge=0.0, le=2)
    """Friction coefficient of the magnet's face on the plate and the surface (steel on
    steel, dry, about 0.2-0.3: an EPM holds in shear about a quarter of its normal
    force) [-]."""
    plate_size: float = Field(0.15, ge=0.04, le=2)
    """Side of the square steel plate on the surface at the anchor [m]."""
    plate_thickness: float = Field(0.005, ge=0.001, le=0.05)
    """Thickness of the steel plate [m]."""
    boom_length: float = Field(0.36, ge=0.05, le=1.5)
    """Length of the folding boom, its hinge at the cable attachment point to the cable's
    eye on the back of the clipped magnet [m]."""
    boom_angle_deg: float = Field(40.0, ge=5, le=75)
    """Angle of the unfolded boom from the approach direction, up toward z_B: a push on
    the magnet along the approach folds it up about its hinge (F L sin(angle) against the
    spring), the face sliding up the plate; it folds only while the face's friction
    coefficient is below tan(angle) (at 30 deg and 0.5 it locked: a 126 N impact) [deg]."""
    boom_stiffness: float = Field(1.0, gt=0, le=1000)
    """Stiffness of the boom's hinge spring, unfolded at its stop [N m/rad]."""
    boom_preload: float = Field(0.2, ge=0, le=100)
    """Torque with which the hinge spring holds the unfolded boom on its stop: the boom
    folds only when the push on the magnet turns it harder, and stays rigid in flight
    (unloaded, its 40 g swung off the stop at a pitch acceleration of about 17 rad/s^2,
    and the robot's rotor fault monitor stopped the flight) [N m]."""
    boom_damping: float = Field(0.05, ge=0, le=100)
    """Damping of the boom's hinge [N m s/rad]."""
    boom_fold_deg: float = Field(60.0, ge=5, le=120)
    """Largest fold of the boom from its stop [deg]."""
    clip_force: float = Field(20.0, gt=0, le=1000)
    """The spring clip that holds the magnet on the boom's tip lets go when the magnet is
    pulled out of it along its axis harder than this (its socket carries the shear and
    the moments), or when the robot opens its latch (``latch_time``) [N]."""
    latch_time: float = Field(0.2, ge=0, le=5)
    """Time the clip's latch takes to open after the robot's command (a micro servo
    pulling the clip's pin: about 0.1 s for its 60 deg at no load, doubled for the pin's
    friction under the magnet's weight): the plant lets the magnet out of its clip then.
    The clip still lets go by itself when pulled harder than ``clip_force`` [s]."""
    latch_settle: float = Field(0.25, ge=0, le=5)
    """The robot commands the latch open this long after the EPM's switching time
    ``epm_on_time`` has passed since its on command (the held magnet settled on the
    plate). It switches the EPM on only at the end of a pass its estimate shows stopped by
    the plate (the believed eye at least half of ``press_depth`` short of the pass's end);
    otherwise it flies the pass again, the magnet still clipped [s]."""
    press_depth: float = Field(0.01, gt=0, le=0.2)
    """Depth of the magnet's eye beyond the anchor where the hooking pass ends (replaces
    ``mission.hooking.overshoot`` for the magnet): the position loop presses the magnet on
    the plate; the boom folds only if the vehicle pushes harder than its preload [m]."""
    catch_time: float = Field(0.05, gt=0, le=1)
    """The plant records the magnet as caught (log column ``hook``) once it has touched
    the plate energised for this long, and as released as soon as it is off or does not
    touch the plate; the robot never reads it [s]."""

    def anchor_height_fields(self, h_A: float) -> tuple[float, dict[str, float]]:
        """A believed anchor height ``h_A`` above the surface as this mechanism can have it,
        and the mechanism fields that give it [m]: the bar's axis is the anchor, so its
        ``standoff`` is h_A (at least ``bar_radius + 2 hook_radius`` +
        :data:`BAR_STANDOFF_MARGIN`); the magnet's anchor is the cable's eye on the magnet
        held on the plate, so the robot, which knows its own magnet, believes the plate
        ``h_A - magnet_thickness`` thick (at least :data:`MAGNET_PLATE_MIN`); the point
        hook's anchor height is free. (A thicker plate than the field's range allows is
        left to the field's own error.)"""
        if self.kind == "bar":
            h = max(h_A, self.bar_radius + 2.0 * self.hook_radius + BAR_STANDOFF_MARGIN)
            return h, {"standoff": h}
        if self.kind == "magnet":
            plate = h_A - self.magnet_thickness
            if plate < MAGNET_PLATE_MIN:  # the thinnest plate, exactly
                plate, h_A = MAGNET_PLATE_MIN, MAGNET_PLATE_MIN + self.magnet_thickness
            return h_A, {"plate_thickness": plate}
        return h_A, {}

    @model_validator(mode="after")
    def _magnet_parts(self) -> MechanismConfig:
        if self.kind != "magnet":
            return self
        if self.clip_force >= self.magnet_force:
            raise ValueError(
                f"mechanism.clip_force = {self.clip_force:g} N must be < magnet_force = "
                f"{self.magnet_force:g} N (the energised magnet pulls itself off its clip)"
            )
        if self.magnet_friction >= math.tan(math.radians(self.boom_angle_deg)):
            raise ValueError(
                f"mechanism.magnet_friction = {self.magnet_friction:g} must be < "
                f"tan(boom_angle_deg) = {math.tan(math.radians(self.boom_angle_deg)):g}: "
                "the pressed boom folds only while the face slides up the plate"
            )
        if 2.0 * self.magnet_radius >= self.plate_size:
            raise ValueError(
                f"mechanism.plate_size = {self.plate_size:g} m must be > the magnet's "
                f"diameter 2 magnet_radius = {2.0 * self.magnet_radius:g} m"
            )
        return self

    @property
    def magnet_eye_height(self) -> float:
        """Height of the cable's eye (the back of the magnet) above the surface when the
        magnet is held on the plate: the anchor height h_A of the magnet [m]."""
        return self.plate_thickness + self.magnet_thickness

    @model_validator(mode="after")
    def _hook_clears_bar(self) -> MechanismConfig:
        if self.kind != "bar":
            return self
        # the crook takes the bar: the gap between the shank and a tip, at its narrowest
        # (the arm), wider than the bar (at 2 bar_radius the hook misses passes)
        crook = self.hook_reach - 2.0 * self.hook_radius
        if crook <= 2.0 * self.bar_radius:
            raise ValueError(
                f"mechanism.hook_reach = {self.hook_reach:g} m must be > 2 bar_radius + "
                f"2 hook_radius = {2.0 * (self.bar_radius + self.hook_radius):g} m (the "
                "crook between the shank and a tip must take the bar)"
            )
        # a tip passing up beside the bar at the pass offset must miss it
        gap = self.pass_offset - self.outer_reach - self.hook_radius - self.bar_radius
        if gap <= 0.0:
            raise ValueError(
                f"mechanism.pass_offset = {self.pass_offset:g} m must be > the hook's outer "
                f"reach (hook_reach + hook_tip_length sin(hook_tip_angle_deg)) + hook_radius "
                f"+ bar_radius = "
                f"{self.pass_offset - gap:g} m (the hook must pass beside the bar)"
            )
        clear = self.outer_reach + self.hook_radius + self.bar_radius
        if self.reverse_climb_offset <= clear:
            raise ValueError(
                f"mechanism.reverse_climb_offset = {self.reverse_climb_offset:g} m must be > "
                f"the hook's outer reach + hook_radius + bar_radius = {clear:g} m (the hook "
                "must rise beside the bar)"
            )
        if self.hook_arm_rise_deg > 0.0:
            foot = self.bar_seat_foot
            arm = self.hook_reach / math.cos(math.radians(self.hook_arm_rise_deg))
            if not foot < min(arm, self.hook_tip_length) or self.bar_seat[0] <= (
                self.bar_radius + self.hook_radius
            ):
                raise ValueError(
                    f"mechanism.hook_arm_rise_deg = {self.hook_arm_rise_deg:g} deg: the bar "
                    f"seated in the arm-tip corner touches them {foot:g} m from it, beyond "
                    "the arm or the tip, or touches the shank (lower the rise)"
                )
        lo = self.hook_tip_length * math.cos(math.radians(self.hook_tip_angle_deg)) + (
            self.hook_radius + self.bar_radius) - self.arm_fall
        hi = self.hook_shank - self.bar_radius - self.line_radius
        if not lo < self.pass_depth < hi:
            raise ValueError(
                f"mechanism.pass_depth = {self.pass_depth:g} m must be in ({lo:g}, {hi:g}) m: "
                "the tips under the bar (> tip height - arm fall + hook_radius + bar_radius) "
                "and the "
                "eye above it (< hook_shank - bar_radius - line_radius)"
            )
        deepest = self.pass_depth + self.pass_margin + self.hook_radius + self.arm_fall
        if deepest >= self.standoff - self.pass_offset:
            room = self.standoff - self.pass_offset - self.pass_depth - self.hook_radius
            raise ValueError(
                f"mechanism.pass_margin = {self.pass_margin:g} m must be < standoff - "
                f"pass_offset - pass_depth - hook_radius - arm fall = "
                f"{room - self.arm_fall:g} m "
                "(the hook's bottom above the surface at the pass's end, any slope)"
            )
        if self.standoff <= self.bar_radius + 2.0 * self.hook_radius:
            raise ValueError(
                f"mechanism.standoff = {self.standoff:g} m must be > bar_radius + 2 hook_radius"
            )
        return self

    @property
    def arm_fall(self) -> float:
        """Drop of each arm's end below the crown, hook_reach tan(hook_arm_rise_deg) [m]."""
        return self.hook_reach * math.tan(math.radians(self.hook_arm_rise_deg))

    @property
    def bar_seat(self) -> tuple[float, float]:
        """The bar's axis where it seats in the hook's crook, in the plane of one arm: (u, z),
        u out along the arm from the shank's axis, z up along the shank from the crown [m].

        Flat arms (``hook_arm_rise_deg`` = 0): the crook has no low point; the design takes
        the bar on the arm at the shank, (0, hook_radius + bar_radius). Rising arms: each
        arm falls from the crown to its tip, so the crook's one low point is the corner
        between the arm and the tip: the bar's axis lies on the corner's bisector,
        hook_radius + bar_radius from both the arm and the tip.
        """
        rad = self.hook_radius + self.bar_radius
        rise = math.radians(self.hook_arm_rise_deg)
        if rise == 0.0:
            return 0.0, rad
        lean = math.radians(self.hook_tip_angle_deg)
        ax, az = -math.cos(rise), math.sin(rise)  # the corner toward the crown
        tx, tz = math.sin(lean), math.cos(lean)  # the corner toward the tip's end
        half = 0.5 * math.acos(ax * tx + az * tz)
        bx, bz = ax + tx, az + tz
        n = math.hypot(bx, bz)
        d = rad / math.sin(half) / n
        return self.hook_reach + d * bx, -self.arm_fall + d * bz

    @property
    def bar_seat_foot(self) -> float:
        """Distance from the arm-tip corner to where the seated bar touches the arm and the
        tip (:attr:`bar_seat`; rising arms only, 0 for flat ones) [m]."""
        rise = math.radians(self.hook_arm_rise_deg)
        if rise == 0.0:
            return 0.0
        lean = math.radians(self.hook_tip_angle_deg)
        half = 0.5 * (0.5 * math.pi - rise + lean)
        return (self.hook_radius + self.bar_radius) / math.tan(half)

    @property
    def outer_reach(self) -> float:
        """Farthest reach of the hook's tips from the shank's axis [m]."""
        return self.hook_reach + self.hook_tip_length * math.sin(
            math.radians(self.hook_tip_angle_deg))
