"""One campaign run, as a pure function of its job (picklable, engine-independent).

:func:`draw_run` draws everything a run's seed decides (the perturbation, the wind and the
injected fault), :func:`fly_perturbed` flies it; :func:`run_job` does both for a campaign
job, :func:`execute` also keeps the run's directory, and ``tetherland replay`` and
``tetherland mission --perturb`` call the same functions, so they fly a campaign run
exactly as the campaign did.
"""

from __future__ import annotations

import threading
import time
import traceback
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

from tetherland.analysis import analyze
from tetherland.campaign.faults import fault_time, phase_at, sample_fault
from tetherland.campaign.perturb import Perturbation, apply_perturbation, sample_perturbation
from tetherland.campaign.spec import RunSpec, Sweep
from tetherland.campaign.store import INFRASTRUCTURE, KEEP_POLICIES, RUNS_DIR
from tetherland.config import FaultsConfig, Scenario, apply_overrides, scenario_from_dict
from tetherland.errors import ConfigError, TetherlandError
from tetherland.io import OutputDir
from tetherland.methods import Flight, Planners
from tetherland.randomness import RandomSource
from tetherland.runs import RunResult, run_mission, save_run
from tetherland.runs.closed_loop import InnerLoopFactory
from tetherland.runs.explain import explain
from tetherland.sim import Plant
from tetherland.sim.disturbances import WindGusts


@dataclass(frozen=True)
class Job:
    """Everything a worker needs: the resolved base scenario and the run to do.

    ``keep`` (:data:`~tetherland.campaign.store.KEEP_POLICIES`) says which runs keep their
    run directory in ``keep_dir`` (the campaign directory's ``runs/``; None: none).
    """

    scenario: dict[str, Any]
    run: RunSpec
    kind: str = "mission"
    controller: str = "hierarchical"
    firmware: str | None = None
    keep: str = "none"
    keep_dir: str | None = None


def run_scenario(job: Job) -> Scenario:
    """The base scenario with the run's sweep value applied."""
    data = job.scenario
    if job.run.sweep_key is not None:
        assert job.run.sweep_value is not None
        data = apply_overrides(data, [Sweep.override(job.run.sweep_key, job.run.sweep_value)])
    return scenario_from_dict(data, str(data.get("name", "custom")))


@dataclass(frozen=True)
class PerturbedRun:
    """What one perturbed run flies, drawn from its seed.

    Attributes
    ----------
    seed : int
        The run's seed: its perturbation, wind, fault and sensor noise.
    truth : Scenario
        The scenario as given (the judge's truth).
    plant, belief : Scenario
        What the plant simulates (the truth with the plant-side disturbances and the
        injected fault) and what the robot believes (:func:`apply_perturbation`).
    perturbation : Perturbation
    faults : FaultsConfig or None
        The injected fault of a fault-campaign run (None: the scenario's own ``[faults]``).
    """

    seed: int
    truth: Scenario
    plant: Scenario
    belief: Scenario
    perturbation: Perturbation
    faults: FaultsConfig | None = None

    def to_dict(self) -> dict[str, Any]:
        """What ``run.json`` records of the draw (provenance ``perturbation``), the gusts
        listed in full."""
        return {
            "seed": self.seed,
            **self.perturbation.to_dict(),
            "gusts": [{"t_start": g.t_start, "duration": g.duration, "force_W": list(g.force_W)}
                      for g in self.perturbation.gusts],
        }  # fmt: skip


def draw_run(
    truth: Scenario,
    seed: int,
    fault: str | None = None,
    fault_slice: tuple[float, float] | None = None,
    random: RandomSource | None = None,
) -> PerturbedRun:
    """Draw a campaign run's perturbation (and fault) from its seed's named streams.

    The wind gusts span the whole run, up to ``mission.time_limit``.

    Parameters
    ----------
    truth : Scenario
        The run's scenario (sweep value applied).
    seed : int
        The run's seed (a campaign's :attr:`RunSpec.seed`).
    fault, fault_slice : str and (float, float), optional
        Fault campaigns: the fault kind and the slice of fault times [s]; drawn from the
        ``faults`` stream, so the perturbation stays that of the seed.
    random : RandomSource, optional
        Default ``RandomSource(seed)``.
    """
    random = RandomSource(seed) if random is None else random
    perturbation = sample_perturbation(truth, random)
    plant, belief = apply_perturbation(truth, perturbation)
    faults = None
    if fault is not None:
        assert fault_slice is not None
        faults = sample_fault(fault, fault_slice, belief, random.stream("faults"))
        plant = plant.model_copy(update={"faults": faults})
    return PerturbedRun(seed, truth, plant, belief, perturbation, faults)


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


