"""The mission supervisor: an explicit state machine over the phases of chapter 6.6.

It implements :class:`~tetherland.interfaces.ReferenceSource` (one reference per control
tick, with the control mode) and :class:`~tetherland.interfaces.EventSource` (every
transition with its reason). It sees only the estimate, never the plant's truth:

- a hook is taken as caught when the estimated tension passes the threshold for the dwell
  time while stretching; without tension the hook counts as missed and is retried;
- touchdown is confirmed by the multi-signal rule of :mod:`tetherland.mission.contact`
  (clearance, link stall, surface force), near the end of the planned landing (whose clock
  slows near the surface, :class:`~tetherland.mission.contact.SlowApproach`) and in the
  guarded descent past it;
- switches are bumpless (6.6.3): a tethered reference starts at the current output and
  blends onto the plan; the release after the takeoff starts at the current position with
  the cable pull as a force feed-forward (the reference acceleration f_L d/m) that fades
  out along the release leg and then, inside the slack point, takes the tension estimate
  (the force-model error along the cable the hand-over left out); a safe hover from
  tethered flight starts where the position error reproduces the pull
  (p + f_L d / (m k_x)), as in stretching;
- an operator abort (``mission.abort_time``) or a fault (slack cable or large tracking error
  in a tethered phase, a non-finite estimate, or one of the measured-signal rules of
  :class:`~tetherland.mission.faults.FaultMonitor`: rotor, anchor belief, motion capture,
  hook jam) moves to a safe state from any phase: hover in free flight (away from the
  surface after a slack cable; inside the cable's reach when the hook jams), land on the
  start pad (a weak rotor before hooking or after unhooking), or stay put when the motors
  are already off on the surface. :attr:`MissionSupervisor.safe_state` names the one
  reached.

The plan (trajectories, waypoints, clearance) is made before by
:func:`~tetherland.mission.plan.plan_mission`; the phases and their allowed successors are
the explicit table :data:`TRANSITIONS`, and every threshold is a ``[mission]`` field.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping
from types import MappingProxyType

import numpy as np

from tetherland import GRAVITY
from tetherland.config import FaultKind, Scenario
from tetherland.control.common import heading_of
from tetherland.errors import TetherlandError
from tetherland.estimation import TensionTare, ThresholdDwell
from tetherland.geometry import theta_A_from_z_B
from tetherland.interfaces import Command, ControlMode, EventRecord, Reference, StateEstimate
from tetherland.mission.blend import BlendedTrack
from tetherland.mission.contact import (
    ContactDecision,
    ContactRule,
    SlowApproach,
    contact_hold,
    early_contact_armed,
    guarded_descent,
    lateral_release_clearance,
    lean_limit,
)
from tetherland.mission.faults import FaultDetection, FaultMonitor
from tetherland.mission.hooking import (
    SHORTEST_LEG,
    bar_climb_path,
    bar_swing_path,
    lift_off_band,
    magnet_drop_path,
    magnet_pull_out_path,
    shortest_leg,
    swing_shaper,
    take_up_legs,
    takeoff_height,
    unhooking_path,
)
from tetherland.mission.paths import Path
from tetherland.mission.phases import Phase, PhaseRecord
from tetherland.mission.plan import Z_W, MissionPlan, unhook_reach
from tetherland.mission.release import ReleasePull
from tetherland.models.hook import (
    MagnetWhere,
    bar_hanging_weight,
    magnet_boom,
    magnet_load,
    weight_torque_B,
)
from tetherland.planning.tracking import TrajectoryTrack
from tetherland.rotations import quat_to_rotmat

_P = Phase
TRANSITIONS: Mapping[Phase, frozenset[Phase]] = MappingProxyType({
    _P.TAKEOFF: frozenset({_P.APPROACH, _P.SAFE_HOVER}),
    _P.APPROACH: frozenset({_P.HOOKING, _P.SAFE_HOVER}),
    _P.HOOKING: frozenset({_P.STRETCH, _P.RETRY, _P.SAFE_HOVER}),
    _P.STRETCH: frozenset({_P.TETHERED_LANDING, _P.RETRY, _P.SAFE_HOVER}),
    _P.RETRY: frozenset({_P.HOOKING, _P.SAFE_HOVER}),
    _P.TETHERED_LANDING: frozenset({_P.TOUCHDOWN, _P.SAFE_HOVER}),
    _P.TOUCHDOWN: frozenset({_P.MOTORS_OFF, _P.SAFE_HOVER}),
    _P.MOTORS_OFF: frozenset({_P.SPIN_UP, _P.ABORTED, _P.SAFE_HOVER}),
    _P.SPIN_UP: frozenset({_P.TETHERED_TAKEOFF, _P.SAFE_HOVER}),
    _P.TETHERED_TAKEOFF: frozenset({_P.RELEASE, _P.SAFE_HOVER}),
    _P.RELEASE: frozenset({_P.UNHOOK, _P.SAFE_HOVER}),
    _P.UNHOOK: frozenset({_P.RETURN, _P.SAFE_HOVER}),
    _P.RETURN: frozenset({_P.LAND, _P.SAFE_HOVER}),
    _P.LAND: frozenset({_P.DONE, _P.SAFE_HOVER}),
    _P.SAFE_HOVER: frozenset({_P.ABORTED}),
    _P.DONE: frozenset(),
    _P.ABORTED: frozenset(),
})  # fmt: skip
"""Every phase and the phases it may move to. An abort moves to SAFE_HOVER (hover in
free flight), or to ABORTED directly when the motors are off on the surface (unless the
cable was lost there: then the motors come on and the vehicle hovers away)."""


_UNHOOKED = frozenset({_P.TAKEOFF, _P.APPROACH, _P.RETRY, _P.RETURN})
"""Free-flight phases without the cable: a weak rotor lands on the start pad from them."""
_NEAR_MECHANISM = frozenset({_P.HOOKING, _P.RELEASE, _P.UNHOOK})
"""Free-flight phases close to the anchoring mechanism: a fault's safe hover moves away
from the surface."""
_NEAR_SURFACE = frozenset({_P.APPROACH, _P.RETRY, _P.HOOKING, _P.STRETCH, _P.RELEASE, _P.UNHOOK,
                           _P.RETURN})  # fmt: skip
"""Free-flight phases around the slope: a fault's safe state moves away from the surface
first when the landers are within ``away_distance`` of it
(:meth:`MissionSupervisor.near_surface`)."""
_ROTOR_NEAR_SURFACE = _NEAR_SURFACE | {_P.TETHERED_LANDING, _P.TETHERED_TAKEOFF}
"""Phases in which a weak rotor's safe state steps away from the surface first when the
landers are within ``away_distance`` of it: those of :data:`_NEAR_SURFACE` and the
tethered landing and takeoff. On a wall the vehicle pitching toward level a few
centimetres from it, its weak corner sagging, put a propeller on the wall while it
hovered at the pull point where the fault found it (wall90 with the magnet, fault
campaign seed 15, run rotor-00009); stepped away along z_S it hovers off the wall on
the taut cable."""


_ENDED = frozenset({_P.SAFE_HOVER, _P.ABORTED, _P.DONE})
"""Phases past an abort or the end: no further abort, no fault checks."""
_PLANNED_TENSION = frozenset({_P.TETHERED_LANDING, _P.SPIN_UP, _P.TETHERED_TAKEOFF})
"""Phases on a planned tethered trajectory: the snap rule gets the plan's tension."""
# members as module constants: an enum member's class attribute lookup costs ~80 ns, and
# the supervisor runs at the control rate
_P_TETHERED_LANDING, _P_TETHERED_TAKEOFF = _P.TETHERED_LANDING, _P.TETHERED_TAKEOFF
_FREE_FLIGHT = ControlMode.FREE_FLIGHT


def handover_tension(scenario: Scenario) -> float:
    """Estimated tension the stretch must hold (``mission.stretch.tension_dwell``) before
    tethered control takes over [N].

    ``mission.stretch.tension_threshold``; with the bar mechanism at least
    ``planner.start_tension``, the tension the landing plan starts with (the stretch's
    pull aims beyond it, :func:`tetherland.config.checks.stretch_tension_limit`). A hook
    caught by a tip instead of its crook holds about the threshold, and rolls over the
    bar as the landing's pull grows: the line goes slack for 0.16 s and the cable-lost
    rule stops the mission (pilot draw slope50 50 deg 00005: crown 37 mm from the bar's
    axis, taut 4 cm short, 1.05 N at the hand-over, slack 0.2 s into the landing). Pulled
    to the start tension in free flight, where the position loop holds the vehicle
    through the slack, it rolls into its crook before the hand-over. The disk's and the
    magnet's cable have no such seat: their threshold is unchanged.
    """
    threshold = scenario.mission.stretch.tension_threshold
    if scenario.mechanism.kind != "bar":
        return threshold
    return max(threshold, scenario.planner.start_tension)


