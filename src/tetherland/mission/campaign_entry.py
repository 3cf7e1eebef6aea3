"""One randomised run for a campaign: the tethered mission or the contact-free perch."""

from __future__ import annotations

from typing import Any

from tetherland.campaign.perturb import Perturbation
from tetherland.config import Scenario
from tetherland.estimation import UkfEstimator
from tetherland.mission.run import run_mission
from tetherland.sim import Plant
from tetherland.sim.disturbances import WindGusts

_LANDING_KEYS = (
    "position_error_m", "attitude_error_rad", "touchdown_speed_mps",
    "touchdown_angular_rate_rps", "touchdown_accel_mps2", "slip_m",
)  # fmt: skip


def run_for_campaign(
    plant: Scenario,
    belief: Scenario,
    perturbation: Perturbation,
    method: str,
    seed: int,
    controller: str = "hierarchical",
) -> dict[str, Any]:
    """The verdict fields of one run (same names for both methods)."""
    period = 1.0 / plant.controller.rate_hz
    wind: list[WindGusts] = []
    if method == "tethered":
        result = run_mission(
            plant, belief, controller=controller, seed=seed, observers=wind,
            plant_setup=lambda p: wind.append(WindGusts(p, perturbation.gusts, period)),
        )  # fmt: skip
        s = result.summary
        landing = s.get("landing", {})
        return {
            "success": s["success"],
            "reason": s["reason"],
            "aborted": s["aborted"],
            "abort_reason": s["abort_reason"],
            "crashed": s["crashed"],
            "landing": {k: landing.get(k) for k in (*_LANDING_KEYS, "min_tension_N")}
            | {"conditions": landing.get("conditions")},
            "takeoff_completed": s["takeoff"].get("completed", False),
            "return_completed": s["return"].get("completed", False),
            "sim_time_s": s["sim_time_s"],
            "real_time_factor": s["real_time_factor"],
        }
    if method == "free-flight":
        from tetherland.perching import run_perching

        def ukf(sc: Scenario, x0, t0: float, w0):
            return UkfEstimator(sc, x0, t0, rotor_speeds0=w0)

        sim_plant = Plant(plant)
        wind.append(WindGusts(sim_plant, perturbation.gusts, period))
        log, verdict = run_perching(plant, belief, seed, ukf, plant=sim_plant, observers=wind)
        v = verdict.to_dict()
        return {
            "success": v["success"],
            "reason": v["reason"],
            "aborted": False,
            "abort_reason": None if v["success"] else v["reason"],
            "crashed": v["crashed"],
            "landing": {k: v.get(k) for k in _LANDING_KEYS} | {"conditions": v["conditions"]},
            "sim_time_s": float(log["t"][-1]) if log is not None and len(log) else 0.0,
            "real_time_factor": None,
        }
    raise ValueError(f"unknown method {method!r}")
