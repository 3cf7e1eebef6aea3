"""The guarded touchdown: contact confirmed by several signals (docs/theory.md section 10.2).

One rule for the mission's supervisor and the gym expert. Near the end of the planned
landing, and past it while the link reference keeps descending (:func:`guarded_descent`),
contact with the surface is believed only when every signal agrees for
``mission.contact.dwell`` (the names below are fields of ``[mission.contact]``):

1. **clearance**: the lowest lander tip of the estimated pose is within ``clearance`` of
   the *believed* surface (and the link within ``gate_deg`` of the believed phi*), so a
   lagging link far above the surface is a tracking error;
2. **link stall**: the estimated link stays ``link_lag_deg`` above the descending
   reference *and* it descends slower than ``stall_rate_deg_s`` and rises slower than
   ``creep_rate_deg_s``: the surface stops it (a link that still descends lags, it is not
   stopped). On a wall the landers pressed by the descending reference let the
   vehicle creep up the surface at up to about 1 deg/s (the weight does not hold it
   there); a bounce or a gust moves the link faster;
3. **contact force** (when the estimate carries the external force, i.e. the IMU's
   specific force and the rotors' thrust): the external force on the vehicle without its
   component along the cable, projected on the believed surface normal, low-passed, is
   above ``surface_force``, or an impact above ``impact_force`` was seen within twice the
   dwell. Both are read against the *tare*: the estimate's own value in the last
   ``tare_time_constant`` before the landers came within ``clearance`` (where nothing
   pushes), so that a biased estimate (a thrust coefficient or a mass a few per cent off
   the belief reads as a surface force of a few tenths of a newton: about -0.2 N on
   perturbed 50 deg landings, more than the threshold) neither hides a light contact nor
   fakes one.

A gust pushes the vehicle away from the surface only while it lasts and gives no
clearance; an anchor belief error shifts the link angles but not the surface force. A
descent that stalls above the surface therefore goes on until the surface pushes back.
At contact the reference holds the link ``press_deg`` below the contact elevation
(:func:`contact_hold`), which keeps the landers loaded until the motors go off.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from tetherland.config import Scenario
from tetherland.config.mission import ContactConfig, TouchdownConfig
from tetherland.geometry import FloatArray, LandingGeometry, effective_h_R
from tetherland.interfaces import ControlMode, Feedforward, Reference, StateEstimate
from tetherland.models.airframe import lander_tips_B
from tetherland.rotations import quat_to_rotmat


class ContactStatus(enum.Enum):
    """What the rule concludes at one tick."""

    NONE = "none"
    """Some signal disagrees (or the rule is not armed)."""
    CANDIDATE = "candidate"
    """Every signal agrees, for less than the dwell."""
    CONFIRMED = "confirmed"
    """Every signal has agreed for the dwell: touchdown (t_L)."""


@dataclass(frozen=True, slots=True)
class ContactEvidence:
    """The signals of one tick.

    Attributes
    ----------
    clearance : float
        Estimated height of the lowest lander tip above the believed surface [m].
    link_lag : float
        Estimated link elevation minus the reference, phi^ - phi_d [rad].
    link_rate : float
        Estimated link elevation rate [rad/s].
    normal_force : float or None
        Low-passed estimated surface force along the believed normal, less the tare
        (None: the estimate carries no external force) [N].
    near, stalled, pressed : bool
        Signals 1-3 of the module docstring (``pressed`` is True without a force signal).
    impact : bool
        An impact above ``impact_force`` was seen within twice the dwell (False without a
        force signal).
    """

    clearance: float
    link_lag: float
    link_rate: float
    normal_force: float | None
    near: bool
    stalled: bool
    pressed: bool
    impact: bool = False

    def describe(self) -> str:
        """One line for the mission's event log."""
        force = "n/a" if self.normal_force is None else f"{self.normal_force:.2f} N"
        return (
            f"clearance {100.0 * self.clearance:.1f} cm, link {math.degrees(self.link_lag):.2f}"
            f" deg above the reference at {math.degrees(self.link_rate):.2f} deg/s, "
            f"surface force {force}"
        )


@dataclass(frozen=True, slots=True)
class ContactDecision:
    """The rule's answer at one tick, with its evidence (None when not armed)."""

    status: ContactStatus
    evidence: ContactEvidence | None = None

    @property
    def confirmed(self) -> bool:
        return self.status is ContactStatus.CONFIRMED


