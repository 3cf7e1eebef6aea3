"""Verify designs by flying perturbed missions, and rank them by what they achieved.

:func:`verify_designs` flies ``runs`` perturbed tethered missions of each of the best
designs, each run exactly a campaign run (:func:`tetherland.campaign.jobs.execute`: the
seed draws the perturbation, wind and sensor noise) of the seeds a campaign
``tetherland campaign SCENARIO --methods tethered --runs N --seed SEED`` with the design's
overrides would fly, on any campaign executor. Designs are then ranked by the lower bound
of the 95 % Wilson interval of their success rate (the campaign statistics' interval,
:func:`tetherland.campaign.stats.wilson_interval`), then by their robust margins
(:func:`rank_verified`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from tetherland.campaign.executors import Executor
from tetherland.campaign.jobs import Job, execute, lost_record
from tetherland.campaign.spec import CampaignSpec
from tetherland.campaign.stats import succeeded
from tetherland.config import Scenario
from tetherland.design.search import Design, rank_key
from tetherland.design.space import DesignSpace
from tetherland.design.verification import Verification
from tetherland.errors import ConfigError

METHOD = "tethered"
"""The method a design is for (it fixes the cable, attachment, anchor and hooking)."""


def verification_jobs(scenario: Scenario, runs: int, seed: int, tag: str = "") -> list[Job]:
    """The campaign jobs of ``runs`` perturbed tethered missions of ``scenario`` at base
    ``seed`` (the run ids prefixed by ``tag``)."""
    spec = CampaignSpec(scenario=scenario.model_dump(mode="json"), runs=runs,
                        methods=(METHOD,), seed=seed)  # fmt: skip
    return [Job(spec.scenario, replace(r, run_id=tag + r.run_id)) for r in spec.expand()]


def rank_verified(
    designs: Sequence[Design], scenario: Scenario, space: DesignSpace
) -> tuple[Design, ...]:
    """Designs best first: verified ones by the lower bound of their success rate's 95 %
    interval, then by :func:`~tetherland.design.search.rank_key` (robust margins); the
    designs not verified after them, in their margins' order."""

    def key(d: Design) -> tuple[float, ...]:
        verified = d.verified
        low = -1.0 if verified is None else verified.ci_low
        return (-low, *rank_key(d, scenario, space))

    return tuple(sorted(designs, key=key))


def verify_designs(
    scenario: Scenario,
    designs: Sequence[Design],
    runs: int,
    seed: int,
    executor: Executor,
    candidates: int = 3,
    space: DesignSpace | None = None,
) -> tuple[Design, ...]:
    """Fly ``runs`` perturbed missions of each of the first ``candidates`` designs and
    rank all designs by :func:`rank_verified`.

    Parameters
    ----------
    scenario : Scenario
        The scenario searched (each design's overrides are applied to it).
    designs : sequence of Design
        The search's designs, best first.
    runs : int
        Missions per design, >= 1.
    seed : int
        Base seed: every design flies the same perturbations (common random numbers).
    executor : Executor
        Where the runs execute (:func:`tetherland.campaign.executors.make_executor`).
    candidates : int
        How many of the first designs are flown, >= 1.
    space : DesignSpace, optional
        For the margins' ranking (its ``target_clearance``).

    Raises
    ------
    ConfigError
        ``runs`` or ``candidates`` below 1.
    """
    if runs < 1:
        raise ConfigError(f"--verify must be >= 1 missions per design (got {runs})")
    if candidates < 1:
        raise ConfigError(f"--candidates must be >= 1 (got {candidates})")
    flown = list(designs[:candidates])
    jobs = [
        job
        for k, d in enumerate(flown)
        for job in verification_jobs(d.point.apply(scenario), runs, seed, f"d{k}-")
    ]
    successes = [0] * len(flown)
    for record in executor.map_unordered(execute, jobs, lost=lost_record):
        k = int(record["run_id"].split("-", 1)[0][1:])
        successes[k] += int(succeeded(record))
    verified = [replace(d, verified=Verification.of(n, runs, seed))
                for d, n in zip(flown, successes, strict=True)]  # fmt: skip
    return rank_verified([*verified, *designs[candidates:]], scenario, space or DesignSpace())
