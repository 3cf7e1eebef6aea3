"""Per-tick values the viewers plot, derived from log rows (vectorised over ticks).

The same functions serve the MCAP export (all rows of a finished log at once) and the live
view (one row at a time), so both publish identical numbers. Angles are in radians here;
the channels convert to degrees at the boundary.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np

from tetherland.config import Scenario
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.models.flatness import FlatnessMap
from tetherland.report.figures import robot_angles
from tetherland.rotations import quat_to_rotmat_many
from tetherland.sim.log import SimLog, link_angles_from_log
from tetherland.viz.run import PlanSpan


@dataclass(frozen=True)
class NominalValues:
    """The planned (nominal, superscript n) values at some times; NaN outside the plans.

    Attributes
    ----------
    phi, theta_A, psi, tension : (n,) arrays [rad, rad, rad, N]
    rotor_thrusts : (n, 4) array
        Including the cancellation of the cable-offset torque (6.6.5), as flown [N].
    """

    phi: FloatArray
    theta_A: FloatArray
    psi: FloatArray
    tension: FloatArray
    rotor_thrusts: FloatArray

    @classmethod
    def empty(cls, n: int) -> NominalValues:
        nan = np.full(n, math.nan)
        return cls(nan, nan.copy(), nan.copy(), nan.copy(), np.full((n, 4), math.nan))


class NominalPlan:
    """Nominal values of the flown plans at mission times (the trajectories through flatness).

    Parameters
    ----------
    scenario : Scenario
        The believed vehicle (flatness map with the cable-offset torque).
    spans : sequence of PlanSpan
    """

    def __init__(self, scenario: Scenario, spans: Sequence[PlanSpan] = ()) -> None:
        self.flatness = FlatnessMap.from_scenario(scenario, with_cable_offset=True)
        self.spans = list(spans)

    def evaluate(self, t: FloatArray) -> NominalValues:
        """Nominal values at mission times ``t`` (n,) [s]."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = NominalValues.empty(len(t))
        for span in self.spans:
            mask = (t >= span.t0) & (t <= span.t1)
            if not mask.any():
                continue
            s = span.trajectory.sample(t[mask] - span.t0)
            nominal = self.flatness.evaluate_many(s.outputs(), check=False)
            out.phi[mask] = s.phi[:, 0]
            out.theta_A[mask] = s.theta_A[:, 0]
            out.psi[mask] = s.psi
            out.tension[mask] = s.tension
            out.rotor_thrusts[mask] = nominal["rotor_thrusts"]
        return out


@dataclass(frozen=True)
class TickSeries:
    """What the channels publish, for n control ticks (arrays with a leading tick axis).

    Attributes
    ----------
    t : (n,) array
        Mission time [s].
    p_W, q_WB : (n, 3), (n, 4) arrays
        True pose of the centre of mass (w, x, y, z) [m].
    est_p_W, est_q_WB : (n, 3), (n, 4) arrays
        Estimated pose [m].
    attachment_W : (n, 3) array
        True cable attachment point p_W + R_WB r_att [m].
    hook, phase, mode : (n,) arrays
        Cable engaged (1), mission phase code, control mode.
    angles : dict of str to (n, 4) arrays
        ``phi``, ``delta``, ``theta_A``, ``psi``: columns desired, nominal, actual, estimated
        [rad].
    tension : (n, 3) array
        Actual, estimated and nominal cable tension [N].
    thrusts_actual, thrusts_nominal, thrusts_commanded : (n, 4) arrays
        Rotor thrusts f_1..f_4 [N].
    """

    t: FloatArray
    p_W: FloatArray
    q_WB: FloatArray
    est_p_W: FloatArray
    est_q_WB: FloatArray
    attachment_W: FloatArray
    hook: FloatArray
    phase: FloatArray
    mode: FloatArray
    angles: dict[str, FloatArray]
    tension: FloatArray
    thrusts_actual: FloatArray
    thrusts_nominal: FloatArray
    thrusts_commanded: FloatArray

    def __len__(self) -> int:
        return len(self.t)

    def rows(self, rows: slice) -> TickSeries:
        """The ticks ``rows`` of this series (views)."""
        return TickSeries(**{
            f.name: ({k: v[rows] for k, v in value.items()} if isinstance(value, dict)
                     else value[rows])
            for f in fields(self) for value in [getattr(self, f.name)]
        })  # fmt: skip


ANGLE_NAMES = ("phi", "delta", "theta_A", "psi")
SERIES_KINDS = ("desired", "nominal", "actual", "estimated")


def tick_series(
    log: SimLog,
    scenario: Scenario,
    nominal: NominalValues | None = None,
    geometry: LandingGeometry | None = None,
) -> TickSeries:
    """The published values of every row of ``log`` (a finished log or one live row).

    Parameters
    ----------
    log : SimLog
        Rows with at least the runner's base columns (the derived link angles are taken
        as the log holds them, or recomputed from the pose for a live row without them).
    scenario : Scenario
        Geometry (anchor, cable attachment) and the rotor thrust coefficient.
    nominal : NominalValues, optional
        The nominal values at ``log["t"]`` (default: none, NaN).
    geometry : LandingGeometry, optional
        ``LandingGeometry.from_scenario(scenario)``, when the caller has it already.
    """
    n = len(log)
    geo = geometry if geometry is not None else LandingGeometry.from_scenario(scenario)
    v = scenario.vehicle
    r_att = np.asarray(v.cable_attachment, dtype=float)
    nominal = nominal or NominalValues.empty(n)
    q, p = log["q_WB"], log["p_W"]
    if "link_phi" in log and "link_delta" in log:
        phi, delta = log["link_phi"], log["link_delta"]
    else:
        phi, delta = link_angles_from_log(log, p_A=geo.p_A, R_WA=geo.R_WA, r_att_B=r_att)
    _, theta, psi = robot_angles(q, geo.R_WA, phi, delta)
    est_link = log["est_link"]
    est_q = log["est_q_WB"]
    _, est_theta, est_psi = robot_angles(est_q, geo.R_WA, est_link[:, 0], est_link[:, 1])
    ref = log["ref_output"]
    angles = {
        "phi": np.column_stack((ref[:, 0], nominal.phi, phi, est_link[:, 0])),
        "delta": np.column_stack((ref[:, 1], np.where(np.isnan(nominal.phi), np.nan, 0.0),
                                  delta, est_link[:, 1])),
        "theta_A": np.column_stack((ref[:, 2], nominal.theta_A, theta, est_theta)),
        "psi": np.column_stack((ref[:, 3], nominal.psi, psi, est_psi)),
    }  # fmt: skip
    R = quat_to_rotmat_many(q) if n else np.zeros((0, 3, 3))
    return TickSeries(
        t=log["t"],
        p_W=p,
        q_WB=q,
        est_p_W=log["est_p_W"],
        est_q_WB=est_q,
        attachment_W=p + R @ r_att,
        hook=log["hook"],
        phase=log["phase"],
        mode=log["mode"],
        angles=angles,
        tension=np.column_stack((log["tension"], log["est_tension"], nominal.tension)),
        thrusts_actual=log["rotor_thrusts"],
        thrusts_nominal=nominal.rotor_thrusts,
        thrusts_commanded=v.thrust_coefficient * np.square(log["cmd_rotor_speeds"]),
    )