_NOT_ARMED = ContactDecision(ContactStatus.NONE)


@dataclass(frozen=True)
class ContactGeometry:
    """What the rule knows of the (believed) vehicle and surface (fixed for a run).

    Attributes
    ----------
    z_S : (3,) array
        Believed surface normal in F_W.
    surface_point : (3,) array
        A point of the believed surface plane P_S in F_W [m].
    tips_B : (4, 3) array
        Lander tips' lowest points in F_B (landers plane at -h_R) [m].
    sag : float
        How far the landers plane sits below P_S when landed (0 on a plane; the pipe sag) [m].
    p_A : (3,) array
        Believed anchor in F_W [m].
    r_att_B : (3,) array
        Cable attachment point in F_B [m].
    phi_star : float
        Believed final link elevation [rad].
    """

    z_S: FloatArray
    surface_point: FloatArray
    tips_B: FloatArray
    sag: float
    p_A: FloatArray
    r_att_B: FloatArray
    phi_star: float

    @classmethod
    def from_scenario(cls, scenario: Scenario) -> ContactGeometry:
        geo = LandingGeometry.from_scenario(scenario)
        v = scenario.vehicle
        return cls(
            z_S=geo.surface.z_S.copy(),
            surface_point=geo.p_L.copy(),
            tips_B=lander_tips_B(v.lander_half_width, v.h_R),
            sag=v.h_R - effective_h_R(scenario),
            p_A=geo.p_A.copy(),
            r_att_B=np.asarray(v.cable_attachment, dtype=float),
            phi_star=geo.phi_star,
        )

    def clearance(self, p_W: FloatArray, R_WB: FloatArray) -> float:
        """Height of the lowest lander tip above the believed surface [m] (0 when landed)."""
        heights = (p_W - self.surface_point) @ self.z_S + (self.tips_B @ (R_WB.T @ self.z_S))
        return float(heights.min()) + self.sag

    def normal_force(self, p_W: FloatArray, R_WB: FloatArray, external_B: FloatArray) -> float:
        """The surface's push N of an external force f = -f_L d + N z_S (+ wind) [N].

        The cable pulls along -d (d from the anchor to the attachment point), the surface
        pushes along z_S; N = (f.z_S - (f.d)(d.z_S)) / (1 - (d.z_S)^2) whatever the tension
        (f.z_S where d is along z_S). ``external_B`` is m (f_B - b_a) - f_R e3 in F_B.
        """
        f_W = R_WB @ external_B
        z = self.z_S
        d = p_W + R_WB @ self.r_att_B - self.p_A
        n = float(np.linalg.norm(d))
        fz = float(f_W @ z)
        if n < 1e-9:
            return fz
        d /= n
        dz = float(d @ z)
        across = 1.0 - dz * dz
        if across < 1e-6:
            return fz
        return (fz - float(f_W @ d) * dz) / across


