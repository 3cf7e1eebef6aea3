"""What a campaign runs: methods x sweep values x seeded runs (issue 7)."""

from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from tetherland.campaign.faults import DEFAULT_WINDOW, FAULT_KINDS, time_slice
from tetherland.errors import ConfigError
from tetherland.methods import method_names
from tetherland.randomness import derive_seed

METHODS = method_names()
JOBS = ("mission", "analysis")


@dataclass(frozen=True)
class Sweep:
    """One scenario key swept over values, e.g. ``surface.slope_deg=30:80:10``."""

    key: str
    values: tuple[float, ...]

    @classmethod
    def parse(cls, text: str) -> Sweep:
        """Parse ``key=start:stop:step`` (inclusive) or ``key=v1,v2,...``."""
        key, sep, raw = text.partition("=")
        key = key.strip()
        if not sep or not key or "." not in key:
            raise ConfigError(f"--sweep '{text}': expected section.key=start:stop:step or a,b,c")
        try:
            if ":" in raw:
                start, stop, step = (float(x) for x in raw.split(":"))
                if step <= 0 or stop < start:
                    raise ValueError
                n = int(np.floor((stop - start) / step + 1e-9)) + 1
                values = tuple(round(start + i * step, 10) for i in range(n))
            else:
                values = tuple(float(x) for x in raw.split(","))
        except ValueError:
            raise ConfigError(
                f"--sweep '{text}': values must be start:stop:step with step > 0 and stop >= start,"
                " or a comma-separated list of numbers"
            ) from None
        if not values:
            raise ConfigError(f"--sweep '{text}': no values")
        return cls(key, values)

    @staticmethod
    def override(key: str, value: float) -> str:
        """``key=value`` as an override; a whole number is written as an integer, so that
        an integer field (``mission.hooking.max_attempts``) takes it under strict types."""
        number = str(int(value)) if float(value).is_integer() else repr(float(value))
        return f"{key}={number}"


@dataclass(frozen=True)
class RunSpec:
    """One mission to run: deterministic from its fields alone.

    ``seed`` is shared by both methods at the same sweep value and index, so methods are
    compared on the same perturbations (common random numbers).
    """

    run_id: str
    method: str
    index: int
    seed: int
    sweep_key: str | None
    sweep_value: float | None
    fault: str | None = None
    """Fault campaigns: the fault kind (:mod:`tetherland.campaign.faults`)."""
    fault_slice: tuple[float, float] | None = None
    """... and the slice of the fault-time window its time is drawn from [s]."""


@dataclass(frozen=True)
class CampaignSpec:
    """A campaign: base scenario (resolved), methods, runs per point, sweep and base seed."""

    scenario: dict[str, Any]
    runs: int
    methods: tuple[str, ...] = METHODS
    sweep: Sweep | None = None
    seed: int = 0
    job: str = "mission"
    controller: str = "hierarchical"
    extra: dict[str, Any] = field(default_factory=dict)
    faults: tuple[str, ...] = ()
    """Fault kinds: ``runs`` tethered runs each instead of the methods (issue 15)."""
    fault_window: tuple[float, float] = DEFAULT_WINDOW
    """Window of the fault times [s]."""
    firmware: str | None = None
    """Flight firmware flying every run as the inner loop (``tetherland.firmware``)."""

    def __post_init__(self) -> None:
        if self.runs < 1:
            raise ConfigError(f"--runs must be >= 1 (got {self.runs})")
        bad = [m for m in self.methods if m not in METHODS]
        if bad or not self.methods:
            raise ConfigError(
                f"--methods: unknown method {bad or '[]'} (allowed: {', '.join(METHODS)})"
            )
        if self.job not in JOBS:
            raise ConfigError(f"job must be one of {JOBS}, got {self.job!r}")
        bad_faults = [k for k in self.faults if k not in FAULT_KINDS]
        if bad_faults:
            raise ConfigError(
                f"--faults: unknown fault kind {bad_faults} (allowed: {', '.join(FAULT_KINDS)})"
            )
        if self.firmware is not None:
            from tetherland.firmware import FIRMWARES  # no firmware package needed to check

            if self.firmware not in FIRMWARES:
                raise ConfigError(f"--firmware must be one of {', '.join(FIRMWARES)} "
                                  f"(got {self.firmware!r})")  # fmt: skip
            if self.job != "mission":
                raise ConfigError("--firmware flies missions (--job mission)")
        if self.faults and (self.sweep is not None or self.job != "mission"):
            raise ConfigError("--faults runs missions without --sweep (and --job mission)")

    def fingerprint(self) -> str:
        """Stable hash of everything that decides the results (for --resume checks)."""
        doc = json.dumps(self.to_dict(), sort_keys=True, default=str)
        return hashlib.sha256(doc.encode()).hexdigest()[:16]

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["methods"] = list(self.methods)
        if self.firmware is None:  # campaigns on tetherland's own inner loop keep theirs
            del d["firmware"]
        if not self.faults:  # campaigns without faults keep their fingerprint
            del d["faults"], d["fault_window"]
        else:
            d["faults"], d["fault_window"] = list(self.faults), list(self.fault_window)
        return d

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> CampaignSpec:
        """Inverse of :meth:`to_dict` (a manifest's ``spec``); the fingerprint is kept.

        Raises
        ------
        ConfigError
            One line when ``data`` is no campaign specification.
        """
        try:
            sweep, window = data.get("sweep"), data.get("fault_window", DEFAULT_WINDOW)
            return cls(
                scenario=dict(data["scenario"]),
                runs=int(data["runs"]),
                methods=tuple(data["methods"]),
                sweep=None if sweep is None else Sweep(str(sweep["key"]),
                                                       tuple(float(v) for v in sweep["values"])),
                seed=int(data["seed"]),
                job=str(data["job"]),
                controller=str(data["controller"]),
                extra=dict(data.get("extra", {})),
                faults=tuple(data.get("faults", ())),
                fault_window=(float(window[0]), float(window[1])),
                firmware=data.get("firmware"),
            )  # fmt: skip
        except (KeyError, TypeError, ValueError, AttributeError) as err:
            why = f"{type(err).__name__}: {err}"
            raise ConfigError(f"not a campaign specification ({why})") from None

    def run(self, run_id: str) -> RunSpec:
        """The run ``run_id`` of this campaign (ConfigError naming the ids when unknown)."""
        runs = {r.run_id: r for r in self.expand()}
        if run_id not in runs:
            ids = list(runs)
            shown = ", ".join(ids[:3]) + (f", ... ({len(ids)} runs)" if len(ids) > 3 else "")
            raise ConfigError(f"RUN_ID {run_id!r} is no run of this campaign (its runs: {shown})")
        return runs[run_id]

    def expand(self) -> list[RunSpec]:
        """Every run of the campaign, in a deterministic order."""
        if self.faults:
            return [
                RunSpec(
                    f"{kind}-{i:05d}", "tethered", i,
                    derive_seed(self.seed, 15, j, i),
                    None, None, kind, time_slice(self.fault_window, i, self.runs),
                )
                for i in range(self.runs)  # interleaved: a partial campaign has every kind
                for j, kind in enumerate(self.faults)
            ]
        sweep_values: tuple[float | None, ...] = self.sweep.values if self.sweep else (None,)
        key = self.sweep.key if self.sweep else None
        specs = []
        for j, value in enumerate(sweep_values):
            for i in range(self.runs):
                seed = derive_seed(self.seed, j, i)
                for method in self.methods:
                    tag = f"{method}-{'base' if value is None else f'{value:g}'}-{i:05d}"
                    specs.append(RunSpec(tag, method, i, seed, key, value))
        return specs