VOLATILE = ("real_time_factor",)
"""Verdict fields of a campaign record that depend on the machine, not on the run."""


def campaign_fields(result: RunResult) -> dict[str, Any]:
    """The verdict fields a campaign keeps of a run (any method), with every failing check
    explained (``failures``: time, phase, and a crash's part and force or a condition's
    value and limit, :func:`tetherland.runs.explain.explain`)."""
    summary = result.summary
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
        "crash": summary.get("crash"),
        "failures": [f.to_dict() for f in explain(summary, result.log, result.record)],
        "landing": {k: landing.get(k) for k in _LANDING_KEYS}
        | {"conditions": landing.get("conditions")},
        "hooking": _hooking_fields(summary.get("hooking")),
        "takeoff_completed": summary["takeoff"].get("completed", False),
        "return_completed": summary["return"].get("completed", False),
        "sim_time_s": summary["sim_time_s"],
        "real_time_factor": summary["real_time_factor"],
    }


def _hooking_fields(hooking: dict[str, Any] | None) -> dict[str, Any] | None:
    """A campaign record's hooking: the last attempt's outcome, the release, when a hook
    caught for the landing came off (``t_lost``) and every attempt's outcome (the plant's
    truth, :mod:`tetherland.verdict.hooking`)."""
    if hooking is None:
        return None
    return {"outcome": hooking["outcome"], "release": hooking["release"],
            "t_lost": hooking["t_lost"],
            "attempts": [a["outcome"] for a in hooking["attempts"]]}  # fmt: skip


def firmware_loop(firmware: str | None) -> InnerLoopFactory | None:
    """The inner loop named ``firmware`` (None: tetherland's own)."""
    if firmware is None:
        return None
    from tetherland.firmware import BetaflightSitl

    return BetaflightSitl()


def fly_perturbed(
    drawn: PerturbedRun,
    method: str,
    *,
    controller: Any = None,
    inner_loop: InnerLoopFactory | None = None,
    planners: Planners | None = None,
    observers: Sequence[Callable[[float, Plant], None]] = (),
    on_flight: Callable[[Flight], None] | None = None,
    provenance: dict[str, Any] | None = None,
) -> RunResult:
    """Fly one perturbed run of ``method`` (its wind gusts on the plant) and judge it.

    ``controller`` names the tethered law (ignored by the contact-free method, which flies
    its own tracker); ``inner_loop`` is flight firmware under it (None: tetherland's own).
    The draw is recorded in ``run.json``'s provenance (``perturbation``), with
    ``provenance`` added.
    """
    if method != "tethered":
        controller = None
    period = 1.0 / drawn.plant.controller.rate_hz
    flying: list[Callable[[float, Plant], None]] = list(observers)
    result = run_mission(
        drawn.plant, drawn.belief, method=method, controller=controller, seed=drawn.seed,
        planners=planners, observers=flying, inner_loop=inner_loop, on_flight=on_flight,
        plant_setup=lambda p: flying.insert(0, WindGusts(p, drawn.perturbation.gusts, period)),
    )  # fmt: skip
    return _with_provenance(result, {"perturbation": drawn.to_dict(), **(provenance or {})})


def run_for_campaign(
    plant: Scenario,
    belief: Scenario,
    perturbation: Perturbation,
    method: str,
    seed: int,
    controller: str = "hierarchical",
    firmware: str | None = None,
) -> dict[str, Any]:
    """Fly one perturbed run of ``method`` from an already drawn plant and belief (e.g.
    with an older random source) and keep its campaign fields (:func:`campaign_fields`)."""
    drawn = PerturbedRun(seed, plant, plant, belief, perturbation)
    loop = firmware_loop(firmware)
    result = fly_perturbed(drawn, method, controller=controller, inner_loop=loop,
                           planners=worker_planners())  # fmt: skip
    return campaign_fields(result)