class ContactRule:
    """The multi-signal contact rule of the guarded touchdown (mutable run state).

    Parameters
    ----------
    scenario : Scenario
        The believed scenario (``[mission.contact]`` thresholds, vehicle, surface, anchor).
    """

    def __init__(self, scenario: Scenario) -> None:
        cfg: ContactConfig = scenario.mission.contact
        self.cfg = cfg
        self.geometry = ContactGeometry.from_scenario(scenario)
        self._error = math.radians(cfg.link_lag_deg)
        self._stall = math.radians(cfg.stall_rate_deg_s)
        self._creep = math.radians(cfg.creep_rate_deg_s)
        self._gate = math.radians(cfg.gate_deg)
        self.reset()

    def reset(self) -> None:
        """Forget the dwell, the filtered force, the tare and the last impact."""
        self._since: float | None = None
        self._force: float | None = None
        self._t_force: float | None = None
        self._impact_at = -math.inf
        self.tare = 0.0
        """Baseline of the estimated surface force, subtracted from it (see the module
        docstring) [N]."""
        self._t_tare: float | None = None

    def _update_tare(self, t: float, raw: float) -> None:
        """Low-pass the unfiltered estimate ``raw`` [N] into the tare (clear of the surface)."""
        tau = self.cfg.tare_time_constant
        if self._t_tare is None:
            self.tare = raw
        else:
            self.tare += (1.0 - math.exp(-max(t - self._t_tare, 0.0) / tau)) * (raw - self.tare)
        self._t_tare = t

    def _filtered_force(self, t: float, raw: float) -> float:
        tau = self.cfg.surface_force_time_constant
        if self._force is None or self._t_force is None or tau == 0.0:
            self._force = raw
        else:
            a = 1.0 - math.exp(-max(t - self._t_force, 0.0) / tau)
            self._force += a * (raw - self._force)
        self._t_force = t
        return self._force

    def evidence(self, t: float, est: StateEstimate, phi_d: float) -> ContactEvidence | None:
        """The signals at ``t`` against the reference elevation ``phi_d`` [rad] (updates the
        force filter and the impact memory); None without a link estimate."""
        link = est.link
        if link is None:
            return None
        cfg, geo = self.cfg, self.geometry
        p_W = est.body.p_W
        R_WB = quat_to_rotmat(est.body.q_WB)
        clearance = geo.clearance(p_W, R_WB)
        lag = link.phi - phi_d
        near = clearance < cfg.clearance and link.phi - geo.phi_star < self._gate
        stalled = lag > self._error and -self._stall < link.phi_dot < self._creep
        force: float | None = None
        pressed, impact = True, False
        if est.external_force_B is not None:
            raw = geo.normal_force(p_W, R_WB, est.external_force_B)
            if cfg.tare_time_constant > 0.0:
                if clearance >= cfg.clearance:
                    self._update_tare(t, raw)
                raw -= self.tare
            force = self._filtered_force(t, raw)
            if raw > cfg.impact_force:
                self._impact_at = t
            impact = t - self._impact_at <= 2.0 * cfg.dwell
            pressed = force > cfg.surface_force or impact
        return ContactEvidence(clearance, lag, link.phi_dot, force, near, stalled, pressed, impact)

    def update(self, t: float, est: StateEstimate, phi_d: float) -> ContactDecision:
        """Feed one tick; CONFIRMED once every signal has agreed for ``contact.dwell``."""
        ev = self.evidence(t, est, phi_d)
        if ev is None or not (ev.near and ev.stalled and ev.pressed):
            self._since = None
            return ContactDecision(ContactStatus.NONE, ev)
        if self._since is None:
            self._since = t
        if t - self._since >= self.cfg.dwell - 1e-12:
            return ContactDecision(ContactStatus.CONFIRMED, ev)
        return ContactDecision(ContactStatus.CANDIDATE, ev)

    def idle(self) -> ContactDecision:
        """The rule is not armed at this tick (far from the planned end): restart it."""
        self._since = None
        return _NOT_ARMED


def early_contact_armed(cfg: ContactConfig, t: float, t0: float, duration: float) -> bool:
    """Early contact counts in the last ``contact.window`` of a landing planned from ``t0``
    over ``duration`` seconds."""
    return t > t0 + (1.0 - cfg.window) * duration


def guarded_descent(cfg: TouchdownConfig, ref: Reference, elapsed: float, phase: int) -> Reference:
    """The planned end with phi_d lowered at ``touchdown.descent_rate_deg_s`` for ``elapsed``
    seconds, down to ``touchdown.search_depth_deg`` below it (the guarded descent past the
    plan)."""
    assert ref.output is not None
    rate = math.radians(cfg.descent_rate_deg_s)
    depth = math.radians(cfg.search_depth_deg)
    s = min(rate * max(elapsed, 0.0), depth)
    out = ref.output.copy()
    out[0, 0] -= s
    out[1, 0] = -rate if s < depth else 0.0
    return Reference(
        t=ref.t, mode=ControlMode.TETHERED, phase=phase, output=out,
        thrust_ff=ref.thrust_ff, feedforward=ref.feedforward,
    )  # fmt: skip


