"""Fault detection from what the robot measures (issue 15, docs/faults.md).

:class:`FaultMonitor` runs inside the mission supervisor at every control tick. It reads
only the state estimate (pose, covariance, estimated tension, link state w.r.t. the
*believed* anchor) and the commands sent (it is ``CommandAware``); it never sees the
injected faults. Each rule compares one measured signal with a ``[mission.detection]``
limit held for a dwell time:

* rotor: the roll/pitch torque the controller commands, low-passed, less the estimated
  cable torque r_att x F_L (F_L = -f_L d in F_B, d the believed link direction). In steady
  flight the rotors cancel the cable torque; a weak rotor i makes the controller command
  the missing arm_i x (1 - eff_i) f_i, which stays;
* anchor belief: with the cable taut, the believed anchor to the estimated attachment
  point is l + f_L/k (the stretch of an elastic cable; l for an ideal one); a believed
  anchor off along the cable shows as a length error. A weak rotor fakes one as well: its
  missing thrust is read as a cable pull (an estimated tension with the cable slack, far
  short of its length). So the rotor is checked first (:meth:`FaultMonitor.check`): while
  the torque residual is above ``rotor_suspect`` of its limit the anchor rule does not
  decide, and a length error beyond its limit with the residual beyond the rotor's limit
  is a rotor fault at once (two signals agree: no need for the rotor's dwell);
* motion capture: the estimator's position standard deviation grows while no pose
  arrives (largest axis of the covariance; from ``airborne_delay`` on, once the filter has
  converged from its initial covariance);
* hook jam: an estimated tension after the unhooking pass (the cable still pulls);
* cable snap: the estimated tension lost in tethered flight for a short dwell (and the
  supervisor's missed-hook rule: no tension after stretching).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from tetherland.config import FaultKind, Scenario
from tetherland.estimation import ThresholdDwell
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import Command, StateEstimate
from tetherland.mission.phases import Phase
from tetherland.rotations import quat_to_rotmat

ROTOR_PHASES = frozenset({
    Phase.TAKEOFF, Phase.APPROACH, Phase.RETRY, Phase.HOOKING, Phase.STRETCH,
    Phase.TETHERED_LANDING, Phase.TETHERED_TAKEOFF, Phase.RELEASE, Phase.UNHOOK,
    Phase.RETURN,
})  # fmt: skip
"""Airborne phases in which the torque rule runs (not on the pad or the surface)."""
ANCHOR_PHASES = frozenset({Phase.STRETCH, Phase.TETHERED_LANDING, Phase.TETHERED_TAKEOFF})
"""Phases in which a taut cable's length is checked."""
SNAP_PHASES = frozenset({Phase.TETHERED_LANDING, Phase.SPIN_UP, Phase.TETHERED_TAKEOFF})
"""The cable carries the vehicle: tethered flight, and the spin-up before the takeoff (the
motors reach the landed hover's thrust with the landers still down)."""
LANDED_PHASES = frozenset({Phase.TOUCHDOWN, Phase.MOTORS_OFF, Phase.SPIN_UP})
"""Landed on the cable: a moving vehicle means the cable no longer holds it. Watched from
the confirmed contact (the spin-down, where the plan no longer tells the tension the cable
must carry) and again from where the motors went off (the landing settles onto the
landers and the cable then)."""
SNAP_PLAN_FACTOR = 3.0
"""The snap rule watches where the planned tension is at least this many snap_tension."""
JAM_PHASES = frozenset({Phase.RETURN, Phase.LAND})
"""Phases after the unhooking pass: any tension means the hook is still engaged."""
_DWELL_RULE_PHASES = SNAP_PHASES | ANCHOR_PHASES | LANDED_PHASES | JAM_PHASES
"""Phases in which the snap, anchor, landed or jam rule watches; in any other phase each of
them only stays reset."""


