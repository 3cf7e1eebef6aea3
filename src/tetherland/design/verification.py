"""What perturbed missions flown with a design achieved (``tetherland design --verify``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from tetherland.campaign.stats import wilson_interval


@dataclass(frozen=True)
class Verification:
    """Perturbed missions flown with one design.

    Attributes
    ----------
    runs, successes : int
        Missions flown and missions that succeeded (a run that raised counts as failed).
    ci_low, ci_high : float
        95 % Wilson interval of the success rate [-].
    seed : int
        Base seed of the runs (a campaign's ``--seed``).
    """

    runs: int
    successes: int
    ci_low: float
    ci_high: float
    seed: int

    @classmethod
    def of(cls, successes: int, runs: int, seed: int) -> Verification:
        lo, hi = wilson_interval(successes, runs)
        return cls(runs, successes, lo, hi, seed)

    def to_dict(self) -> dict[str, Any]:
        """The ``verified`` entry of ``tetherland design --json``."""
        return {"runs": self.runs, "successes": self.successes, "ci_low": self.ci_low,
                "ci_high": self.ci_high, "seed": self.seed}  # fmt: skip