def contact_hold(
    cfg: ContactConfig, t: float, est: StateEstimate, ref: Reference, phase: int
) -> Reference:
    """The reference held from contact until the motors go off: the plan's delta,
    theta_A, psi and the estimated link elevation less ``contact.press_deg``, at rest
    (the link azimuth still left to gravity if it was, ``Reference.lateral_free``, and the
    lean limit kept, ``Reference.lean_limit``)."""
    assert est.link is not None and ref.output is not None
    out = np.zeros((5, 4))
    out[0] = ref.output[0]
    out[0, 0] = est.link.phi - math.radians(cfg.press_deg)
    return Reference(
        t=t, mode=ControlMode.TETHERED, phase=phase, output=out,
        thrust_ff=ref.thrust_ff, feedforward=ref.feedforward, lateral_free=ref.lateral_free,
        lean_limit=ref.lean_limit,
    )  # fmt: skip


LATERAL_CLEARANCE = 0.05
"""``mission.touchdown.lateral_clearance`` when it is None, but with the bar [m]."""


def lateral_release_clearance(scenario: Scenario) -> float:
    """The lateral release's clearance [m]: ``mission.touchdown.lateral_clearance``; when
    None, :data:`LATERAL_CLEARANCE`, or 0 (no release) with the bar mechanism, whose hook
    seats beside the anchor in the plane the vehicle flew the stretch in: let hang, the
    vehicle swings into the seat's plumb plane rather than the landing point's."""
    c = scenario.mission.touchdown.lateral_clearance
    if c is not None:
        return c
    return 0.0 if scenario.mechanism.kind == "bar" else LATERAL_CLEARANCE


BAR_LEAN_LIMIT_DEG = 2.5
"""``mission.touchdown.lean_limit_deg`` when it is None, with the bar mechanism [deg]."""


def lean_limit(scenario: Scenario) -> float:
    """The landing's lean limit [rad] (0: none): ``mission.touchdown.lean_limit_deg``;
    when None, :data:`BAR_LEAN_LIMIT_DEG` with the bar mechanism (its lateral release is
    off: :func:`lateral_release_clearance`), none otherwise."""
    limit = scenario.mission.touchdown.lean_limit_deg
    if limit is None:
        limit = BAR_LEAN_LIMIT_DEG if scenario.mechanism.kind == "bar" else 0.0
    return math.radians(limit)


