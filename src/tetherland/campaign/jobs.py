"""One campaign run, as a pure function of its job (picklable, engine-independent)."""

from __future__ import annotations

import threading
import time
import traceback
from dataclasses import dataclass
from typing import Any

from tetherland.analysis import analyze
from tetherland.campaign.faults import fault_time, phase_at, sample_fault
from tetherland.campaign.perturb import Perturbation, apply_perturbation, sample_perturbation
from tetherland.campaign.spec import RunSpec, Sweep
from tetherland.campaign.store import INFRASTRUCTURE
from tetherland.config import Scenario, apply_overrides, scenario_from_dict
from tetherland.errors import TetherlandError
from tetherland.methods import Planners
from tetherland.randomness import RandomSource
from tetherland.runs import run_mission
from tetherland.sim.disturbances import WindGusts


@dataclass(frozen=True)
class Job:
    """Everything a worker needs: the resolved base scenario and the run to do."""

    scenario: dict[str, Any]
    run: RunSpec
    kind: str = "mission"
    controller: str = "hierarchical"
    firmware: str | None = None


def run_scenario(job: Job) -> Scenario:
    """The base scenario with the run's sweep value applied."""
    data = job.scenario
    if job.run.sweep_key is not None:
        assert job.run.sweep_value is not None
        data = apply_overrides(data, [Sweep.override(job.run.sweep_key, job.run.sweep_value)])
    return scenario_from_dict(data, str(data.get("name", "custom")))


def _analysis_verdict(plant: Scenario, belief: Scenario, method: str) -> dict[str, Any]:
    """Static feasibility of the method on the true scenario (fast campaign mode)."""
    result = analyze(plant)
    part = result.tethered if method == "tethered" else result.free_flight
    return {"success": bool(part.feasible), "max_slope_rad": part.max_slope_rad}


_LANDING_KEYS = (
    "position_error_m", "attitude_error_rad", "touchdown_speed_mps",
    "touchdown_angular_rate_rps", "touchdown_accel_mps2", "slip_m", "settle_m", "min_tension_N",
)  # fmt: skip
_local = threading.local()


def worker_planners() -> Planners:
    """This worker thread's compiled planners, built once and reused by every run."""
    planners = getattr(_local, "planners", None)
    if planners is None:
        planners = _local.planners = Planners()
    return planners


def campaign_fields(summary: dict[str, Any]) -> dict[str, Any]:
    """The verdict fields a campaign keeps of a run's ``summary.json`` (any method)."""
    landing = summary.get("landing", {})
    return {
        "success": summary["success"],
        "outcome": summary["outcome"],
        "reason": summary["reason"],
        "aborted": summary["aborted"],
        "abort_reason": summary["abort_reason"],
        "safe_stop": summary.get("safe_stop"),
        "phases": [
            {"name": p["name"], "start": p["start"], "end": p["end"]}
            for p in summary.get("phases", [])
        ],
        "crashed": summary["crashed"],
        "landing": {k: landing.get(k) for k in _LANDING_KEYS}
        | {"conditions": landing.get("conditions")},
        "takeoff_completed": summary["takeoff"].get("completed", False),
        "return_completed": summary["return"].get("completed", False),
        "sim_time_s": summary["sim_time_s"],
        "real_time_factor": summary["real_time_factor"],
    }


def run_for_campaign(
    plant: Scenario,
    belief: Scenario,
    perturbation: Perturbation,
    method: str,
    seed: int,
    controller: str = "hierarchical",
    firmware: str | None = None,
) -> dict[str, Any]:
    """Fly one perturbed run of ``method`` (wind gusts on the plant) and keep its verdict.

    ``controller`` names the tethered law; the contact-free method flies its own tracker.
    ``firmware`` names flight firmware as the inner loop (None: tetherland's own).
    """
    if method != "tethered":
        controller = None
    inner_loop = None
    if firmware is not None:
        from tetherland.firmware import BetaflightSitl

        inner_loop = BetaflightSitl()
    period = 1.0 / plant.controller.rate_hz
    wind: list[WindGusts] = []
    result = run_mission(
        plant, belief, method=method, controller=controller, seed=seed,
        planners=worker_planners(), observers=wind, inner_loop=inner_loop,
        plant_setup=lambda p: wind.append(WindGusts(p, perturbation.gusts, period)),
    )  # fmt: skip
    return campaign_fields(result.summary)


def execute(job: Job, random: RandomSource | None = None) -> dict[str, Any]:
    """Run one job and return its record for the results table.

    Every draw comes from ``random`` (default: the run seed's
    :class:`~tetherland.randomness.RandomSource`): the perturbation, the wind, the fault,
    and the sensor noise (``run_mission`` with the run's seed). Bad inputs and failures
    inside the run are recorded (``status = "error"``), not raised, so one broken run
    cannot stop a campaign.
    """
    start = time.perf_counter()
    run = job.run
    record: dict[str, Any] = {
        "run_id": run.run_id,
        "method": run.method,
        "index": run.index,
        "seed": run.seed,
        "sweep_key": run.sweep_key,
        "sweep_value": run.sweep_value,
    }
    try:
        truth = run_scenario(job)
        random = RandomSource(run.seed) if random is None else random
        perturbation = sample_perturbation(truth, random)
        record["perturbation"] = perturbation.to_dict()
        plant, belief = apply_perturbation(truth, perturbation)
        faults = None
        if run.fault is not None:  # its own stream: the perturbation stays that of the seed
            assert run.fault_slice is not None
            faults = sample_fault(run.fault, run.fault_slice, belief, random.stream("faults"))
            plant = plant.model_copy(update={"faults": faults})
            record["fault"] = {"kind": run.fault, "t": fault_time(faults),
                               **faults.model_dump(mode="json")}  # fmt: skip
        if job.kind == "analysis":
            verdict = _analysis_verdict(plant, belief, run.method)
        else:
            verdict = run_for_campaign(
                plant, belief, perturbation, run.method, run.seed, job.controller, job.firmware
            )
            if faults is not None:
                record["fault"]["phase"] = phase_at(verdict["phases"], fault_time(faults))
        record.update(status="ok", error=None, verdict=verdict)
    except TetherlandError as err:  # the run's own error: the same on every attempt
        record.update(status="error", error_kind="run", error=str(err), verdict={"success": False})
    except Exception as err:
        last = traceback.format_exception_only(err)[-1].strip()
        record.update(status="error", error_kind="run", error=f"internal error: {last}",
                      verdict={"success": False})  # fmt: skip
    record["wall_time_s"] = time.perf_counter() - start
    return record


def lost_record(job: Job, error: BaseException) -> dict[str, Any]:
    """The record of a run whose worker was lost for good (the engine gave up on it):
    an infrastructure error, which ``--resume`` runs again."""
    run = job.run
    return {
        "run_id": run.run_id, "method": run.method, "index": run.index, "seed": run.seed,
        "sweep_key": run.sweep_key, "sweep_value": run.sweep_value, "status": "error",
        "error_kind": INFRASTRUCTURE, "error": f"worker lost: {type(error).__name__}: {error}",
        "verdict": {"success": False}, "wall_time_s": 0.0,
    }  # fmt: skip
