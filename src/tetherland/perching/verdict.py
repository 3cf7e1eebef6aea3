"""Landing conditions (1)-(5) of a contact-free perching run, from its log.

Touchdown t_L is the first logged control tick with a contact force on a lander (or on
the frame: a crash); t_L- is the tick before. Measured with the plant's true geometry:

* (1) ||p_RL(t_L) - p*_L||, p_RL = p - h_R z_B;
* (2) angle between z_B(t_L) and z_S;
* (3) ||p'(t_L-)|| and ||omega(t_L-)||;
* (4) ||p''(t_L-)|| (from the true specific force) and ||omega'(t_L-)|| (difference of
  the two ticks before contact);
* (5) observed: displacement of p_RL (slip) and speed while the motors are off, from
  ``perching.settle_time`` after the cut-off to the end of the log.

``success``: touchdown happened, conditions (1), (2), (3) and (5) hold and the frame never
touched anything. Condition (4) is reported but not required: without a tether it can
hold only on horizontal ground (section 6.4.1, Table 6.1: "all but condition (4)").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tetherland import GRAVITY
from tetherland.analysis.conditions import (
    LandingTolerances,
    LandingVerdict,
    evaluate_landing,
    touchdown_index,
)
from tetherland.config import Scenario
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import ControlMode
from tetherland.rotations import quat_to_rotmat_many
from tetherland.sim.log import RunStatus, SimLog

REQUIRED = (1, 2, 3, 5)
"""Conditions a contact-free landing must meet to count as a success."""


@dataclass(frozen=True)
class PerchVerdict:
    """The landing conditions of one perching run (field names shared with the tethered
    mission's summary).

    Attributes
    ----------
    position_error_m : float
        Condition (1): ||p_RL(t_L) - p*_L|| [m].
    attitude_error_rad : float
        Condition (2): angle(z_B(t_L), z_S) [rad].
    touchdown_speed_mps, touchdown_angular_rate_rps : float
        Condition (3) at t_L- [m/s, rad/s].
    touchdown_accel_mps2 : float
        Condition (4): ||p''(t_L-)|| [m/s^2].
    slip_m : float
        Condition (5): largest displacement of p_RL while resting with the motors off [m].
    conditions : dict of int to bool
        Conditions (1)-(5).
    success : bool
        See the module docstring.
    crashed : bool
        The frame (hub or rotor guards) touched something during the run.
    touchdown_time_s, motors_off_time_s : float or None
        [s].
    reason : str
        One line: ``"ok"`` or why not.
    landing : LandingVerdict or None
        The full per-condition measures.
    """

    position_error_m: float
    attitude_error_rad: float
    touchdown_speed_mps: float
    touchdown_angular_rate_rps: float
    touchdown_accel_mps2: float
    slip_m: float
    conditions: dict[int, bool]
    success: bool
    crashed: bool = False
    touchdown_time_s: float | None = None
    motors_off_time_s: float | None = None
    reason: str = "ok"
    landing: LandingVerdict | None = field(default=None, repr=False)

    @classmethod
    def failed(cls, reason: str, crashed: bool = False) -> PerchVerdict:
        """A verdict without a touchdown to measure (no plan, no contact, diverged)."""
        nan = math.nan
        return cls(nan, nan, nan, nan, nan, nan, dict.fromkeys(range(1, 6), False),
                   success=False, crashed=crashed, reason=reason)  # fmt: skip

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready (NaN as None, condition numbers as strings)."""

        def num(x: float | None) -> float | None:
            return None if x is None or not math.isfinite(x) else float(x)

        return {
            "position_error_m": num(self.position_error_m),
            "attitude_error_rad": num(self.attitude_error_rad),
            "touchdown_speed_mps": num(self.touchdown_speed_mps),
            "touchdown_angular_rate_rps": num(self.touchdown_angular_rate_rps),
            "touchdown_accel_mps2": num(self.touchdown_accel_mps2),
            "slip_m": num(self.slip_m),
            "conditions": {str(k): bool(v) for k, v in sorted(self.conditions.items())},
            "success": self.success,
            "crashed": self.crashed,
            "touchdown_time_s": num(self.touchdown_time_s),
            "motors_off_time_s": num(self.motors_off_time_s),
            "reason": self.reason,
        }


def contact_index(log: SimLog) -> int | None:
    """First row with a contact force on a lander or on the frame (None: no contact)."""
    force = np.nansum(log["lander_forces"], axis=1) + np.nan_to_num(log["frame_force"])
    return touchdown_index(-force, -1e-9)


def evaluate_perch(
    log: SimLog, scenario: Scenario, tol: LandingTolerances | None = None
) -> PerchVerdict:
    """Landing conditions of a perching run logged by the runner (plant truth).

    Parameters
    ----------
    log : SimLog
        A run of :class:`~tetherland.perching.PerchingReference` (``mode`` column marks
        the motors-off interval).
    scenario : Scenario
        The plant's (true) scenario: surface, landing point, h_R, ``perching.settle_time``.
    """
    tol = tol or LandingTolerances()
    crashed = bool(np.any(np.nan_to_num(log["frame_force"]) > 0.0))
    if log.status in (RunStatus.DIVERGED, RunStatus.FAILED):
        return PerchVerdict.failed(f"run {log.status.value}: {log.metadata.get('message', '')}",
                                   crashed)  # fmt: skip
    k = contact_index(log)
    if k is None or k == 0:
        return PerchVerdict.failed(
            "no touchdown: the vehicle never touched the surface" if k is None
            else "in contact from the first tick", crashed,
        )  # fmt: skip
    geo = LandingGeometry.from_scenario(scenario)
    z_S = geo.surface.z_S
    t = log.t
    R = quat_to_rotmat_many(log["q_WB"])
    z_B = R[:, :, 2]
    p_RL = log["p_W"] - geo.h_R * z_B
    v, w = log["v_W"], log["omega_B"]
    a = np.einsum("nij,nj->ni", R, log["specific_force_B"]) + np.array([0.0, 0.0, -GRAVITY])
    j = k - 1
    w_dot = (w[j] - w[j - 1]) / (t[j] - t[j - 1]) if j >= 1 else np.zeros(3)
    off = np.flatnonzero(log["mode"] == int(ControlMode.MOTORS_OFF))
    t_off = float(t[off[0]]) if off.size else None
    rest = off[t[off] >= t_off + scenario.perching.settle_time] if t_off is not None else off
    landing = evaluate_landing(
        p_RL=p_RL[k], z_B=z_B[k], v_W=v[j], omega_B=w[j], a_W=a[j], omega_dot_B=w_dot,
        p_L_star=geo.p_L, z_S=z_S, rest_p_RL=p_RL[rest], rest_v_W=v[rest], tol=tol,
    )  # fmt: skip
    measures = {m.name: m.value for c in landing.conditions for m in c.measures}
    conditions = {c.number: c.holds for c in landing.conditions}
    success = all(conditions[n] for n in REQUIRED) and not crashed
    failed = [str(n) for n in REQUIRED if not conditions[n]]
    reasons = []
    if failed:
        reasons.append("condition(s) " + ", ".join(failed) + " not met")
    if crashed:
        reasons.append("the frame touched something (crash)")
    reason = "; ".join(reasons) or "ok"
    if t_off is None:
        success, reason = False, "the motors were never switched off"
    elif rest.size == 0:
        success, reason = False, "the log ends before the motors-off rest could be observed"
    return PerchVerdict(
        position_error_m=measures["position_error"],
        attitude_error_rad=measures["attitude_error"],
        touchdown_speed_mps=measures["speed"],
        touchdown_angular_rate_rps=measures["angular_rate"],
        touchdown_accel_mps2=measures["accel"],
        slip_m=measures["slip"],
        conditions=conditions,
        success=success,
        crashed=crashed,
        touchdown_time_s=float(t[k]),
        motors_off_time_s=t_off,
        reason=reason,
        landing=landing,
    )