class SlowApproach:
    """The plan's clock slowed near the surface: the last centimetres at a capped speed.

    The link reference approaches the surface at l |phi_d'| (the attachment point moves
    across the cable, nearly along z_S near phi*). Within reach of the believed surface
    the plan's clock tau advances at alpha = min(1, v_cap / (l |phi_d'(tau)|)) with
    v_cap = ``approach_speed`` + ``approach_gain`` * clearance (``[mission.touchdown]``): the
    closer the estimated landers, the slower the reference, and every output (tilt too)
    still follows the planned path. The k-th derivative rows scale by alpha^k, as do the
    feed-forward's rates (d alpha/dt is neglected: alpha changes slowly).

    Rate hold: within ``hold_clearance`` the clock runs backwards (alpha =
    -``hold_retreat``, never before the plan's start) while the estimated
    roll-pitch rate exceeds ``hold_rate`` or the estimated sideways link speed l |delta'|
    exceeds ``hold_lateral_speed`` (a swing along a wall; once ``touched`` the swing only
    stops the clock, alpha = 0), for at most ``hold_max_time`` in
    total, so the reference backs away and a gust's roll or pitch swing decays before the
    landers meet the surface (condition (3)). Backing away along the plan moves the link
    elevation only: the hierarchical law's thrust direction in the link plane is set by
    theta_A, so the retreat itself does not tilt the frame.

    Parameters
    ----------
    cfg : TouchdownConfig
        The ``[mission.touchdown]`` settings.
    geometry : ContactGeometry
    length : float
        Believed cable length l [m].
    lateral_clearance : float
        The lateral release's clearance (:func:`lateral_release_clearance`) [m].
    """

    def __init__(
        self, cfg: TouchdownConfig, geometry: ContactGeometry, length: float,
        lateral_clearance: float,
    ) -> None:  # fmt: skip
        self.cfg = cfg
        self.lateral_clearance = lateral_clearance
        self.geometry = geometry
        self.length = length
        g = geometry
        self._z = g.z_S.tolist()
        self._o = g.surface_point.tolist()
        # the lowest tip lies at most this far below the centre of mass, whatever the tilt
        self._reach = float(np.linalg.norm(g.tips_B, axis=1).max()) - g.sag
        self.start(0.0)

    def start(self, t0: float) -> None:
        """The plan starts at mission time ``t0`` (clock tau = t)."""
        self.tau = t0
        self._t = t0
        self._t0 = t0
        self.alpha = 1.0
        self.held = 0.0
        """Total time the rate hold has held the clock (backing away) [s]."""
        self.clearance = math.inf
        """Estimated lander clearance at the last tick where it was needed (within reach
        of the slowing, the rate hold or the lateral release; inf farther) [m]."""
        self.touched = False
        """Set by the supervisor once the landers are sensed on the surface (the preload's
        start): from then on a swing stops the clock but no longer backs it away (the
        judge measures the slip from the first touch: a vehicle that has touched must
        not leave to land elsewhere)."""

    def advance(self, t: float, est: StateEstimate, rate_at: float) -> float:
        """Advance the clock to mission time ``t``; ``rate_at`` is |phi_d'| at the current
        tau [rad/s]. Returns the new tau [s]."""
        dt = t - self._t
        self._t = t
        cfg = self.cfg
        alpha = 1.0
        v0, gain = cfg.approach_speed, cfg.approach_gain
        speed = self.length * abs(rate_at)
        slow = v0 > 0.0 and speed > v0
        holds = cfg.hold_rate > 0.0 or cfg.hold_lateral_speed > 0.0
        hold = holds and self.held < cfg.hold_max_time
        lateral = self.lateral_clearance
        self.clearance = math.inf
        if slow or hold or lateral > 0.0:
            px, py, pz = est.body.p_W.tolist()
            (zx, zy, zz), (ox, oy, oz) = self._z, self._o
            # a lower bound of the lander clearance, whatever the attitude
            low = (px - ox) * zx + (py - oy) * zy + (pz - oz) * zz - self._reach
            reach = max(cfg.hold_clearance if hold else 0.0, lateral)
            if slow:  # the slowing starts where the capped speed falls below the plan's
                reach = max(reach, (speed - v0) / gain if gain > 0.0 else math.inf)
            if low < reach:  # within reach: the exact clearance
                clearance = self.geometry.clearance(est.body.p_W, quat_to_rotmat(est.body.q_WB))
                self.clearance = clearance
                wx, wy, _ = est.body.omega_B.tolist()
                near = hold and clearance < cfg.hold_clearance
                if near and 0.0 < cfg.hold_rate**2 < wx * wx + wy * wy:
                    alpha = -cfg.hold_retreat
                    self.held += max(dt, 0.0)
                elif near and self._swings(est):
                    alpha = 0.0 if self.touched else -cfg.hold_retreat
                    self.held += max(dt, 0.0)
                elif slow:
                    cap = v0 + gain * max(clearance, 0.0)
                    if speed > cap:
                        alpha = cap / speed
        self.alpha = alpha
        self.tau = max(self.tau + alpha * max(dt, 0.0), self._t0)
        return self.tau

    def _swings(self, est: StateEstimate) -> bool:
        """Whether the estimated sideways link speed l |delta'| exceeds
        ``hold_lateral_speed`` (0: never)."""
        v = self.cfg.hold_lateral_speed
        return v > 0.0 and est.link is not None and self.length * abs(est.link.delta_dot) > v

    def scale(self, ref: Reference, t: float) -> Reference:
        """``ref`` (sampled at tau) for mission time ``t`` with its rates scaled by alpha."""
        a = self.alpha
        if a == 1.0 or ref.output is None:
            if ref.t == t:
                return ref
            return Reference(
                t=t, mode=ref.mode, phase=ref.phase, output=ref.output,
                thrust_ff=ref.thrust_ff, feedforward=ref.feedforward,
            )  # fmt: skip
        out = ref.output * np.array([1.0, a, a * a, a**3, a**4])[: ref.output.shape[0], None]
        ff = ref.feedforward
        if ff is not None:
            ff = Feedforward(
                omega_B=a * ff.omega_B, omega_dot_B=a * a * ff.omega_dot_B, f_R=ff.f_R,
                f_R_dot=a * ff.f_R_dot, f_R_ddot=a * a * ff.f_R_ddot, tension=ff.tension,
            )  # fmt: skip
        return Reference(
            t=t, mode=ref.mode, phase=ref.phase, output=out, thrust_ff=ref.thrust_ff,
            feedforward=ff,
        )  # fmt: skip