class TransitionError(TetherlandError):
    """The supervisor tried a phase change that :data:`TRANSITIONS` does not allow."""


class MissionSupervisor:
    """Executes a :class:`~tetherland.mission.plan.MissionPlan` (section 6.6).

    Parameters
    ----------
    scenario : Scenario
        The believed scenario (mission thresholds, vehicle mass, controller rate).
    plan : MissionPlan
        What to fly: trajectories, waypoints (see :func:`~tetherland.mission.plan_mission`).
    """

    def __init__(self, scenario: Scenario, plan: MissionPlan):
        self.scenario = scenario
        self.plan = plan
        cfg = scenario.mission
        self.cfg = cfg
        self.geo = plan.geometry
        self.mass = scenario.vehicle.mass
        self.rate_hz = scenario.controller.rate_hz
        wn = scenario.controller.free_flight.position_frequency
        self.k_x = wn * wn
        self.landing_traj = plan.landing_trajectory
        self.takeoff_traj = plan.takeoff_trajectory
        wp = plan.waypoints
        self.wp = wp
        self._unhook_reach = unhook_reach(scenario, plan.geometry, wp)
        self._magnet = scenario.mechanism.kind == "magnet"
        self._magnet_on = False
        self._latch_open = False
        self._hook_end = wp.hook_end
        """End of the hooking pass, F_W [m]: the plan's, or with the magnet a plate not
        met moves it ``press_depth`` deeper for the next pass (:meth:`_plate_met`)."""
        self._latch_at: float | None = None
        """Magnet mechanism: when the robot decides whether to open its clip's latch (the
        EPM's switching time and ``mechanism.latch_settle`` after the on command) [s]."""
        self._magnet_moves: list[tuple[float, MagnetWhere]] = [(0.0, "clipped")]
        """Magnet mechanism: from when the robot believes its magnet clipped on the boom,
        held on the plate or hanging on the cable (its EPM commands and switching times),
        in time order (:meth:`_weight_torque`)."""
        self._loads = (
            {w: magnet_load(scenario, w) for w in ("clipped", "held", "hanging")}
            if self._magnet else {}
        )  # fmt: skip
        self._torque_ff: np.ndarray | None = None
        """The weight's torque fed forward at the last tick, F_B [N m]."""
        self._min_leg = shortest_leg(scenario)
        self._shaper = swing_shaper(scenario)
        if self._magnet:  # clipped on its boom until released: nothing swings before
            self._hanging = (self._min_leg, self._shaper)
            self._min_leg, self._shaper = SHORTEST_LEG, None
        self._take_up = take_up_legs(scenario)
        """Shortest leg [s] and shaper of the take-up's legs (:meth:`_take_up_path`)."""
        self._climb_slack: np.ndarray | None = None
        """Bar mechanism: the slack point of a climb that checks the hook is off the bar."""
        self._entry_climb: tuple[float, np.ndarray, np.ndarray] | None = None
        """Bar mechanism, after a reverse pass: when the climb from its entry begins [s],
        the entry and the climb's top (the hooking start), F_W [m]; that climb checks the
        hook is off the bar as well (:meth:`_unhook`)."""
        self._swing_at: float | None = None
        """Bar mechanism: when the take-up's swing starts from where the seat's climb left
        the vehicle (the end of the climb plus the settle time) [s]."""
        self._stretch_leg: int | None = None
        """Bar mechanism: index in the take-up path of the stretch leg, before whose start
        a taut cable does not hand over to tethered control (:meth:`_stretch`)."""
        self._takeoff_height = takeoff_height(scenario)
        self.yaw = wp.yaw
        # state
        self.phase = Phase.TAKEOFF
        self._phase_start = 0.0
        self.records: list[PhaseRecord] = []
        self.events: list[EventRecord] = []
        self.times: dict[str, float] = {}
        self.hook_attempts = 0
        self.abort_reason: str | None = None
        self.safe_state: str | None = None
        """The safe state reached after an abort: "hover", "landed" or "motors_off"."""
        self.fault: FaultDetection | None = None
        """The fault the monitor detected, if any."""
        self.monitor = FaultMonitor(scenario, self.geo)
        self._airborne_after = cfg.settle_time + cfg.detection.airborne_delay
        """Time from which the rotor rule may run (off the pad) [s]."""
        self._safe_land = False
        self._moving_at = 0.0
        """Last time the estimated speed exceeded ``safe_hover_settle_speed`` in a safe
        hover (from the abort) [s]."""
        self._terminate_at: float | None = None
        self._final_mode = ControlMode.MOTORS_OFF
        self._taut = ThresholdDwell(cfg.stretch.tension_threshold, cfg.stretch.tension_dwell)
        self._handover = ThresholdDwell(handover_tension(scenario), cfg.stretch.tension_dwell)
        """The stretch's taut rule (:func:`handover_tension`); ``_taut`` is the unhooking
        climb's."""
        m = scenario.mechanism
        self._r_att = np.asarray(scenario.vehicle.cable_attachment, dtype=float)
        tare = cfg.stretch.tension_tare
        self.tare = (
            TensionTare(bar_hanging_weight(scenario.tether.length, m) if m.kind == "bar" else 0.0)
            if (m.kind == "bar" if tare is None else tare)
            else None
        )
        """The tension estimate's bias, zeroed on the line hanging free at the first hooking
        start (``mission.stretch.tension_tare``; None: off): every reading of the
        supervisor and its fault monitor is taken less it from then on."""
        self._contact_rule = ContactRule(scenario)
        self._lateral_clearance = lateral_release_clearance(scenario)
        """The lateral release's clearance (``mission.touchdown.lateral_clearance``) [m]."""
        self._lean_limit = lean_limit(scenario)
        """The landing's lean limit (:func:`~tetherland.mission.contact.lean_limit`; 0:
        none) [rad]."""
        self._slow = SlowApproach(
            cfg.touchdown, self._contact_rule.geometry, self.geo.link_length,
            self._lateral_clearance,
        )  # fmt: skip
        self._landing_rate = 0.0  # |phi_d'| of the landing plan at the approach clock
        self._search_start: float | None = None
        self._delta_lock: float | None = None  # link azimuth held from the first contact sign
        self._sign_t: float | None = None  # time of the first sign of contact [s]
        self._press_t: float | None = None  # time the preload began (landers stopped) [s]
        self._backed_away = False
        """True from a tick at which the rate hold ran the landing's clock backwards
        (:class:`~tetherland.mission.contact.SlowApproach`) until the estimated link is
        back at or above the reference: meanwhile a stopped link without an impact is not
        taken for the landers' stop (:meth:`_lock_on_contact`)."""
        self._press_phi = 0.0  # estimated link elevation at the preload's start [rad]
        self._shed_at_contact = 0.0  # preload's thrust shed at the confirmed contact [-]
        self._shed = 0.0  # preload's thrust shed now [-]
        self._shed_t: float | None = None  # time of its last update [s]
        self._surface_force = 0.0  # last estimated surface push of the contact rule [N]
        self._slack = ThresholdDwell(0.0, cfg.detection.slack_dwell)
        self._path = self._new_path(0.0, wp.start, free_hook=True)
        band = lift_off_band(scenario)
        if band is not None:  # the hanging hook leaves the ground slowly
            self._path.to(wp.start + band[0] * Z_W).to(
                wp.start + band[1] * Z_W, speed=scenario.mechanism.lift_speed)
        self._path.to(wp.start + self._takeoff_height * Z_W, pause=cfg.settle_time)
        self._track: BlendedTrack | None = None
        self._hold: Reference | None = None
        self._release_pull: ReleasePull | None = None
        self._t_free = 0.0  # last tick of the free-flight reference [s]
        self._suspect_held = 0.0  # time the passes near the mechanism held still [s]
        self._thrust_loss: Phase | None = None
        """The phase of a weak rotor's fault near the surface: its lost thrust is fed
        forward in the safe hover (:meth:`_lost_thrust`)."""
        self._handlers: Mapping[Phase, Callable[[float, StateEstimate], Reference]] = {
            Phase.TAKEOFF: self._takeoff,
            Phase.APPROACH: self._approach,
            Phase.RETRY: self._approach,
            Phase.HOOKING: self._hooking,
            Phase.STRETCH: self._stretch,
            Phase.TETHERED_LANDING: self._tethered_landing,
            Phase.TOUCHDOWN: self._touchdown,
            Phase.MOTORS_OFF: self._motors_off,
            Phase.SPIN_UP: self._spin_up,
            Phase.TETHERED_TAKEOFF: self._tethered_takeoff,
            Phase.RELEASE: self._release,
            Phase.UNHOOK: self._unhook,
            Phase.RETURN: self._return,
            Phase.LAND: self._land,
            Phase.DONE: self._motors_off_hold,
            Phase.SAFE_HOVER: self._safe_hover,
            Phase.ABORTED: self._motors_off_hold,
        }
        self._event(0.0, "phase", f"start: {self.phase.name.lower()}")

    # ------------------------------------------------------------------ helpers
    @property
    def magnet_on(self) -> bool:
        """The EPM command of the magnet mechanism (``MagnetCommander``): on from the end
        of a hooking pass until the release after the takeoff [-]."""
        return self._magnet_on

    @property
    def latch_open(self) -> bool:
        """The command to the latch of the clip that holds the magnet on its boom
        (``MagnetCommander``): open once the robot believes the magnet held on the plate
        (:meth:`_latch_or_retry`), never closed again in the run [-]."""
        return self._latch_open

    def _switch_magnet(self, t: float, on: bool, why: str) -> None:
        if self._magnet and on != self._magnet_on:
            self._magnet_on = on
            self._event(t, "magnet", f"EPM {'on' if on else 'off'}: {why}")

    def _event(self, t: float, kind: str, message: str) -> None:
        self.events.append(EventRecord(t=t, source="mission", kind=kind, message=message))

    def _enter(self, phase: Phase, t: float, reason: str) -> None:
        if phase not in TRANSITIONS[self.phase]:
            raise TransitionError(
                f"mission phase {self.phase.name.lower()} cannot move to {phase.name.lower()}"
            )
        self.records.append(PhaseRecord(self.phase, self._phase_start, t, reason))
        self._event(t, "phase", f"{self.phase.name.lower()} -> {phase.name.lower()}: {reason}")
        self.phase = phase
        self._phase_start = t

    def _free(self, t: float, est: StateEstimate) -> Reference:
        dt, self._t_free = t - self._t_free, t
        det = self.cfg.detection
        if (
            self.phase in _NEAR_MECHANISM
            and self.monitor.torque_residual > det.rotor_suspect * det.rotor_torque
            and self._suspect_held < det.rotor_suspect_max_time
            and dt > 0.0
        ):  # a rotor fault is suspected close to the mechanism: the pass holds still
            self._path.delay(dt)
            self._suspect_held += dt
            rows = self._path.sample(t).copy()
            rows[1:] = 0.0
        else:
            rows = self._path.sample(t)
        if self._release_pull is not None:
            if not rows.flags.writeable:  # the path's held rows are shared and read-only
                rows = rows.copy()
            rows[2] += self._release_pull.feedforward(t, est, rows[0])
        elif self._thrust_loss is not None:
            if not rows.flags.writeable:
                rows = rows.copy()
            rows[2] += self._lost_thrust(est)
        # (t, mode, phase, p_W, yaw: positional, the control-rate path)
        return Reference(t, _FREE_FLIGHT, int(self.phase), rows, self.yaw)

    def _new_path(self, t: float, start: np.ndarray, speed: float | None = None,
                  free_hook: bool = False) -> Path:  # fmt: skip
        """A free-flight path from ``start``; ``free_hook``: a leg on which a hanging hook
        swings free of the mechanism (takeoff, approach, retry, return), shaped so that it
        leaves no swing (:func:`~tetherland.mission.hooking.swing_shaper`); legs near or on
        the mechanism (passes, release, the disk's unhooking) are not shaped (the take-up
        and the bar's unhooking: :meth:`_take_up_path`)."""
        return Path(t, start, speed or self.cfg.flight.cruise_speed, self.cfg.flight.cruise_accel,
                    self._min_leg, self._shaper if free_hook else None)  # fmt: skip

    def _take_up_path(self, t: float, start: np.ndarray) -> Path:
        """A take-up path from ``start`` at the take-up's speed
        (``stretch.take_up_speed_factor`` of the cruise speed): with the bar every leg
        shaped at the hanging hook's believed swing period and as short as the speed
        limits allow (:func:`~tetherland.mission.hooking.take_up_legs`). The bar's
        unhooking flies its legs so too (:meth:`_climb_away`, :meth:`_unhook`)."""
        shortest, shaper = self._take_up
        cfg = self.cfg
        speed = cfg.stretch.take_up_speed_factor * cfg.flight.cruise_speed
        return Path(t, start, speed, cfg.flight.cruise_accel, shortest, shaper)

    def _output_now(self, est: StateEstimate) -> np.ndarray:
        """Estimated y^b = [phi, delta, theta_A, psi]."""
        link = est.link
        assert link is not None
        R_AB = self.geo.R_WA.T @ quat_to_rotmat(est.body.q_WB)
        theta = theta_A_from_z_B(R_AB[:, 2], link.phi, link.delta)
        return np.array([link.phi, link.delta, theta, heading_of(R_AB)])

    def _pull_point(self, est: StateEstimate) -> np.ndarray:
        """Free-flight reference whose position error reproduces the cable pull."""
        d = est.body.p_W - self.geo.p_A
        d /= max(float(np.linalg.norm(d)), 1e-9)
        tension = max(est.tension or 0.0, 0.0)
        return est.body.p_W + tension / (self.mass * self.k_x) * d

    def _link_axes(self, est: StateEstimate) -> tuple[float, float]:
        """The unit link direction d (the believed anchor to the estimated attachment
        point, F_W): its vertical part d . z_W and its part along the thrust axis d . z_B
        [-] (:class:`~tetherland.estimation.TensionTare`)."""
        R_WB = est.body.R_WB
        d = est.body.p_W + R_WB @ self._r_att - self.geo.p_A
        d /= max(float(np.linalg.norm(d)), 1e-9)
        return float(d[2]), float(d @ R_WB[:, 2])

    def _close_tare(self, t: float, tare: TensionTare) -> None:
        """End the tare at the hooking start and log what it found."""
        n = tare.samples
        bias = tare.close()
        if bias is None:
            self._event(t, "tension", "no tare of the tension estimate (no hover sampled)")
        else:
            self._event(
                t, "tension",
                f"tension tare over {n} readings of the line hanging free (believed weight "
                f"{tare.weight:.3f} N): bias {bias:+.3f} N along the thrust axis, taken off "
                "every later reading",
            )  # fmt: skip

    def _close(self, est: StateEstimate, p: np.ndarray, tol: float) -> bool:
        x, y, z = est.body.p_W.tolist()
        px, py, pz = np.asarray(p, dtype=float).tolist()
        dx, dy, dz = x - px, y - py, z - pz
        return math.sqrt(dx * dx + dy * dy + dz * dz) <= tol  # (np.linalg.norm's bits)

    # ------------------------------------------------------------------ abort and faults
    def abort(
        self, t: float, est: StateEstimate, reason: str, *, hover_at: np.ndarray | None = None,
        land: bool = False, away: bool = False, step: bool = False,
    ) -> None:  # fmt: skip
        """Go to the safe state from the current phase and log ``reason``.

        Hover where the vehicle is (at the pull point in a tethered phase, ``away`` from
        the surface by ``mission.detection.away_distance``), or at ``hover_at``; or, with
        ``land``, fly back to the start pad and land (free flight). Landed with the motors
        off, the motors stay off, unless ``away``: the vehicle is moving without its cable,
        so the motors come on and it hovers away from the surface. With ``step`` the
        reference jumps to the point away from the surface at once (a weak rotor near it,
        or a lost cable on it: the vehicle is already sinking, sliding or tilting towards
        it) instead of moving there along a path from the estimate.
        """
        if self.phase in (Phase.SAFE_HOVER, Phase.ABORTED, Phase.DONE):
            return
        self.abort_reason = reason
        self._event(t, "abort", reason)
        self._moving_at = t
        if self.phase == Phase.MOTORS_OFF and not away:
            self._enter(Phase.ABORTED, t, f"abort while landed, motors stay off: {reason}")
            self.safe_state = "motors_off"
            self._terminate_at = t
            return
        start = self._pull_point(est) if self.phase.tethered else est.body.p_W
        if away:
            start = start + self.cfg.detection.away_distance * self.geo.surface.z_S
        self._path = self._new_path(t, est.body.p_W if away and not step else start)
        if land:
            wp = self.wp
            self._path = (
                self._path.to(np.array([*start[:2], max(start[2], wp.z_safe)]))
                .to(np.array([*wp.start[:2], wp.z_safe]))
                .to(wp.start + self._takeoff_height * Z_W)
                .to(wp.start - self.cfg.flight.pad_press_depth * Z_W, speed=self.cfg.hooking.speed,
                    pause=self.cfg.settle_time)
            )  # fmt: skip
            self._safe_land = True
        else:
            target = start if hover_at is None else np.asarray(hover_at, dtype=float)
            self._path = self._path.to(target, pause=self.cfg.safe_hover_time)
        self._enter(Phase.SAFE_HOVER, t, f"abort: {reason}")

    def _lost_thrust(self, est: StateEstimate) -> np.ndarray:
        """After a rotor fault near the surface, the cable believed slack: the estimated
        cable pull is the thrust the weak rotor does not deliver (the estimator reads the
        deficit as a pull along -d, d from the believed anchor to the vehicle), fed
        forward as the acceleration f_L d / m [m/s^2] that makes it up, as the release
        hand-over does with a real pull; the position integral needs seconds for it, and
        the vehicle sinks 0.2 m/s meanwhile. Zero once the attachment point is within
        ``mission.detection.jam_slack`` of the cable's reach (the pull may be real), unless
        the fault came before the hooking pass or after the unhooking pass
        (:data:`_UNHOOKED`: no cable to pull)."""
        r_att = np.asarray(self.scenario.vehicle.cable_attachment, dtype=float)
        d = est.body.p_W + est.body.R_WB @ r_att - self.geo.p_A
        n = float(np.linalg.norm(d))
        reach = self.scenario.tether.length - self.cfg.detection.jam_slack
        if n < 1e-9 or (n >= reach and self._thrust_loss not in _UNHOOKED):
            return np.zeros(3)
        return max(est.tension or 0.0, 0.0) / (self.mass * n) * d

    def near_surface(self, est: StateEstimate, phases: frozenset[Phase] = _NEAR_SURFACE) -> bool:
        """In one of ``phases`` (default :data:`_NEAR_SURFACE`, free flight around the
        slope; not the tethered phases, where the cable holds the vehicle, nor the pad's;
        a weak rotor's check adds the tethered ones, :data:`_ROTOR_NEAR_SURFACE`) with
        the estimated landers closer to the believed surface than
        ``mission.detection.away_distance``: a fault's safe state first moves away from
        the surface along z_S (a weak rotor sinks and tilts the vehicle by centimetres
        before its fault is confirmed, the end of the hooking pass keeps the landers
        0.1-0.2 m from the slope)."""
        if self.phase not in phases:
            return False
        clearance = self._contact_rule.geometry.clearance(est.body.p_W, est.body.R_WB)
        return clearance < self.cfg.detection.away_distance

    def command_sent(self, t: float, command: Command) -> None:
        """The runner tells each command sent (``CommandAware``): for the fault monitor,
        which reads the torque the control law asked for (the weight's torque fed
        forward, :meth:`_weight_torque`, is known and not a rotor's fault)."""
        ff = self._torque_ff
        if ff is not None and command.torque_B is not None:
            command = Command(command.rotor_speeds, command.thrust,
                              np.asarray(command.torque_B) - ff, command.diagnostics)  # fmt: skip
        self.monitor.command_sent(t, command)

    def _weight_torque(self, t: float, est: StateEstimate) -> np.ndarray | None:
        """Magnet mechanism: the torque about the body origin that holds the vehicle's
        weight where the robot believes its centre of mass (with the magnet clipped,
        held or hanging: :func:`~tetherland.models.hook.magnet_load`), at the estimated
        attitude, F_B [N m] (``Reference.torque_ff_B``). The frame balances the magnet
        only in part, so its centre of mass moves by several millimetres when the magnet
        leaves the boom; without this the attitude loop held the moment (0.065 N m for
        the defaults) with a steady attitude error of about 1 deg, and the landers met
        the wall one after the other (wall90: a bounce at the touchdown). None for the
        other mechanisms."""
        if not self._magnet:
            return None
        where: MagnetWhere = "clipped"
        for t_from, w in self._magnet_moves:
            if t >= t_from:
                where = w
        mass, c_B = self._loads[where]
        return weight_torque_B(mass, c_B, est.body.R_WB)

    def _on_fault(self, t: float, est: StateEstimate, found: FaultDetection) -> None:
        """A measured-signal fault: log it and move to the safe state of its kind."""
        self.fault = found
        self._event(t, "fault", found.reason)
        near = self.near_surface(est)
        if found.kind == FaultKind.JAM:  # still hooked: hover inside the cable's reach
            self.abort(t, est, found.reason, hover_at=self.wp.hook_start)
        elif found.kind == FaultKind.ROTOR and self.near_surface(est, _ROTOR_NEAR_SURFACE):
            # a weak rotor sinks and tilts the vehicle towards the surface: away at once
            # (a step of the reference along z_S), its lost thrust fed forward, then hover
            self._thrust_loss = self.phase
            self.abort(t, est, found.reason, away=True, step=True)
        elif found.kind == FaultKind.ROTOR and self.phase in _UNHOOKED:
            self.abort(t, est, found.reason, land=True)
        elif found.kind == FaultKind.SNAP:
            # on or just above the slope (landed, spinning up, the last centimetres of a
            # landing) the cable was all that held the vehicle: it slides and tips at once,
            # so the reference steps away along z_S (the thrust pushes it off the surface
            # before the attitude levels, instead of levelling a frame that lies on it)
            clearance = self._contact_rule.geometry.clearance(est.body.p_W, est.body.R_WB)
            step = clearance < self.cfg.detection.away_distance
            self.abort(t, est, found.reason, away=True, step=step)
        elif self.phase in _NEAR_MECHANISM or near:
            self.abort(t, est, found.reason, away=True)  # stop away from the surface
        else:
            self.abort(t, est, found.reason)

    def _check_faults(self, t: float, est: StateEstimate, ref: Reference) -> None:
        body = est.body
        if not math.isfinite(sum(body.p_W.tolist()) + sum(body.q_WB.tolist())):
            self.abort(t, est, "fault: the state estimate is not finite")
            return
        phase = self.phase
        if phase in _ENDED:
            return
        det = self.cfg.detection
        # the torque rule explains the commanded torque by the cable alone: not in the
        # landing's preload (the landers believed on the surface, whose push turns the
        # vehicle too; 60 deg bar draw 00014 read one lander's 0.8 N as a lost rotor)
        airborne = t >= self._airborne_after and not (
            (phase == _P_TETHERED_TAKEOFF and t < self._phase_start + det.tethered_airborne_delay)
            or (phase == _P_TETHERED_LANDING and self._press_t is not None)
        )
        planned = None
        if phase in _PLANNED_TENSION:
            ff = ref.feedforward
            planned = ff.tension if ff is not None else 0.0  # off the plan: not needed
        found = self.monitor.check(t, est, phase, airborne, planned)
        if found is not None:
            self._on_fault(t, est, found)
            return
        active = phase == _P_TETHERED_LANDING or (
            phase == _P_TETHERED_TAKEOFF and self._track is not None
            and t > self._track.track.t0 + det.tethered_takeoff_delay
        )  # fmt: skip
        if not active or est.link is None or self._track is None:
            self._slack.reset()
            return
        if self._contact_rule.geometry.clearance(body.p_W, body.R_WB) < self.cfg.contact.clearance:
            # the landers are at the surface and may carry the vehicle: a slackening cable
            # is expected there (flat ground, gentle slopes), not a fault
            self._slack.reset()
        elif self._slack.update(t, det.slack_tension - (est.tension or 0.0)):
            self.abort(
                t,
                est,
                f"fault: cable slack (estimated tension < {det.slack_tension} N)",
                away=True,
            )
            return
        if ref.output is None:
            return
        err = math.degrees(abs(ref.output[0, 0] - est.link.phi))
        if err > det.tracking_error_deg:
            self.abort(t, est, f"fault: link tracking error {err:.1f} deg")

    # ------------------------------------------------------------------ ReferenceSource
    def reference(self, t: float, estimate: StateEstimate) -> Reference:
        """Advance the state machine and return the reference for time ``t`` (the tension
        read less the tare's bias, :attr:`tare`; with the magnet, its weight's torque fed
        forward: :meth:`_weight_torque`)."""
        tare = self.tare
        if tare is not None and tare.bias is not None and estimate.tension is not None:
            estimate = dataclasses.replace(
                estimate, tension=tare.correct(estimate.tension, self._link_axes(estimate)[1])
            )
        ref = self._reference(t, estimate)
        ff = self._torque_ff = self._weight_torque(t, estimate)
        return ref if ff is None else dataclasses.replace(ref, torque_ff_B=ff)

    def _reference(self, t: float, estimate: StateEstimate) -> Reference:
        if self._terminate_at is not None and t >= self._terminate_at:
            if self._final_mode == ControlMode.FREE_FLIGHT:
                ref = self._free(t, estimate)
                return Reference(
                    t=t, mode=ref.mode, phase=ref.phase, p_W=ref.p_W, yaw=ref.yaw, terminate=True
                )
            return Reference(
                t=t, mode=ControlMode.MOTORS_OFF, phase=int(self.phase), terminate=True
            )
        abort_time = self.cfg.abort_time
        if abort_time is not None and t >= abort_time and self.abort_reason is None:
            self.abort(t, estimate, f"operator abort at t = {abort_time:g} s")
        ref = self._handlers[self.phase](t, estimate)
        phase = self.phase
        self._check_faults(t, estimate, ref)
        if self.phase != phase:  # a fault moved to the safe state: its reference instead
            ref = self._handlers[self.phase](t, estimate)
        return ref

    # ------------------------------------------------------------------ phases
    def _takeoff(self, t: float, est: StateEstimate) -> Reference:
        wp, cfg = self.wp, self.cfg
        tol = cfg.flight.waypoint_tolerance
        if t >= self._path.t_end and self._close(est, self._path.end, tol):
            up = np.array([*self._path.end[:2], wp.z_safe])
            above = np.array([*wp.hook_start[:2], wp.z_safe])
            self._path = (
                self._new_path(t, self._path.end, free_hook=True)
                .to(up)
                .to(above)
                .to(wp.hook_start, pause=cfg.settle_time)
            )
            self._enter(Phase.APPROACH, t, "takeoff height reached")
        elif t > self._path.t_end + cfg.detection.leg_timeout:
            self.abort(t, est, "fault: takeoff height not reached")
        return self._free(t, est)

    def _approach(self, t: float, est: StateEstimate) -> Reference:
        wp, cfg = self.wp, self.cfg
        tare = self.tare
        if tare is not None and tare.bias is None and est.tension is not None:
            hold = self._path.segments[-1]
            if t >= hold.t0 and not (hold.p1 - hold.p0).any():
                # the hover at the first hooking start: the line hangs free (on a retry it
                # may hang on the bar or the slope, and the bias has not changed)
                tare.add(est.tension, *self._link_axes(est))
        if t >= self._path.t_end and self._close(est, wp.hook_start, cfg.hooking.start_tolerance):
            if tare is not None and tare.bias is None:
                self._close_tare(t, tare)
            self._path = self._new_path(t, wp.hook_start, cfg.hooking.speed).to(
                self._hook_end, pause=cfg.settle_time
            )
            self.hook_attempts += 1
            self._enter(Phase.HOOKING, t, f"at the hooking start (attempt {self.hook_attempts})")
        elif t > self._path.t_end + cfg.detection.leg_timeout:
            self.abort(t, est, "fault: hooking start not reached")
        return self._free(t, est)

    def _hooking(self, t: float, est: StateEstimate) -> Reference:
        wp, cfg = self.wp, self.cfg
        if t >= self._path.t_end:
            self._path = self._take_up_path(t, self._hook_end)
            m = self.scenario.mechanism
            if m.kind == "bar":
                # level to the pass's mirror across the bar and climb to seat the hook in
                # its crook; the swing down around the anchor (descending at once let the
                # hook drop off the bar) starts, in _stretch, from where the climb left the
                # vehicle: a hook seated early holds it lower
                for corner, speed in bar_climb_path(self.scenario, self.geo.R_WA[:, 0],
                                                    wp.hook_end):  # fmt: skip
                    self._path.to(corner, speed=speed)
                self._swing_at = self._path.t_end + cfg.settle_time
                self._handover.reset()
                self._enter(Phase.STRETCH, t, "hooking pass done")
                return self._free(t, est)
            why = "end of the hooking pass, the magnet on the plate"
            if self._magnet:
                if not self._plate_met(t, est):
                    return self._free(t, est)
                short = self._pressed_on_plate(est)
                why = f"{why} (the pass stopped {1e3 * short:.1f} mm short of its end)"
            if self._magnet:  # straight back first: out of the clip, not along the plate
                for corner in magnet_pull_out_path(self.scenario, self._hook_end,
                                                   self.geo.R_WA):  # fmt: skip
                    self._path.to(corner)
                # pressed on the plate while the EPM switches on and settles, then while
                # the latch opens (_open_latch)
                self._latch_at = t + m.epm_on_time + m.latch_settle
                self._path.delay(m.epm_on_time + m.latch_settle + m.latch_time)
            self._path.to(wp.slack_out)
            self._path.to(wp.stretch, speed=cfg.stretch.speed)
            self._switch_magnet(t, True, why)
            self._handover.reset()
            self._enter(Phase.STRETCH, t, "hooking pass done")
        return self._free(t, est)

    def _pressed_on_plate(self, est: StateEstimate) -> float:
        """Magnet mechanism: how far short of the hooking pass's end the estimate puts the
        magnet's eye along the approach direction (the believed boom on the estimated
        attitude) [m]. The pass ends ``press_depth`` beyond the believed plate: a vehicle
        stopped well short of it was stopped by the plate (the position loop yields to the
        magnet's push); one at the end met nothing."""
        boom = magnet_boom(self.scenario)
        R_WA = self.geo.R_WA
        n_W = R_WA @ boom.n_B
        eye_end = self._hook_end + R_WA @ boom.eye_B
        eye_est = est.body.p_W + est.body.R_WB @ boom.eye_B
        return float((eye_end - eye_est) @ n_W)

    def _plate_met(self, t: float, est: StateEstimate) -> bool:
        """Magnet mechanism, at the end of a hooking pass: whether the plate stopped it
        (:meth:`_pressed_on_plate` beyond half of ``press_depth``: the magnet pressed on
        the plate, the EPM may be switched on); if not (the plate deeper than believed, or
        missed), the pass is flown again, ``press_depth`` deeper, with the EPM off and the
        magnet clipped (RETRY), or the mission aborts after
        ``mission.hooking.max_attempts``."""
        short = self._pressed_on_plate(est)
        if short > 0.5 * self.scenario.mechanism.press_depth:
            return True
        self._event(t, "hook", f"missed plate (attempt {self.hook_attempts}): the pass "
                    f"stopped {1e3 * short:.1f} mm short of its end, nothing pressed")  # fmt: skip
        if self.hook_attempts >= self.cfg.hooking.max_attempts:
            self.abort(t, est, f"hook missed {self.hook_attempts} times")
        else:
            m = self.scenario.mechanism
            self._hook_end = self._hook_end + m.press_depth * (
                self.geo.R_WA @ magnet_boom(self.scenario).n_B)
            self._retry(t, est, "the pass did not meet the plate: EPM off, retrying "
                        f"{1e3 * m.press_depth:.0f} mm deeper")  # fmt: skip
        return False

    def _open_latch(self, t: float) -> None:
        """Magnet mechanism: the EPM on for its switching time and ``latch_settle`` after a
        pass the plate stopped: the robot believes the magnet held and opens the clip's
        latch; the magnet leaves the boom ``latch_time`` later (:meth:`_weight_torque`)."""
        self._latch_at = None
        m = self.scenario.mechanism
        self._latch_open = True
        self._event(t, "magnet", f"latch open: the EPM on for {m.epm_on_time + m.latch_settle:g} "
                    "s after a pass the plate stopped")  # fmt: skip
        self._magnet_moves.append((t + m.latch_time, "held"))

    def _retry(self, t: float, est: StateEstimate, reason: str) -> None:
        """Back to the hooking start over the safe height from the estimated position."""
        wp = self.wp
        above = np.array([*wp.hook_start[:2], wp.z_safe])
        self._path = (
            self._new_path(t, est.body.p_W, free_hook=True)
            .to(above)
            .to(wp.hook_start, pause=self.cfg.settle_time)
        )
        self._enter(Phase.RETRY, t, reason)

    def _stretch(self, t: float, est: StateEstimate) -> Reference:
        wp, cfg = self.wp, self.cfg
        if self._latch_at is not None and t >= self._latch_at:
            self._open_latch(t)
        if self._swing_at is not None and t >= self._swing_at:
            # the bar: swing from the estimated position at the end of the seat's climb
            self._swing_at = None
            seat = est.body.p_W.copy()
            self._path = self._take_up_path(t, seat)
            for corner, _ in bar_swing_path(self.scenario, self.geo.p_A, seat, wp.stretch,
                                            wp.attachment_W):  # fmt: skip
                self._path.to(corner)
            self._stretch_leg = len(self._path.segments)  # the next move is the stretch
            self._path.to(wp.stretch, speed=cfg.stretch.speed)
            self._handover.reset()
        if self._swing_at is not None or self._swinging(t):
            # the bar: not during the seat's climb (a hook seated early holds the vehicle
            # under the climb's top and the line pulls: 1.24 N estimated for 0.2 s on a
            # 20 deg pilot draw, the bar 1.4 cm lower than believed, read as taut began the
            # tethered landing from the seat), nor during the swing over the bar (a belief
            # error of the anchor, or the tension estimate's bias, reads taut there, far
            # above the direction where the landing plan, its thrust and tension start)
            self._handover.reset()
        elif self._handover.update(t, est.tension or 0.0) and est.link is not None:
            self.times["t_tethered"] = t
            track = TrajectoryTrack(self.landing_traj, t, self.rate_hz, int(Phase.TETHERED_LANDING))
            self._track = BlendedTrack(track, self._output_now(est), t, cfg.blend_time)
            self._slow.start(t)
            self._landing_rate = 0.0
            self._enter(
                Phase.TETHERED_LANDING, t,
                f"estimated tension {est.tension:.2f} N above {self._handover.threshold} N "
                f"for {cfg.stretch.tension_dwell} s: cable taut, tethered control",
            )  # fmt: skip
            return self._track.reference(t, self.phase)
        if self._swing_at is None and t > self._path.t_end + cfg.stretch.timeout:
            self._event(t, "hook", f"missed hook (attempt {self.hook_attempts}): no tension")
            if self.hook_attempts >= cfg.hooking.max_attempts:
                self.abort(t, est, f"hook missed {self.hook_attempts} times")
                return self._free(t, est)
            if self._latch_open:  # let out of its clip, not held: nothing to retry with
                self.abort(t, est, "magnet lost: no tension after the latch opened (the "
                           "magnet did not hold and hangs on the cable)")  # fmt: skip
                return self._free(t, est)
            self._retry(t, est, "no tension after stretching: hook missed, retrying")
        return self._free(t, est)

    def _swinging(self, t: float) -> bool:
        """Whether the bar's take-up is still before its stretch leg at ``t`` [s]: the
        seating swing around the anchor, where a taut cable does not start tethered
        control (the landing plan and its feedforward start on the stretch direction)."""
        k = self._stretch_leg
        return k is not None and k < len(self._path.segments) and t < self._path.segments[k].t0

    def _contact(
        self, t: float, est: StateEstimate, ref: Reference, decision: ContactDecision, when: str
    ) -> Reference:
        """Touchdown confirmed: hold the link at contact until the motors go off."""
        self.times["t_L"] = t
        self._shed_at_contact = self._preload_shed(t)
        self._hold = contact_hold(self.cfg.contact, t, est, ref, int(Phase.TOUCHDOWN))
        assert decision.evidence is not None
        reason = f"contact {when} (t_L): {decision.evidence.describe()}"
        self._event(t, "touchdown", reason)
        if self.phase != Phase.TOUCHDOWN:
            self._enter(Phase.TOUCHDOWN, t, reason)
        return dataclasses.replace(self._hold, thrust_shed=self._shed_at_contact)

    def _tethered_landing(self, t: float, est: StateEstimate) -> Reference:
        assert self._track is not None
        track = self._track.track
        tau = self._slow.advance(t, est, self._landing_rate)  # the slowed plan clock
        planned = self._track.reference(tau, self.phase)
        self._landing_rate = abs(float(planned.output[1, 0]))
        ref = self._slow.scale(planned, t)
        ref = self._lateral(ref, self._slow.clearance < self._lateral_clearance)
        ref = self._pressed(ref, t)
        if early_contact_armed(self.cfg.contact, tau, track.t0, track.duration):
            decision = self._contact_rule.update(t, est, ref.output[0, 0])
            self._lock_on_contact(t, est, decision)
            if decision.confirmed:
                return self._contact(t, est, ref, decision, "before the planned end")
        else:
            self._contact_rule.idle()
        if tau >= track.t_end:
            self.times["t_L_plan"] = t
            self._search_start = t
            self._hold = None
            self._enter(Phase.TOUCHDOWN, t, "planned landing completed: guarded descent to contact")
        return self._preloaded(ref, t)

    def _lateral(self, ref: Reference, release: bool) -> Reference:
        """``ref`` with the link azimuth left to gravity (``release``, the lateral release
        of ``mission.touchdown.lateral_clearance``), or held where it was at the first sign
        of contact once there was one; with the landing's lean limit
        (``mission.touchdown.lean_limit_deg``)."""
        lean = self._lean_limit
        if self._delta_lock is not None:
            assert ref.output is not None
            out = ref.output.copy()
            out[0, 1] = self._delta_lock
            out[1:, 1] = 0.0
            return dataclasses.replace(ref, output=out, lateral_free=False, lean_limit=lean)
        if release:
            return dataclasses.replace(ref, lateral_free=True, lean_limit=lean)
        return dataclasses.replace(ref, lean_limit=lean) if lean > 0.0 else ref

    def _pressed(self, ref: Reference, t: float) -> Reference:
        """``ref`` with its link elevation no higher than a guarded descent from where the
        landers stopped (``mission.touchdown.press_descent``): phi_d <= phi_p - r (t - t_p),
        phi_p the estimated elevation at the start of the preload t_p, r the descent rate,
        so the reference neither holds the landers up nor lifts them off the surface."""
        td = self.cfg.touchdown
        if not td.press_descent or self._press_t is None:
            return ref
        rate = math.radians(td.descent_rate_deg_s)
        cap = self._press_phi - rate * (t - self._press_t)
        assert ref.output is not None
        if ref.output[0, 0] <= cap:
            return ref
        out = ref.output.copy()
        out[0, 0] = cap
        out[1, 0] = -rate
        out[2:, 0] = 0.0
        return dataclasses.replace(ref, output=out)

    def _lock_on_contact(self, t: float, est: StateEstimate, decision: ContactDecision) -> None:
        """End the lateral release at the first sign of contact: the landers near the
        believed surface and the surface force (or an impact) sensed. Hanging free on its
        landers, a vehicle slides along the surface wherever the sideways forces (a thrust
        tilted by the belief's surface error, the rotors' ground effect) leave it.

        The preload (``mission.touchdown.preload``) begins later, once the link has also
        stopped descending (its estimated rate above -``contact.stall_rate_deg_s``): a
        first sign can come while the landers are still a centimetre or so off the surface
        (the estimated push faked by the approach), and shedding thrust then drives them
        into it rocking (condition (3)); a link that the descending reference no longer
        moves is held by something. Not so after the rate hold has backed the reference
        away (a roll, pitch or sideways swing near the surface): the retreat itself brakes
        and stops the link, with the reference above it and the braking thrust read as a
        push, a centimetre or two above the surface. Such a stop counts again only once
        the estimated link is back at or above the reference, or with an impact (above
        ``contact.impact_force``, which braking does not make: a lander that meets the
        surface during the retreat, as in wall90 draw 00039, still starts the preload at
        once and keeps the vehicle from leaving). Without this, in wall90 draw 00025, 35
        deg bar draw 00096 and 70 deg draw 1787690056 the shed thrust and the press
        descent drove the landers from 1-2 cm into the surface at 7-9 cm/s (conditions
        (2)-(3))."""
        ev = decision.evidence
        if ev is not None and ev.normal_force is not None:
            self._surface_force = ev.normal_force
        if self._slow.alpha < 0.0:
            self._backed_away = True
        elif self._backed_away and ev is not None and ev.link_lag >= 0.0:
            self._backed_away = False
        sign = (
            ev is not None and ev.normal_force is not None and ev.near and ev.pressed
            and est.link is not None
        )  # fmt: skip
        if not sign:
            return
        assert ev is not None and est.link is not None
        td = self.cfg.touchdown
        if (
            self._press_t is None and td.preload > 0.0
            and ev.link_rate > -math.radians(self.cfg.contact.stall_rate_deg_s)
            and (ev.impact or not self._backed_away)
        ):  # fmt: skip
            self._press_t = t
            self._press_phi = est.link.phi
            self._slow.touched = True
            self._event(
                t, "contact",
                f"landers stopped on the surface, thrust shed to {1.0 - td.preload:.2f} at "
                f"{td.preload_rate:g}/s: {ev.describe()}",
            )  # fmt: skip
        if self._sign_t is not None:
            return
        self._sign_t = t
        if td.lateral_lock and self._lateral_clearance > 0.0:
            self._delta_lock = est.link.delta
            self._event(t, "contact", f"first sign of contact, link azimuth held: {ev.describe()}")

    def _preload_shed(self, t: float) -> float:
        """Advance the preload to ``t`` and return the thrust fraction it sheds [-].

        From the start of the preload (:meth:`_lock_on_contact`) the shed fraction moves
        at ``preload_rate`` towards min(``preload``, (N + ``preload_lead``) / (m g)), N the
        estimated surface push: the landers are handed only the load they are measured to
        take, plus a small lead. On the surface N grows with the shed and the fraction
        climbs to ``preload``; after a start that came early (the landers still in the air,
        N about 0) it stays at the lead's few per cent, and a vehicle that leaves the
        surface gets the thrust back."""
        td = self.cfg.touchdown
        if self._press_t is None or td.preload == 0.0:
            return 0.0
        dt = max(t - self._shed_t, 0.0) if self._shed_t is not None else 0.0
        self._shed_t = t
        push = max(self._surface_force, 0.0)
        target = min(td.preload, (push + td.preload_lead) / (self.mass * GRAVITY))
        step = td.preload_rate * dt
        self._shed += min(max(target - self._shed, -step), step)
        return self._shed

    def _preloaded(self, ref: Reference, t: float) -> Reference:
        """``ref`` with the preload's thrust shed."""
        shed = self._preload_shed(t)
        return ref if shed == 0.0 else dataclasses.replace(ref, thrust_shed=shed)

    def _search_reference(self, t: float) -> Reference:
        """The planned end with phi_d descending at touchdown_rate (guarded touchdown)."""
        assert self._track is not None and self._search_start is not None
        ref = self._track.reference(t, self.phase)
        return guarded_descent(self.cfg.touchdown, ref, t - self._search_start, int(self.phase))

    def _touchdown(self, t: float, est: StateEstimate) -> Reference:
        assert self._track is not None
        cfg = self.cfg
        if self._hold is None:  # searching for the surface
            ref = self._lateral(self._search_reference(t), self._lateral_clearance > 0.0)
            ref = self._pressed(ref, t)
            decision = self._contact_rule.update(t, est, ref.output[0, 0])
            self._lock_on_contact(t, est, decision)
            if decision.confirmed:
                return self._contact(t, est, ref, decision, "during the guarded descent")
            td = cfg.touchdown
            limit = td.search_depth_deg / td.descent_rate_deg_s + cfg.detection.no_contact_grace
            if t > self._search_start + limit:
                depth = td.search_depth_deg
                self.abort(t, est, f"fault: no contact within {depth:g} deg beyond phi*")
                return self._free(t, est)
            return self._preloaded(ref, t)
        since = t - self.times["t_L"]  # time on the surface, the spin-down under way [s]
        spin_down = cfg.touchdown.spin_down_time
        if since >= max(cfg.settle_time, spin_down):
            self.times["t_G"] = t
            self._enter(Phase.MOTORS_OFF, t, "landed: motors off (t_G)")
            return Reference(t=t, mode=ControlMode.MOTORS_OFF, phase=int(self.phase))
        scale = max(1.0 - since / spin_down, 0.0) if spin_down > 0.0 else 1.0
        return Reference(
            t=t, mode=ControlMode.TETHERED, phase=int(self.phase), output=self._hold.output,
            thrust_ff=self._hold.thrust_ff, feedforward=self._hold.feedforward,
            lateral_free=self._hold.lateral_free, lean_limit=self._hold.lean_limit,
            thrust_scale=scale,
            thrust_shed=self._shed_at_contact,
        )  # fmt: skip

    def _motors_off(self, t: float, est: StateEstimate) -> Reference:
        cfg = self.cfg
        if t >= self.times["t_G"] + cfg.deploy_time and est.link is not None:
            self.times["t_T"] = t
            t0 = t + cfg.spinup_time
            track = TrajectoryTrack(
                self.takeoff_traj, t0, self.rate_hz, int(Phase.TETHERED_TAKEOFF)
            )
            self._track = BlendedTrack(
                track, self._output_now(est), t, cfg.spinup_time + cfg.blend_time
            )
            self._enter(Phase.SPIN_UP, t, "deployment time over: motors on (t_T)")
            return self._track.reference(t, self.phase)
        return Reference(t=t, mode=ControlMode.MOTORS_OFF, phase=int(self.phase))

    def _spin_up(self, t: float, est: StateEstimate) -> Reference:
        assert self._track is not None
        if t >= self._track.track.t0:
            self._enter(Phase.TETHERED_TAKEOFF, t, "motors up to speed")
        return self._track.reference(t, self.phase)

    def _tethered_takeoff(self, t: float, est: StateEstimate) -> Reference:
        assert self._track is not None
        cfg = self.cfg
        if t >= self._track.track.t_end + cfg.settle_time:
            self.times["t_released"] = t
            # the pull is handed over as a fading force feed-forward (mission.release)
            d = est.body.p_W - self.geo.p_A
            d /= np.linalg.norm(d)
            slack = self.geo.p_A + self.wp.release_distance * d - self.wp.attachment_W
            self._path = self._new_path(t, est.body.p_W, cfg.hooking.speed).to(
                slack, pause=cfg.settle_time
            )
            self._release_pull = ReleasePull(
                t0=t, fade=self._path.segments[0].duration,
                tension=max(est.tension or 0.0, 0.0), d0=d.copy(), mass=self.mass,
                p_A=self.geo.p_A,
            )  # fmt: skip
            self._track = None
            self._enter(
                Phase.RELEASE, t, "takeoff trajectory completed: free flight, releasing tension"
            )
            return self._free(t, est)
        return self._track.reference(t, self.phase)

    def _release(self, t: float, est: StateEstimate) -> Reference:
        wp, cfg = self.wp, self.cfg
        if t >= self._path.t_end:
            slack = self._path.end
            if self._release_pull is not None:  # the pass turns d: freeze the pull
                self._release_pull.freeze(t, est, slack)
            if self.scenario.mechanism.kind == "bar":
                return self._climb_away(t, est, slack)
            if self._magnet:
                return self._drop_magnet(t, est, slack)
            # the reverse pass, no deeper than mission.hooking.unhook_depth
            *corners, last = unhooking_path(
                slack, wp.unhook_entry, wp.hook_start, self._unhook_reach,
                back_off=self.scenario.mechanism.kind != "bar",
            )
            self._path = self._new_path(t, slack, cfg.hooking.speed)
            for p in corners:
                self._path.to(p)
            self._path.to(last, pause=cfg.settle_time)
            self._enter(Phase.UNHOOK, t, "cable slack: reverse hooking pass")
        return self._free(t, est)

    def _drop_magnet(self, t: float, est: StateEstimate, slack: np.ndarray) -> Reference:
        """Magnet mechanism, the cable slack: away from p_A, then up about it, the EPM still
        on, to the drop point (:func:`~tetherland.mission.hooking.magnet_drop_path`: the
        empty boom's tip as far from the surface as the cable lets it, the cable almost
        taut above the magnet), so
        that the magnet, let go, falls a few centimetres before the cable swings it
        (switched off at the slack point, 0.25 m under it, it fell 0.6 m and the snatch
        tipped the vehicle: the rotor fault monitor stopped the flight). :meth:`_unhook`
        then switches it off."""
        cfg = self.cfg
        att = self.wp.attachment_W
        *way, drop = magnet_drop_path(self.scenario, self.geo, slack + att)
        self._path = self._new_path(t, slack, cfg.hooking.speed)
        for p in way:
            self._path.to(p - att)
        self._path.to(drop - att, pause=cfg.settle_time)
        self._enter(Phase.UNHOOK, t, "cable slack: to the drop point, the magnet still held")
        return self._free(t, est)

    def _let_go_of_magnet(self, t: float, est: StateEstimate) -> None:
        """At the drop point: the EPM off, the magnet drops off the plate and hangs on the
        cable. The vehicle holds while the EPM switches off and one swing period more
        (the magnet swings clear of the plate),
        then flies out to the hooking start on a leg shaped at the hanging magnet's swing
        period, as every leg after it (:func:`~tetherland.mission.hooking.swing_shaper`):
        no move adds to its swing."""
        wp, cfg = self.wp, self.cfg
        self._switch_magnet(t, False, "at the drop point: releasing the magnet")
        self._magnet_moves.append((t + self.scenario.mechanism.epm_off_time, "hanging"))
        self._min_leg, self._shaper = self._hanging
        assert self._shaper is not None
        here = self._path.end
        self._path = self._new_path(t, here, cfg.hooking.speed, free_hook=True).to(
            wp.hook_start, pause=cfg.settle_time
        )
        self._path.delay(self.scenario.mechanism.epm_off_time + self._shaper.period)

    def _bar_x(self) -> np.ndarray:
        """Bar mechanism: the horizontal unit direction of x_A, across the bar towards the
        landing point, F_W [-]."""
        x = self.geo.R_WA[:, 0].copy()
        x[2] = 0.0
        return x / np.linalg.norm(x)

    def _climb_away(self, t: float, est: StateEstimate, slack: np.ndarray) -> Reference:
        """Bar mechanism, the cable slack: climb on the landing side until a hook hanging
        free clears the bar, then fly over it to the hooking start. If the hook still sits
        on the bar, the climb draws the line taut: the measured tension above
        ``mission.stretch.tension_threshold`` for ``tension_dwell`` shows it
        (:meth:`_unhook`), and the reverse pass under the bar follows instead.

        The legs are the take-up's (:meth:`_take_up_path`): shaped at the hook's believed
        swing period, so that none leaves a free hook swinging (the robot cannot tell a
        free hook from one on the bar), at the take-up's speed but for the climb, which
        keeps ``hooking.speed``: with a hook on the bar it draws the line taut, slowly.
        Unshaped at ``hooking.speed`` the legs left a free hook still only by lasting
        3-4 periods, and the unhooking took 19-25 s (the pilot, 20-60 deg)."""
        wp, cfg = self.wp, self.cfg
        climb = np.array([*slack[:2], wp.hook_start[2]])
        self._path = (
            self._take_up_path(t, slack)
            .to(climb, speed=cfg.hooking.speed)
            .to(wp.hook_start, pause=cfg.settle_time)
        )
        self._climb_slack = slack.copy()
        self._taut.reset()
        self._enter(Phase.UNHOOK, t, "cable slack: climbing clear of the bar")
        return self._free(t, est)

    def _unhook(self, t: float, est: StateEstimate) -> Reference:
        wp, cfg = self.wp, self.cfg
        if self._magnet_on and t >= self._path.t_end:
            self._let_go_of_magnet(t, est)
            return self._free(t, est)
        slack = self._climb_slack
        if slack is not None and self._taut.update(t, est.tension or 0.0):
            # the hook still sits on the bar (the tension held over the stretch's dwell: a
            # hook that just fell off the bar snatches the line at the bottoms of its
            # swing, 1.26 N for a few ms on slope50 seed 2, and was passed under the bar
            # and caught again): back to slack and the reverse pass under it
            self._climb_slack = None
            *corners, last = unhooking_path(slack, wp.unhook_entry, wp.hook_start,
                                            back_off=False)  # fmt: skip
            # the pass under the bar goes on pass_offset farther from it, and the climb
            # rises there: straight up from the entry (the crown pass_offset beside the
            # believed bar) the tips, pointing up, of a hook swinging or a bar off its
            # belief met the bar and caught it again (pilot draw 35-00000: released, then
            # caught by that climb, "hook did not release"); the return starts from there
            away = -self.scenario.mechanism.pass_offset * self._bar_x()
            corners, last = [p + away for p in corners], last + away
            # the take-up's legs (shaped, at its speed): main's, unshaped at hooking.speed,
            # took 31 s from the climb's top (pilot draw 60-00008 out of the 180 s)
            self._path = self._take_up_path(t, est.body.p_W).to(slack)
            for p in corners:
                self._path.to(p)
            self._entry_climb = (self._path.t_end, corners[-1].copy(), last.copy())
            self._path.to(last, pause=cfg.settle_time)
            self._taut.reset()
            self._event(t, "hook", f"tension {est.tension:.2f} N while climbing: the hook is "
                        "still on the bar, reverse pass under it")  # fmt: skip
            return self._free(t, est)
        climb = self._entry_climb
        if climb is not None and t >= climb[0] and self._taut.update(t, est.tension or 0.0):
            # the climb from the reverse pass's entry drew the line taut: the hook, out of
            # its crook at the entry, hung on the bar's landing side with its line over the
            # bar, and the climb lifted it into the bar (60 deg draw 00011: 2.8 cm beside
            # the axis, 10.7 cm under it; caught, the jam rule's safe stop). Back down to
            # the entry (slack: the hook drops off again), over the bar at the entry's depth
            # (the line leaves the bar, the hook hangs free on the landing side), up there
            # mechanism.reverse_climb_offset beyond the believed axis to the hooking start's
            # height, and over the bar to the hooking start. Not first: a hook hanging free
            # beside the entry (flat arms, the common case) is dragged under the bar by that
            # move and its line draped over it (flat-arm draws 50-00004, -07, 60-00000)
            self._entry_climb = None
            _, entry, last = climb
            x = self._bar_x()
            side = entry + (
                self.scenario.mechanism.reverse_climb_offset - float(x @ (entry - self.geo.p_A))
            ) * x
            self._path = (
                self._take_up_path(t, est.body.p_W)
                .to(entry)
                .to(side)
                .to(np.array([*side[:2], last[2]]), speed=cfg.hooking.speed)
                .to(last, pause=cfg.settle_time)
            )
            self._event(t, "hook", f"tension {est.tension:.2f} N climbing from the reverse "
                        "pass: the hook caught the bar again, down, over and up on its "
                        "landing side")  # fmt: skip
            return self._free(t, est)
        if t >= self._path.t_end:
            up = np.array([*wp.hook_start[:2], wp.z_safe])
            home_high = np.array([*wp.start[:2], wp.z_safe])
            home = wp.start + self._takeoff_height * Z_W
            self._path = (
                self._new_path(t, self._path.end, free_hook=True)
                .to(up)
                .to(home_high)
                .to(home, pause=cfg.settle_time)
            )
            self._enter(Phase.RETURN, t, "hook released: returning")
        return self._free(t, est)

    def _return(self, t: float, est: StateEstimate) -> Reference:
        cfg = self.cfg
        if t >= self._path.t_end:
            self._path = self._new_path(t, self._path.end, cfg.hooking.speed).to(
                self.wp.start - cfg.flight.pad_press_depth * Z_W, pause=cfg.settle_time
            )
            self._enter(Phase.LAND, t, "above the start pad")
        return self._free(t, est)

    def _land(self, t: float, est: StateEstimate) -> Reference:
        if t >= self._path.t_end:
            self.times["t_done"] = t
            self._enter(Phase.DONE, t, "landed on the start pad: motors off")
            self._terminate_at = t + self.cfg.done_hold_time
            return Reference(t=t, mode=ControlMode.MOTORS_OFF, phase=int(self.phase))
        return self._free(t, est)

    def _safe_hover(self, t: float, est: StateEstimate) -> Reference:
        v = est.body.v_W
        if v[0] * v[0] + v[1] * v[1] + v[2] * v[2] > self.cfg.safe_hover_settle_speed**2:
            self._moving_at = t
        if t >= self._path.t_end:
            if self._safe_land:
                self._enter(Phase.ABORTED, t, "safe landing on the start pad: motors off")
                self.safe_state = "landed"
                self._terminate_at = t + self.cfg.done_hold_time
                return Reference(t=t, mode=ControlMode.MOTORS_OFF, phase=int(self.phase))
            cfg = self.cfg
            still = t - self._moving_at >= cfg.settle_time
            if not still and t < self._path.t_end + cfg.safe_hover_max_time:
                return self._free(t, est)  # held on until the vehicle is still
            self._enter(Phase.ABORTED, t, "safe hover held: run ended" if still
                        else "safe hover held, the vehicle not still: run ended")  # fmt: skip
            self.safe_state = "hover"
            self._final_mode = ControlMode.FREE_FLIGHT
            self._terminate_at = t
        return self._free(t, est)

    def _motors_off_hold(self, t: float, est: StateEstimate) -> Reference:
        return Reference(t=t, mode=ControlMode.MOTORS_OFF, phase=int(self.phase))

    def finish(self, t: float) -> None:
        """Close the record of the last phase at the end of the run."""
        self.records.append(PhaseRecord(self.phase, self._phase_start, t, "end of run"))
