"""The verdict of a mission run: landing conditions (1)-(5), takeoff, return (SI units).

Everything is measured on the plant's truth against the *true* desired landing point (the
robot may believe otherwise). Touchdown t_L is the first tick of the landing phases at which
a lander carries load or the landers plane is within ``CONTACT_CLEARANCE`` of the surface;
t_L- is the tick before. Condition (5) is observed while the motors are off.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np

from tetherland import GRAVITY, __version__
from tetherland.analysis.conditions import LandingTolerances, evaluate_landing
from tetherland.geometry import LandingGeometry
from tetherland.mission.phases import Phase
from tetherland.provenance import provenance
from tetherland.rotations import quat_to_rotmat, quat_to_rotmat_many

if TYPE_CHECKING:
    from tetherland.mission.run import MissionResult

CONTACT_CLEARANCE = 0.002
"""Landers-plane clearance below which the vehicle counts as touching down [m]."""
CONTACT_FORCE = 0.05
"""Lander normal force above which the vehicle counts as touching down [N]."""
REST_SETTLE = 0.3
"""Condition (5): the rest speed is judged from this long after the motors go off (the
slip is measured over the whole interval) [s]."""
_LANDING = (int(Phase.TETHERED_LANDING), int(Phase.TOUCHDOWN))
_TETHERED = (
    int(Phase.TETHERED_LANDING),
    int(Phase.TOUCHDOWN),
    int(Phase.SPIN_UP),
    int(Phase.TETHERED_TAKEOFF),
)


def _z_axes(q: np.ndarray) -> np.ndarray:
    return quat_to_rotmat_many(q)[:, :, 2]


def _landing(result: MissionResult, geo: LandingGeometry, tol: LandingTolerances) -> dict[str, Any]:
    log = result.log
    min_tension = result.belief_scenario.planner.min_tension
    phase = log["phase"].astype(int)
    in_landing = np.isin(phase, _LANDING)
    if not in_landing.any():
        return {"reached": False}
    z_B = _z_axes(log["q_WB"])
    p_RL = log["p_W"] - geo.h_R * z_B
    clearance = (p_RL - geo.surface.origin) @ geo.surface.z_S
    touching = (log["lander_forces"].max(axis=1) > CONTACT_FORCE) | (clearance <= CONTACT_CLEARANCE)
    idx = np.flatnonzero(in_landing & touching)
    if idx.size == 0:
        return {"reached": False, "min_clearance_m": float(clearance[in_landing].min())}
    k = int(idx[0])
    k_prev = max(k - 1, 0)
    t = log["t"]
    dt = float(t[1] - t[0])
    R_prev = quat_to_rotmat(log["q_WB"][k_prev])
    a_W = R_prev @ log["specific_force_B"][k_prev] + np.array([0.0, 0.0, -GRAVITY])
    w = log["omega_B"]
    w_dot = (w[k_prev] - w[max(k_prev - 1, 0)]) / dt
    rest = phase == int(Phase.MOTORS_OFF)
    rest_idx = np.flatnonzero(rest)
    rest_p = p_RL[rest_idx] if rest_idx.size else p_RL[k : k + 1]
    settled = rest_idx[t[rest_idx] >= t[rest_idx[0]] + REST_SETTLE] if rest_idx.size else rest_idx
    rest_v = log["v_W"][settled] if settled.size else np.zeros((1, 3))
    verdict = evaluate_landing(
        p_RL=p_RL[k],
        z_B=z_B[k],
        v_W=log["v_W"][k_prev],
        omega_B=w[k_prev],
        a_W=a_W,
        omega_dot_B=w_dot,
        p_L_star=geo.p_L,
        z_S=geo.surface.z_S,
        rest_p_RL=rest_p,
        rest_v_W=rest_v,
        tol=tol,
    )
    measures = {m.name: m.value for c in verdict.conditions for m in c.measures}
    tethered = np.isin(phase, _TETHERED)
    # the cable must be taut during the tethered landing and takeoff maneuvers wherever the
    # vehicle flies on a plan that needs tension: not while the landers carry it (on a
    # gentle slope friction alone may hold it and the cable slackens; spin-up), nor where
    # the plan itself is slack (flat ground, footnote 3)
    airborne = log["lander_forces"].max(axis=1) <= CONTACT_FORCE
    maneuvers = np.isin(phase, (int(Phase.TETHERED_LANDING), int(Phase.TETHERED_TAKEOFF)))
    planned = maneuvers & airborne & (np.nan_to_num(log["diag.ff_tension"]) >= min_tension)
    return {
        "reached": True,
        "t_L": float(t[k]),
        "position_error_m": measures["position_error"],
        "attitude_error_rad": measures["attitude_error"],
        "touchdown_speed_mps": measures["speed"],
        "touchdown_angular_rate_rps": measures["angular_rate"],
        "touchdown_accel_mps2": measures["accel"],
        "touchdown_angular_accel_rps2": measures["angular_accel"],
        "slip_m": measures["slip"] if rest_idx.size else None,
        "rest_speed_mps": measures["rest_speed"] if rest_idx.size else None,
        "min_tension_N": float(log["tension"][planned].min()) if planned.any() else None,
        "min_tension_all_N": float(log["tension"][tethered].min()) if tethered.any() else None,
        "conditions": {
            str(c.number): c.holds and (c.number != 5 or bool(rest_idx.size))
            for c in verdict.conditions
        },
        "all_conditions": verdict.all_hold and bool(rest_idx.size),
    }


def _takeoff(result: MissionResult) -> dict[str, Any]:
    sup = result.supervisor
    log = result.log
    if "t_released" not in sup.times:
        return {"completed": False}
    target = sup.takeoff_traj.output(sup.takeoff_traj.duration).value
    k = int(np.searchsorted(log["t"], sup.times["t_released"]))
    k = min(k, len(log) - 1)
    phi = float(log["link_phi"][k]) if "link_phi" in log else float("nan")
    z_A = sup.geo.R_WA.T @ _z_axes(log["q_WB"][k : k + 1])[0]
    theta = math.atan2(z_A[0], z_A[2])
    during = log["phase"].astype(int) == int(Phase.TETHERED_TAKEOFF)
    return {
        "completed": True,
        "phi_error_rad": abs(phi - target[0]),
        "theta_A_error_rad": abs(theta - target[2]),
        "min_tension_N": float(log["tension"][during].min()) if during.any() else None,
    }


def _return(result: MissionResult) -> dict[str, Any]:
    sup = result.supervisor
    log = result.log
    if "t_done" not in sup.times:
        return {"completed": False}
    z_B = _z_axes(log["q_WB"][-1:])[0]
    p_RL = log["p_W"][-1] - result.plant_scenario.vehicle.h_R * z_B
    pad = sup.p_start - result.plant_scenario.vehicle.h_R * np.array([0.0, 0.0, 1.0])
    return {
        "completed": True,
        "position_error_m": float(np.linalg.norm(p_RL - pad)),
        "speed_mps": float(np.linalg.norm(log["v_W"][-1])),
    }


def evaluate(result: MissionResult, tol: LandingTolerances | None = None) -> dict[str, Any]:
    """The ``summary.json`` document of a run (see the module docstring)."""
    tol = tol or LandingTolerances()
    log = result.log
    sup = result.supervisor
    geo = LandingGeometry.from_scenario(result.plant_scenario)
    events = log.metadata.get("events", [])
    hook = [e for e in events if e.get("source") == "hook"]
    landing = _landing(result, geo, tol)
    takeoff = _takeoff(result)
    ret = _return(result)
    crashed = bool(np.any(log["frame_force"] > 1e-6))
    sim_time = float(log["t"][-1]) if len(log) else 0.0
    done = sup.phase == Phase.DONE or any(r.phase == Phase.DONE for r in sup.records)
    tension_ok = landing.get("min_tension_N") is None or landing["min_tension_N"] > 0.0
    reasons = []
    if sup.abort_reason is not None:
        reasons.append(f"aborted: {sup.abort_reason}")
    if not landing.get("reached", False):
        reasons.append("no touchdown in the landing phases")
    elif not landing.get("all_conditions", False):
        failed = [k for k, ok in landing["conditions"].items() if not ok]
        reasons.append(f"landing condition(s) {', '.join(failed)} not met")
    if not tension_ok:
        reasons.append("cable went slack where the plan needs tension")
    if landing.get("reached") and not takeoff.get("completed", False):
        reasons.append("takeoff not completed")
    if takeoff.get("completed") and not ret.get("completed", False):
        reasons.append("return not completed")
    if crashed:
        reasons.append("the frame touched something (crash)")
    if not done and not reasons:
        reasons.append(f"mission did not finish ({log.metadata.get('status')})")
    success = not reasons
    return {
        "success": success,
        "reason": "ok" if success else "; ".join(reasons),
        "method": "tethered",
        "scenario": result.plant_scenario.name,
        "controller": result.controller,
        "seed": result.seed,
        "status": log.metadata.get("status"),
        "aborted": sup.abort_reason is not None,
        "abort_reason": sup.abort_reason,
        "crashed": crashed,
        "phases": [r.to_dict() for r in sup.records],
        "times": dict(sup.times),
        "hook": {
            "attempts": sup.hook_attempts,
            "events": [{"t": e["t"], "kind": e["kind"]} for e in hook],
        },
        "landing": landing,
        "takeoff": takeoff,
        "return": ret,
        "switches": [
            {
                "t": s.t,
                "from": s.from_mode.name.lower(),
                "to": s.to_mode.name.lower(),
                "thrust_jump_N": s.thrust_jump,
                "rotor_speed_jump_radps": s.rotor_speed_jump,
            }
            for s in result.switches
        ],
        "tolerances": {
            "position_m": tol.position,
            "attitude_rad": tol.attitude,
            "speed_mps": tol.speed,
            "angular_rate_rps": tol.angular_rate,
            "accel_mps2": tol.accel,
            "slip_m": tol.slip,
        },
        "sim_time_s": sim_time,
        "wall_time_s": result.wall_time_s,
        "real_time_factor": sim_time / result.wall_time_s if result.wall_time_s > 0 else None,
        "version": __version__,
        "provenance": provenance(
            result.plant_scenario, seed=result.seed, extra={"controller": result.controller}
        ),
    }
