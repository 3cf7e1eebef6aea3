"""The verification core shared by the planners' checks of a planned trajectory.

A planner hands out a trajectory only after an independent check of it (the *re-
simulation*: its inputs integrated again from the initial state in fine RK4 steps,
:mod:`.shooting`, and sampled every :data:`CHECK_STEP`). The checks that are the same for
the tethered (:mod:`.verify`) and the contact-free (:mod:`.perching.verify`) maneuver live
here: the sampling grid, final conditions against tolerances, the rotor thrust bounds,
a sampled quantity above its floor (cable tension, surface, clearance) and finite
values. Each verify module keeps only its own criteria and its own result record, a
:class:`CheckResult`.

:class:`CheckScope` says what a result was computed on: the dense re-simulation (what
``plan()`` always does) or only the solver's nodes (the cheap check of an online re-plan,
see :meth:`tetherland.planning.Planner.replan`).
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from tetherland.geometry import FloatArray

CHECK_STEP = 1e-3
"""Sampling step of the re-simulation checks [s] (node times are added)."""


class CheckScope(enum.Enum):
    """What a check looked at."""

    RESIMULATION = "resimulation"
    """The inputs re-integrated from the initial state (RK4 steps <= 2 ms), sampled every
    :data:`CHECK_STEP` and at the nodes."""
    NODES = "nodes"
    """The solver's node states only: final state, thrusts by the Bernstein hull of each
    quadratic thrust arc (which bounds the arc between the nodes exactly), tension and
    surface at the nodes, and the shooting gaps closed by the same RK4 the OCP used."""


@dataclass(frozen=True, kw_only=True)
class CheckResult:
    """Base of the planners' verification records.

    Attributes
    ----------
    problems : tuple of str
        What is out of tolerance (empty when the trajectory is accepted).
    scope : CheckScope
        What the check was computed on.
    """

    problems: tuple[str, ...]
    scope: CheckScope = CheckScope.RESIMULATION

    @property
    def ok(self) -> bool:
        return not self.problems


def check_times(
    duration: float, nodes: ArrayLike | None = None, step: float = CHECK_STEP
) -> FloatArray:
    """Sample times on [0, T] every ``step`` with the node times added [s]."""
    times = np.linspace(0.0, duration, max(2, math.ceil(duration / step) + 1))
    return times if nodes is None else np.union1d(times, np.asarray(nodes, dtype=float))


def tolerance_problem(
    what: str, errors: Mapping[str, float] | float, tol: float, unit: str
) -> str | None:
    """A message when some |error| exceeds ``tol`` (None otherwise).

    ``errors`` is one number or named numbers, e.g. ``{"phi": e1, "theta_A": e2}``.
    """
    values = errors if isinstance(errors, Mapping) else {"": float(errors)}
    if max(abs(v) for v in values.values()) <= tol:
        return None
    text = ", ".join(f"{name} {v:.2e}".strip() for name, v in values.items())
    return f"{what} {text} {unit} (tolerance {tol:g})"


def thrust_problem(
    thrusts: FloatArray, t: FloatArray, f_lo: float, f_hi: float, tol: float
) -> str | None:
    """A message when rotor thrusts (n, 4) at times ``t`` leave [f_lo, f_hi] by more than
    ``tol`` [N] (the planned bounds: f_min/f_max narrowed by the control margin)."""
    lo, hi = float(thrusts.min()), float(thrusts.max())
    if lo >= f_lo - tol and hi <= f_hi + tol:
        return None
    i = int(np.argmax(np.maximum(f_lo - thrusts, thrusts - f_hi).max(axis=1)))
    return (
        f"rotor thrusts {lo:.3f}..{hi:.3f} N leave [{f_lo:g}, {f_hi:g}] N "
        f"(f_min/f_max with the control margin) near t = {t[i]:.3f} s"
    )


def floor_problem(
    what: str, values: FloatArray, floor: FloatArray | float, t: FloatArray, tol: float, unit: str
) -> tuple[float, str | None]:
    """The least margin ``values - floor`` and a message when it is below ``-tol``."""
    margin = np.asarray(values - floor, dtype=float)
    i = int(np.argmin(margin))
    least = float(margin[i])
    if least >= -tol:
        return least, None
    bound = float(np.broadcast_to(floor, margin.shape)[i])
    return least, (
        f"{what} {float(values[i]):.4g} {unit} below its bound {bound:.4g} {unit} "
        f"(by {-least:.2e}) at t = {t[i]:.3f} s"
    )


def finite_problem(*arrays: ArrayLike) -> str | None:
    """A message when some array holds NaN or infinite values."""
    if all(np.all(np.isfinite(a)) for a in arrays):
        return None
    return "trajectory contains NaN or infinite values"


def collect(*problems: str | None) -> tuple[str, ...]:
    """The messages that are not None, in order."""
    return tuple(p for p in problems if p is not None)
