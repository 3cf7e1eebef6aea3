"""The perching OCP as an :class:`~tetherland.planning.ocp.OcpProblem` (fixed duration).

  minimise   integral_0^T  k_jerk |p'''|^2 + k_omega theta'^2 + k_u sum_i f_i''^2  dt
  subject to the extended planar model (:mod:`.model`), x(0) = x_start,
             f_lo <= f_i <= f_hi at the nodes and between them (Bernstein bound on the
             quadratic thrust arcs, as the tethered planner does),
             lander tips and rotor-guard rims at least ``clearance_margin`` above P_S,
             and the lander tips above the approach funnel min(d_f, rho v_n (T - t)),
             |theta| <= max_pitch,
             p(T) = p*_L + h_R z_S, theta(T) = beta, theta'(T) = 0, tau(T) = 0,
             p'(T) = -v_n z_S, f_R(T) = m g cos(beta).

The last condition balances the normal component of gravity at touchdown: zero normal
acceleration, and the least acceleration any touchdown with z_B = z_S can have,
|p''(t_L)| = g sin(beta), which is zero on flat ground, where condition (4) can hold.

Every number (vehicle, slope, target, weights) is a parameter of the statement, so one
compiled solver serves every slope and vehicle; the duration T is a number too, which
the free-final-time search of :mod:`.planner` varies.

With the believed rotor drag (``PerchSpec.rotor_drag`` > 0) the dynamics carry it
(:func:`.model.rhs`), its coefficient one more parameter; a drag-free request keeps the
drag-free statement (the same expressions, the same compiled solver, the same plan).

The approach funnel keeps the plan from grazing the surface: without it the optimum
skims along the slope for the last ~0.1 s (the tips within a millimetre of the surface
while moving tangentially), so a millimetre of tracking error brings contact that much
earlier at full tangential speed. With it the last d_f are flown towards the surface at
a normal speed of at least rho v_n. With v_n = 0 the funnel vanishes (see
``perching.approach_speed``).
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from tetherland.planning.ocp import OcpProblem
from tetherland.planning.perching.model import (
    CASADI,
    INPUT_NAMES,
    NU,
    NX,
    STATE_NAMES,
    PerchSpec,
    clearance_terms,
    rhs,
)

FUNNEL_FRACTION = 0.5
"""rho: the lander tips' clearance floor rises at this fraction of the approach speed."""

_PARAMS = (
    ("mass", 1), ("inertia", 1), ("gravity", 1), ("G", 8), ("beta", 1), ("h_R", 1),
    ("w", 1), ("reach", 1), ("target", 2), ("v_final", 2), ("k_jerk", 1), ("k_omega", 1),
    ("k_u", 1), ("f_R_final", 1), ("funnel_height", 1), ("funnel_speed", 1),
)  # fmt: skip


_DRAG_PARAMS = (*_PARAMS, ("drag", 1))


def _params(drag: bool) -> tuple[tuple[str, int], ...]:
    return _DRAG_PARAMS if drag else _PARAMS


def _param_values(spec: PerchSpec) -> np.ndarray:
    w = spec.weights
    values = {
        "mass": spec.mass, "inertia": spec.inertia, "gravity": spec.gravity,
        "G": spec.G.reshape(-1), "beta": spec.beta, "h_R": spec.h_R,
        "w": spec.lander_half_width, "reach": spec.guard_reach, "target": spec.p_landed,
        "v_final": spec.v_final, "k_jerk": w.k_jerk, "k_omega": w.k_omega,
        "k_u": w.k_thrust_accel, "f_R_final": spec.f_R_final,
        "funnel_height": spec.approach_height,
        "funnel_speed": FUNNEL_FRACTION * spec.approach_speed, "drag": spec.rotor_drag,
    }  # fmt: skip
    names = _params(spec.rotor_drag > 0.0)
    return np.concatenate([np.atleast_1d(np.asarray(values[n], dtype=float)) for n, _ in names])


def _numbers(spec: PerchSpec, duration: float) -> dict[str, object]:
    x_lb, x_ub = np.full(NX, -np.inf), np.full(NX, np.inf)
    x_lb[2], x_ub[2] = -spec.max_pitch, spec.max_pitch
    m = spec.clearance_margin
    return {
        "duration": duration,
        "x0": spec.x_start,
        "p_value": _param_values(spec),
        "path_lb": np.array([spec.f_lo] * 8 + [m] * 4),
        "path_ub": np.array([spec.f_hi] * 8 + [np.inf] * 4),
        "x_lb": x_lb,
        "x_ub": x_ub,
        "u_lb": np.full(NU, -np.inf),
        "u_ub": np.full(NU, np.inf),
    }


def build_perching_ocp(
    spec: PerchSpec, duration: float, template: OcpProblem | None = None
) -> OcpProblem:
    """The perching OCP of ``spec`` over ``duration`` seconds.

    ``template``: a problem built before by this function for a request of the same
    kind (drag-free, or with rotor drag); its symbolic statement is reused (only the
    numbers change), which keeps the structure key and the compiled solver.
    """
    numbers = _numbers(spec, duration)
    if template is not None:
        return template.with_numbers(**numbers)
    return OcpProblem(**_statement(spec.rotor_drag > 0.0), **numbers)


def _statement(drag: bool = False) -> dict[str, object]:
    s = {name: ca.SX.sym(name, n) for name, n in _params(drag)}
    P = ca.vertcat(*s.values())
    x, u = ca.SX.sym("x", NX), ca.SX.sym("u", NU)
    t, T, h = ca.SX.sym("t"), ca.SX.sym("T"), ca.SX.sym("h")
    G = ca.reshape(s["G"], 2, 4).T  # (4, 2) from row-major values
    m = s["mass"]
    ode = rhs(x, u, m, s["inertia"], s["gravity"], CASADI, s["drag"] if drag else None)
    F, om, dF = x[6], x[5], x[8]
    wrench, wrench_dot = x[6:8], x[8:10]
    jerk_sq = (dF / m) ** 2 + (F * om / m) ** 2
    L = s["k_jerk"] * jerk_sq + s["k_omega"] * om**2 + s["k_u"] * ca.sumsqr(G @ u)
    # Thrusts are quadratic in t on an interval (f'' held): f_k, f_k + f_k' h/2 and
    # f_{k+1} are their Bernstein coefficients; bounding them bounds the whole arc.
    clear = clearance_terms(x, s["beta"], s["h_R"], s["w"], s["reach"], CASADI)
    # Approach funnel: the lander tips stay above min(d_f, rho v_n (T - t)).
    funnel = ca.fmin(s["funnel_height"], s["funnel_speed"] * (T - t))
    path = ca.vertcat(
        G @ wrench,
        G @ (wrench + 0.5 * h * wrench_dot),
        clear[0:2] - funnel,
        clear[2:4],
    )
    target, v_f = s["target"], s["v_final"]
    terminal = ca.vertcat(
        x[0] - target[0], x[1] - target[1], x[2] - s["beta"], x[3] - v_f[0], x[4] - v_f[1],
        om, x[7], x[6] - s["f_R_final"],
    )  # fmt: skip
    return {
        "x": x, "u": u, "p": P, "t": t, "T": T, "h": h, "ode": ode, "stage_cost": L,
        "terminal_cost": ca.SX(0), "path": path, "terminal": terminal,
        "state_names": STATE_NAMES, "input_names": INPUT_NAMES,
    }  # fmt: skip
