"""The analytic taut-tether model in closed loop (no MuJoCo, no sensors, no motor lag).

For controller tests and tuning: :func:`simulate_tethered` integrates
:func:`tetherland.models.tethered.tethered_body_rhs` with RK4 at ``dt`` and runs any
:class:`~tetherland.interfaces.Controller` at ``control_dt`` on the true state, applying
the wrench the controller's allocation achieved (``Command.thrust``, ``Command.torque_B``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tetherland.config import Scenario
from tetherland.geometry import FloatArray, LandingGeometry, link_direction, link_jacobian
from tetherland.interfaces import Command, Controller, Reference, StateEstimate
from tetherland.models.tethered import tethered_body_rhs
from tetherland.state import LinkState, RigidBodyState


@dataclass(frozen=True)
class AnalyticRun:
    """Samples of a closed-loop analytic run at the control ticks.

    Attributes
    ----------
    t : (n,) array [s]
    x : (n, 11) array
        [phi, delta, phi', delta', q_WB, omega_B].
    commands : list of Command
    """

    t: FloatArray
    x: FloatArray
    commands: list[Command]


def estimate_of(x: FloatArray, t: float, geo: LandingGeometry, length: float) -> StateEstimate:
    """The true :class:`StateEstimate` of a tethered-body state vector."""
    phi, delta, dphi, ddelta = x[0:4]
    p = geo.p_A + length * geo.R_WA @ link_direction(phi, delta)
    v = geo.R_WA @ (link_jacobian(phi, delta, length) @ np.array([dphi, ddelta]))
    return StateEstimate(
        t=t,
        body=RigidBodyState(p, v, x[4:8] / np.linalg.norm(x[4:8]), x[8:11].copy()),
        link=LinkState(phi, delta, dphi, ddelta),
    )


def simulate_tethered(
    scenario: Scenario,
    controller: Controller,
    reference: Callable[[float], Reference],
    x0: FloatArray,
    duration: float,
    *,
    dt: float = 1e-3,
    control_dt: float = 2e-3,
    tension_of: Callable[[FloatArray, Command], float] | None = None,
) -> AnalyticRun:
    """Run ``controller`` on the analytic model from ``x0`` for ``duration`` seconds."""
    v = scenario.vehicle
    geo = LandingGeometry.from_scenario(scenario)
    length = geo.link_length  # the rigid link of the stretched cable, l + s (theory 4.2)
    J = np.asarray(v.inertia, dtype=float)
    every = round(control_dt / dt)
    n = round(duration / dt)
    x = np.asarray(x0, dtype=float).copy()
    ts, xs, cmds = [], [], []
    cmd: Command | None = None

    def rhs(y: FloatArray, c: Command) -> FloatArray:
        return tethered_body_rhs(y, c.thrust, c.torque_B, v.mass, length, J, geo.R_WA)

    for k in range(n):
        t = k * dt
        if k % every == 0:
            est = estimate_of(x, t, geo, length)
            cmd = controller.update(t, est, reference(t))
            ts.append(t)
            xs.append(x.copy())
            cmds.append(cmd)
        assert cmd is not None
        k1 = rhs(x, cmd)
        k2 = rhs(x + 0.5 * dt * k1, cmd)
        k3 = rhs(x + 0.5 * dt * k2, cmd)
        k4 = rhs(x + dt * k3, cmd)
        x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        x[4:8] /= np.linalg.norm(x[4:8])
    return AnalyticRun(np.array(ts), np.array(xs), cmds)
