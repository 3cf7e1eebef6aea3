"""The landing-method role: plan from the belief, fly a reference, say what to judge.

A landing method (the tethered mission of chapter 6.6, the contact-free perching
baseline of section 6.4.1) is one implementation of :class:`LandingMethod`:

1. :meth:`~LandingMethod.plan` plans on the *believed* scenario (what the robot knows),
   from the vehicle's start state, with reusable compiled planners;
2. :meth:`~LandingMethod.fly` builds the roles of the closed loop from that plan: a
   :class:`~tetherland.interfaces.ReferenceSource` (supervisor), a
   :class:`~tetherland.interfaces.Controller`, the initial state, the run length;
3. :meth:`~LandingMethod.record` reports, after the run, what the judge needs besides the
   log (phases, key times, targets), and :attr:`~LandingMethod.expects` what the judge
   must require of this method.

Every method is judged by the one :func:`tetherland.verdict.judge`. Methods are registered
in :mod:`tetherland.methods` (:func:`get_method`), which the CLI, the closed loop and the
campaign all use. Nothing here imports the simulator.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

from tetherland.config import Scenario
from tetherland.geometry import FloatArray
from tetherland.interfaces import Controller, ReferenceSource
from tetherland.planning import Planner
from tetherland.planning.perching import PerchingPlanner
from tetherland.state import RigidBodyState
from tetherland.verdict.record import Expectations, RunRecord


@dataclass
class Planners:
    """Compiled planners kept between runs (one per worker: building them costs seconds).

    Attributes
    ----------
    tethered : Planner
        Landing/takeoff OCP (6.21).
    perching : PerchingPlanner
        Contact-free perching OCP.
    """

    tethered: Planner = field(default_factory=Planner)
    perching: PerchingPlanner = field(default_factory=PerchingPlanner)


@dataclass(frozen=True)
class Flight:
    """What a method hands the closed loop for one run (everything from the belief).

    Attributes
    ----------
    reference : ReferenceSource
        The method's supervisor: mode and reference every control tick.
    controller : Controller
        Maps estimate and reference to rotor speeds.
    initial_state : RigidBodyState
        Where the vehicle starts (t = 0).
    rotor_speeds : (4,) array or None
        Initial rotor speeds [rad/s] (None: at rest).
    duration : float
        Longest simulated time; the reference usually terminates earlier [s].
    diagnostic_keys : tuple of str
        Controller diagnostics logged as ``diag.<key>`` columns.
    """

    reference: ReferenceSource
    controller: Controller
    initial_state: RigidBodyState
    rotor_speeds: FloatArray | None
    duration: float
    diagnostic_keys: tuple[str, ...] = ()


ControllerChoice = str | Controller | None
"""A controller by name (tethered: ``"hierarchical"``, ``"dfl"``), your own
:class:`~tetherland.interfaces.Controller`, or None for the scenario's default."""


@runtime_checkable
class LandingMethod(Protocol):
    """A way to land on (and leave) a surface; see the module docstring."""

    name: str
    """Registered name (``"tethered"``, ``"free-flight"``)."""
    expects: Expectations
    """What the judge requires of this method's runs."""

    def plan(self, belief: Scenario, start: RigidBodyState, planners: Planners) -> Any:
        """Plan on the believed scenario from ``start``.

        Raises :class:`~tetherland.errors.InfeasibleError` (one line) when there is no
        plan; the closed loop then records a run that was not flown.
        """
        ...

    def fly(self, plan: Any, belief: Scenario, controller: ControllerChoice) -> Flight:
        """The roles of one closed-loop run of ``plan``; ``controller`` replaces the
        method's own controller for its main maneuver (see :data:`ControllerChoice`)."""
        ...

    def record(self, plan: Any, flight: Flight, t_end: float, base: RunRecord) -> RunRecord:
        """``base`` (method, seed, scenarios, expectations, timing) completed with what
        the run's reference source and controller reported, the run ending at ``t_end``."""
        ...

    def trajectories(self, plan: Any) -> Mapping[str, Any]:
        """The planned trajectories by file stem (each has ``save_csv(path)``)."""
        ...
