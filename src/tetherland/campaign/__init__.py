"""Randomised robustness campaigns: perturbations, executors, durable results, statistics."""

from tetherland.campaign.executors import ENGINES, make_executor
from tetherland.campaign.jobs import Job, execute
from tetherland.campaign.perturb import Gust, Perturbation, apply_perturbation, sample_perturbation
from tetherland.campaign.run import CampaignResult, open_store, run_campaign
from tetherland.campaign.spec import METHODS, CampaignSpec, RunSpec, Sweep
from tetherland.campaign.stats import RateSummary, summarize, wilson_interval
from tetherland.campaign.store import ResultsStore

__all__ = [
    "ENGINES",
    "METHODS",
    "CampaignResult",
    "CampaignSpec",
    "Gust",
    "Job",
    "Perturbation",
    "RateSummary",
    "ResultsStore",
    "RunSpec",
    "Sweep",
    "apply_perturbation",
    "execute",
    "make_executor",
    "open_store",
    "run_campaign",
    "sample_perturbation",
    "summarize",
    "wilson_interval",
]