@njit(cache=True)
def cable_torque_xy_of(
    q_WB: np.ndarray, p_W: np.ndarray, tension: float, r_att_B: np.ndarray, p_A: np.ndarray
) -> tuple[float, float, float]:  # pragma: no cover (compiled)
    """Compiled :meth:`FaultMonitor.cable_torque_xy` with the distance of
    :meth:`FaultMonitor._geometry` (the same operations in the same order: the same bits;
    a test checks it): the roll and pitch of the cable torque r_att x F_L, F_L = -f_L d,
    in F_B [N m] and the distance D = |p_att - p_A| [m], from the estimated attitude
    ``q_WB`` (unit, w first), position ``p_W`` [m], the tension (clamped at 0 here) [N],
    the attachment point ``r_att_B`` [m] and the believed anchor ``p_A`` [m]. Called at
    every control tick of the rotor rule."""
    w, x, y, z = q_WB[0], q_WB[1], q_WB[2], q_WB[3]
    rx, ry, rz = r_att_B[0], r_att_B[1], r_att_B[2]
    r00, r01, r02 = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
    r10, r11, r12 = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
    r20, r21, r22 = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
    dx = p_W[0] + r00 * rx + r01 * ry + r02 * rz - p_A[0]
    dy = p_W[1] + r10 * rx + r11 * ry + r12 * rz - p_A[1]
    dz = p_W[2] + r20 * rx + r21 * ry + r22 * rz - p_A[2]
    D = math.sqrt(dx * dx + dy * dy + dz * dz)
    inv = 1.0 / (1e-9 if 1e-9 > D else D)  # max(D, 1e-9), as Python's max picks
    bx = (r00 * dx + r10 * dy + r20 * dz) * inv
    by = (r01 * dx + r11 * dy + r21 * dz) * inv
    bz = (r02 * dx + r12 * dy + r22 * dz) * inv
    f = 0.0 if 0.0 > tension else tension
    fx, fy, fz = -f * bx, -f * by, -f * bz
    return ry * fz - rz * fy, rz * fx - rx * fz, D


_cable_torque_xy_of = cable_torque_xy_of  # (a module global: one lookup per tick)


@dataclass(frozen=True)
class FaultDetection:
    """A detected fault.

    Attributes
    ----------
    kind : FaultKind
    t : float
        Detection time [s].
    reason : str
        One line naming the signal and the limit (logged, and the abort reason).
    """

    kind: FaultKind
    t: float
    reason: str