def _with_provenance(result: RunResult, extra: dict[str, Any]) -> RunResult:
    """``result`` with ``extra`` in its record's provenance and in the verdict's copy of it
    (the judge copies the record's provenance into ``summary.json``)."""
    record = replace(result.record, provenance={**result.record.provenance, **extra})
    summary = dict(result.verdict.summary)
    if "provenance" in summary:
        summary["provenance"] = dict(record.provenance)
    return replace(result, record=record, verdict=replace(result.verdict, summary=summary))


def run_job(
    job: Job, random: RandomSource | None = None
) -> tuple[dict[str, Any], RunResult | None]:
    """Run one job: its record for the results table, and the flown run (None for the
    analysis job or when the run raised).

    Every draw comes from ``random`` (default: the run seed's
    :class:`~tetherland.randomness.RandomSource`): the perturbation, the wind, the fault,
    and the sensor noise (``run_mission`` with the run's seed). Bad inputs and failures
    inside the run are recorded (``status = "error"``), not raised, so one broken run
    cannot stop a campaign. The record keeps the run's wall time and its process CPU time
    (``wall_time_s``, ``cpu_time_s`` [s]; the worker's start-up is not in them).
    """
    start, cpu = time.perf_counter(), time.process_time()
    run = job.run
    record: dict[str, Any] = {
        "run_id": run.run_id,
        "method": run.method,
        "index": run.index,
        "seed": run.seed,
        "sweep_key": run.sweep_key,
        "sweep_value": run.sweep_value,
    }
    result = None
    try:
        drawn = draw_run(run_scenario(job), run.seed, run.fault, run.fault_slice, random)
        record["perturbation"] = drawn.perturbation.to_dict()
        faults = drawn.faults
        if faults is not None:
            record["fault"] = {"kind": run.fault, "t": fault_time(faults),
                               **faults.model_dump(mode="json")}  # fmt: skip
        if job.kind == "analysis":
            verdict = _analysis_verdict(drawn.plant, drawn.belief, run.method)
        else:
            result = fly_perturbed(
                drawn, run.method, controller=job.controller,
                inner_loop=firmware_loop(job.firmware), planners=worker_planners(),
                provenance={"campaign_run": run.run_id},
            )  # fmt: skip
            verdict = campaign_fields(result)
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
    record["cpu_time_s"] = time.process_time() - cpu
    return record, result


def keeps(keep: str, record: dict[str, Any]) -> bool:
    """Does policy ``keep`` keep this run's directory (``failures``: every run that did
    not succeed)?"""
    if keep not in KEEP_POLICIES:
        raise ConfigError(f"--keep must be one of {', '.join(KEEP_POLICIES)} (got {keep!r})")
    return keep == "all" or (keep == "failures" and not record["verdict"].get("success"))


def keep_run(result: RunResult, directory: str | Path) -> Path:
    """Write the run directory of ``result`` at ``directory`` all at once (staged next to
    it and moved into place; an earlier attempt's directory there is replaced)."""
    target = OutputDir(directory, overwrite=True)
    with target.staging() as stage:
        save_run(result, stage, listed_as=target.path)
    return target.path


def execute(job: Job, random: RandomSource | None = None) -> dict[str, Any]:
    """Run one job (:func:`run_job`) and return its record for the results table.

    A run that ``job.keep`` keeps gets its run directory in ``job.keep_dir``
    (``runs/<run_id>`` of the campaign directory, recorded as ``run_dir``); a directory
    that cannot be written is recorded (``run_dir_error``), the verdict stays.
    """
    record, result = run_job(job, random)
    if result is not None and job.keep_dir is not None and keeps(job.keep, record):
        try:
            keep_run(result, Path(job.keep_dir) / job.run.run_id)
            record["run_dir"] = f"{RUNS_DIR}/{job.run.run_id}"
        except Exception as err:  # no room, a remote worker without the directory, ...
            record["run_dir_error"] = f"{type(err).__name__}: {err}"
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
