"""What to change when no design exists: a vehicle value that makes the search find one.

When :func:`~tetherland.design.search.search_designs` finds no design, :func:`find_fixes`
searches, one field at a time, the value of a vehicle field that does give a design:

* ``vehicle.f_max`` raised (stronger rotors: hover, landed hover, rotor margins),
* ``vehicle.mass`` lowered (a lighter vehicle: the same),
* ``vehicle.f_min`` lowered (rotors that throttle further down: the lower rotor limit),

and, only when none of them gives a design, ``surface.slope_deg`` lowered (the steepest
slope this vehicle can land on).

Each field is scanned in geometric steps from its value to the end of its range until a
search finds a design, then bisected between the last value that failed and the first
that worked, and the value reported is rounded towards the working side and confirmed
by one more search: every fix it reports has been searched and gives a design. The
cable length, attachment, anchor height and hooking approach are what the search itself
varies, so they are not fixes.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

from tetherland.config import Scenario, with_overrides
from tetherland.design.space import DesignSpace
from tetherland.errors import ConfigError

STEPS = 8
"""Geometric steps of the scan to the end of a field's range."""
BISECTIONS = 6
"""Bisections between the last value that failed and the first that worked."""


@dataclass(frozen=True)
class Fix:
    """A value of one field with which a design exists.

    Attributes
    ----------
    field : str
        The scenario field, e.g. ``vehicle.f_max``.
    value : float
        The value that gives a design [the field's unit].
    unit : str
    """

    field: str
    value: float
    unit: str

    @property
    def override(self) -> str:
        """The ``--set`` override of the fix."""
        return f"{self.field}={self.value:g}"

    def describe(self) -> str:
        return f"{self.field} = {self.value:g} {self.unit} (--set {self.override})"

    def to_dict(self) -> dict[str, object]:
        return {"field": self.field, "value": self.value, "unit": self.unit,
                "override": self.override}  # fmt: skip


@dataclass(frozen=True)
class _Field:
    field: str
    unit: str
    up: bool
    """True: the fix raises the value (towards ``end``)."""
    end: float
    """The far end of the scan (the field's range)."""
    step: float
    """Rounding step of the reported value [unit]."""

    def value(self, scenario: Scenario) -> float:
        section, key = self.field.split(".")
        return float(getattr(getattr(scenario, section), key))

    def tidy(self, x: float) -> float:
        """``x`` rounded to ``step`` towards the side that works."""
        k = math.ceil(x / self.step - 1e-9) if self.up else math.floor(x / self.step + 1e-9)
        return round(k * self.step, 6)


FIELDS = (
    _Field("vehicle.f_max", "N", True, 200.0, 0.05),
    _Field("vehicle.mass", "kg", False, 0.01, 0.005),
    _Field("vehicle.f_min", "N", False, 0.0, 0.01),
)
"""The vehicle fields a fix may change (their ends are the ends of their ranges)."""
SLOPE = _Field("surface.slope_deg", "deg", False, 0.0, 0.5)
"""The last resort: a shallower slope."""


def find_fixes(scenario: Scenario, works: Callable[[Scenario], bool]) -> tuple[Fix, ...]:
    """The fixes for ``scenario`` (the base of a design search that found nothing).

    Parameters
    ----------
    scenario : Scenario
        The scenario searched (at the slope searched).
    works : callable
        Does a design exist for this scenario? (a design search, e.g.
        ``lambda sc: search_designs(sc).feasible``).
    """
    out = [fix for field in FIELDS if (fix := _search(scenario, field, works)) is not None]
    if not out and (fix := _search(scenario, SLOPE, works)) is not None:
        out.append(fix)
    return tuple(out)


def _with(scenario: Scenario, field: _Field, x: float) -> Scenario | None:
    try:
        return with_overrides(scenario, [f"{field.field}={x!r}"])
    except ConfigError:
        return None


def _search(scenario: Scenario, field: _Field, works: Callable[[Scenario], bool]) -> Fix | None:
    x0 = field.value(scenario)

    def ok(x: float) -> bool:
        sc = _with(scenario, field, x)
        return sc is not None and works(sc)

    # scan: geometric from x0 towards the end of the range (linear when x0 is 0)
    bad, good = x0, None
    for k in range(1, STEPS + 1):
        if x0 > 0 and field.end > 0:
            x = x0 * (field.end / x0) ** (k / STEPS)
        else:
            x = x0 + (field.end - x0) * k / STEPS
        if ok(x):
            good = x
            break
        bad = x
    if good is None:
        return None
    for _ in range(BISECTIONS):
        mid = 0.5 * (bad + good)
        if ok(mid):
            good = mid
        else:
            bad = mid
    tidy = field.tidy(good)
    if tidy != good and not ok(tidy):
        tidy = good  # the rounded value fails: report the searched one
    return Fix(field.field, tidy, field.unit)


def fixes_message(fixes: tuple[Fix, ...]) -> str:
    """The hint appended to a "no design" reason."""
    if fixes:
        return "a design exists with " + " or ".join(f.describe() for f in fixes)
    return (
        "no vehicle.f_max up to 200 N, vehicle.mass down to 0.01 kg, vehicle.f_min down to "
        "0 N or surface.slope_deg down to 0 deg gives a design"
    )


def fast_space(space: DesignSpace) -> DesignSpace:
    """``space`` asked for one design (enough to know that one exists)."""
    return replace(space, max_designs=1)