class FaultMonitor:
    """The measured-signal fault rules of the module docstring.

    Parameters
    ----------
    scenario : Scenario
        The believed scenario (``mission.detection`` limits, mass, cable, attachment).
    geometry : LandingGeometry
        The believed geometry (anchor p_A).
    """

    def __init__(self, scenario: Scenario, geometry: LandingGeometry) -> None:
        cfg = scenario.mission.detection
        self.cfg = cfg
        self._tension_threshold = scenario.mission.stretch.tension_threshold
        self._p_A = np.ascontiguousarray(geometry.p_A, dtype=float)
        self._r_att = np.asarray(scenario.vehicle.cable_attachment, dtype=float)
        self._length = scenario.tether.length
        self._stiffness = scenario.tether.stiffness
        self._rx, self._ry, self._rz = (float(x) for x in self._r_att)
        self._ax, self._ay, self._az = (float(x) for x in self._p_A)
        self._torque_cmd = (0.0, 0.0)
        self._lp_x = self._lp_y = 0.0
        self._t_last: float | None = None
        self._lp_dt = math.nan  # the step of the low-pass weight _lp_a [s]
        self._lp_a = 0.0
        self._rotor = ThresholdDwell(cfg.rotor_torque, cfg.rotor_dwell)
        self._anchor = ThresholdDwell(cfg.anchor_length_error, cfg.anchor_dwell)
        self._jam = ThresholdDwell(cfg.jam_tension, cfg.jam_dwell)
        self._snap = ThresholdDwell(0.0, cfg.snap_dwell)  # fed limit - tension
        self._landed_p: tuple[float, float, float] | None = None  # where the phase began
        self._landed_phase: Phase | None = None  # TOUCHDOWN, or MOTORS_OFF for both after
        # a phase in which the snap, anchor, jam and landed rules were last found idle (all
        # reset): while it lasts, their resets are not repeated every tick
        self._idle_phase: Phase | None = None
        self._distance: float | None = None  # D of the estimate being checked [m]
        self.torque_residual = 0.0
        """Last low-passed roll/pitch torque residual [N m]."""
        self.length_error = math.nan
        """Last taut-cable length error [m] (NaN when not checked)."""
        self.position_std = math.nan
        """Last estimated position standard deviation, largest axis [m]."""

    # ------------------------------------------------------------------ CommandAware
    def command_sent(self, t: float, command: Command) -> None:
        """Keep the commanded roll/pitch torque (zero with the motors off)."""
        tau = command.torque_B
        self._torque_cmd = (0.0, 0.0) if tau is None else (float(tau[0]), float(tau[1]))

    # ------------------------------------------------------------------ rules
    def cable_torque_B(self, est: StateEstimate) -> np.ndarray:
        """Estimated cable torque r_att x F_L in F_B, F_L = -f_L d (toward the believed
        anchor) [N m]."""
        tension = max(est.tension or 0.0, 0.0)
        R_WB = quat_to_rotmat(est.body.q_WB)
        d = est.body.p_W + R_WB @ self._r_att - self._p_A
        d /= max(float(np.linalg.norm(d)), 1e-9)
        return np.cross(self._r_att, R_WB.T @ (-tension * d))

    def _geometry(self, est: StateEstimate) -> tuple[float, float, float, float]:
        """Scalar form (the control-rate path) of the attachment geometry: the unit link
        direction d in F_B and the distance D = |p_att - p_A| [m]; :meth:`cable_torque_B`
        is its plain reference (a test checks both agree)."""
        w, x, y, z = est.body.q_WB.tolist()
        px, py, pz = est.body.p_W.tolist()
        rx, ry, rz = self._rx, self._ry, self._rz
        # R_WB from the unit quaternion (w, x, y, z)
        r00, r01, r02 = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
        r10, r11, r12 = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
        r20, r21, r22 = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
        dx = px + r00 * rx + r01 * ry + r02 * rz - self._ax
        dy = py + r10 * rx + r11 * ry + r12 * rz - self._ay
        dz = pz + r20 * rx + r21 * ry + r22 * rz - self._az
        D = math.sqrt(dx * dx + dy * dy + dz * dz)
        inv = 1.0 / max(D, 1e-9)
        # d in F_B = R_WB^T d_W
        bx = (r00 * dx + r10 * dy + r20 * dz) * inv
        by = (r01 * dx + r11 * dy + r21 * dz) * inv
        bz = (r02 * dx + r12 * dy + r22 * dz) * inv
        return bx, by, bz, D

    def cable_torque_xy(self, est: StateEstimate) -> tuple[float, float]:
        """Roll and pitch of :meth:`cable_torque_B` in scalar form [N m]."""
        tension = max(est.tension or 0.0, 0.0)
        bx, by, bz, _ = self._geometry(est)
        fx, fy, fz = -tension * bx, -tension * by, -tension * bz
        rx, ry, rz = self._rx, self._ry, self._rz
        return ry * fz - rz * fy, rz * fx - rx * fz

    def check(
        self,
        t: float,
        est: StateEstimate,
        phase: Phase,
        airborne: bool,
        nominal_tension: float | None = None,
    ) -> FaultDetection | None:
        """Run every rule at time ``t`` in ``phase``; the first fault found, or None.

        ``airborne`` says the vehicle has been off the pad long enough for the torque
        rule (``airborne_delay``). ``nominal_tension`` is the plan's tension at ``t`` [N]
        (None: unknown): the snap rule only watches where the plan needs at least
        :data:`SNAP_PLAN_FACTOR` times ``snap_tension`` (near a flat touchdown the planned
        tension itself falls towards zero, and the slower slack-cable rule covers it).
        """
        cfg = self.cfg
        self._distance = None  # the rotor rule's D of this estimate, when it runs
        cov = est.covariance
        if cov is not None:
            std = math.sqrt(max(cov.diagonal()[:3].tolist()))  # (one call, not 3 indexings)
            self.position_std = std
            if t >= cfg.airborne_delay and std > cfg.position_std:
                return FaultDetection(
                    FaultKind.MOCAP, t,
                    f"fault: motion capture lost (estimated position std {100 * std:.1f} cm "
                    f"> {100 * cfg.position_std:g} cm)",
                )  # fmt: skip
        found = self._rotor_rule(t, est, phase, airborne)
        if found is not None or phase == self._idle_phase:
            return found  # (idle: the other rules are reset and would only reset again)
        needs = nominal_tension is None or (
            nominal_tension >= SNAP_PLAN_FACTOR * self.cfg.snap_tension
        )
        limit = self.cfg.snap_tension
        if nominal_tension is not None:
            limit = max(limit, self.cfg.snap_fraction * nominal_tension)
        found = self._snap_rule(t, est, phase, needs, limit)
        if found is None:
            found = self._anchor_rule(t, est, phase)
        if found is None:
            found = self._jam_rule(t, est, phase)
        if found is None:
            found = self._landed_rule(t, est, phase)
        self._idle_phase = None if phase in _DWELL_RULE_PHASES else phase
        return found

    def _rotor_rule(
        self, t: float, est: StateEstimate, phase: Phase, airborne: bool
    ) -> FaultDetection | None:
        dt = 0.0 if self._t_last is None else t - self._t_last
        self._t_last = t
        if not (airborne and phase in ROTOR_PHASES):
            self._lp_x = self._lp_y = 0.0
            self.torque_residual = 0.0
            self._rotor.reset()
            return None
        # cable_torque_xy and the distance in one compiled call (the control-rate path);
        # the distance is kept for the anchor and jam rules of this check
        body = est.body
        cx, cy, self._distance = _cable_torque_xy_of(
            body.q_WB, body.p_W, est.tension or 0.0, self._r_att, self._p_A
        )
        if dt != self._lp_dt:  # (the tick is constant: the weight is computed once)
            self._lp_dt = dt
            self._lp_a = 1.0 - math.exp(-dt / self.cfg.rotor_torque_time_constant)
        a = self._lp_a
        self._lp_x += a * (self._torque_cmd[0] + cx - self._lp_x)
        self._lp_y += a * (self._torque_cmd[1] + cy - self._lp_y)
        self.torque_residual = r = math.hypot(self._lp_x, self._lp_y)
        if self._rotor.update(t, r):
            return FaultDetection(
                FaultKind.ROTOR, t,
                f"fault: rotor thrust lost (commanded roll/pitch torque beyond the cable's "
                f"{r:.3f} N m > {self.cfg.rotor_torque:g} N m)",
            )  # fmt: skip
        return None

    def _snap_rule(
        self, t: float, est: StateEstimate, phase: Phase, armed: bool, limit: float
    ) -> FaultDetection | None:
        if not (armed and phase in SNAP_PHASES):
            self._snap.reset()
            return None
        tension = est.tension or 0.0
        if self._snap.update(t, limit - tension):  # below the limit for the dwell
            return FaultDetection(
                FaultKind.SNAP, t,
                f"fault: cable lost, tension gone (estimated {tension:.2f} N < "
                f"{limit:.2f} N for {self.cfg.snap_dwell:g} s)",
            )  # fmt: skip
        return None

    def rotor_suspected(self) -> bool:
        """The low-passed torque residual is above ``rotor_suspect`` of the rotor limit: a
        weak rotor may be what the other signals see."""
        cfg = self.cfg
        return self.torque_residual > cfg.rotor_suspect * cfg.rotor_torque

    def _anchor_rule(self, t: float, est: StateEstimate, phase: Phase) -> FaultDetection | None:
        """The taut cable's length error; checked against the rotor before it names the
        anchor: beyond the rotor limit the torque residual makes it a rotor fault at once,
        above ``rotor_suspect`` of it the anchor is not named (its dwell keeps running,
        the rotor rule may confirm)."""
        tension = est.tension or 0.0
        if phase not in ANCHOR_PHASES or tension < self._tension_threshold:
            self._anchor.reset()
            self.length_error = math.nan
            return None
        stretch = 0.0 if self._stiffness is None else tension / self._stiffness
        D = self._geometry(est)[3] if self._distance is None else self._distance
        err = D - self._length - stretch
        self.length_error = err
        held = self._anchor.update(t, abs(err))
        if abs(err) <= self.cfg.anchor_length_error:
            return None
        # a weak rotor's missing thrust reads as a cable pull too: the torque decides
        r, cfg = self.torque_residual, self.cfg
        if r > cfg.rotor_torque:  # two signals agree: no need for the rotor's dwell
            return FaultDetection(
                FaultKind.ROTOR, t,
                f"fault: rotor thrust lost (commanded roll/pitch torque beyond the cable's "
                f"{r:.3f} N m > {cfg.rotor_torque:g} N m, with the taut cable "
                f"{100 * err:+.1f} cm off its length: the missing thrust read as a cable "
                f"pull, not the anchor)",
            )  # fmt: skip
        if held and not self.rotor_suspected():
            return FaultDetection(
                FaultKind.ANCHOR, t,
                f"fault: anchor belief error (taut cable {100 * err:+.1f} cm off its length "
                f"from the believed anchor, limit {100 * self.cfg.anchor_length_error:g} cm)",
            )  # fmt: skip
        return None

    def _landed_rule(self, t: float, est: StateEstimate, phase: Phase) -> FaultDetection | None:
        if phase not in LANDED_PHASES:
            self._landed_p = None
            return None
        since = Phase.TOUCHDOWN if phase == Phase.TOUCHDOWN else Phase.MOTORS_OFF
        px, py, pz = est.body.p_W.tolist()
        if self._landed_p is None or since != self._landed_phase:
            self._landed_p, self._landed_phase = (px, py, pz), since
            return None
        x0, y0, z0 = self._landed_p
        moved = math.sqrt((px - x0) ** 2 + (py - y0) ** 2 + (pz - z0) ** 2)
        if moved > self.cfg.landed_distance:
            when = "the contact" if since == Phase.TOUCHDOWN else "the motors went off"
            return FaultDetection(
                FaultKind.SNAP, t,
                f"fault: cable lost while landed (the vehicle moved {100 * moved:.1f} cm > "
                f"{100 * self.cfg.landed_distance:g} cm since {when})",
            )  # fmt: skip
        return None

    def _jam_rule(self, t: float, est: StateEstimate, phase: Phase) -> FaultDetection | None:
        if phase not in JAM_PHASES:
            self._jam.reset()
            return None
        tension = est.tension or 0.0
        if tension > self.cfg.jam_tension and (
            (self._geometry(est)[3] if self._distance is None else self._distance)
            < self._length - self.cfg.jam_slack
        ):  # the cable could be slack: it cannot be what pulls
            tension = 0.0
        if self._jam.update(t, tension):
            return FaultDetection(
                FaultKind.JAM, t,
                f"fault: hook did not release (estimated tension {est.tension:.2f} N > "
                f"{self.cfg.jam_tension:g} N after unhooking)",
            )  # fmt: skip
        return None


__all__ = [
    "ANCHOR_PHASES",
    "JAM_PHASES",
    "LANDED_PHASES",
    "ROTOR_PHASES",
    "SNAP_PHASES",
    "FaultDetection",
    "FaultMonitor",
    "cable_torque_xy_of",
]
