"""The DFL model: Lie derivatives of y^b = [phi, delta, theta_A, psi] (docs/theory.md section 7).

The symbolic statement (CasADi) of the model in :mod:`tetherland.control.dfl`'s docstring,
with the vehicle parameters symbolic, so that one generated kernel
(:mod:`tetherland.control.kernels.dfl_terms`) serves every vehicle. The controller is
:class:`tetherland.control.DflController`, the law (plain and compiled) in
:mod:`tetherland.control.kernels.dfl`.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

from tetherland import GRAVITY
from tetherland.control.kernels.packing import Fields

DFL_RELATIVE_DEGREES = (4, 4, 2, 2)
"""Relative degrees of (phi, delta, theta_A, psi): 12 in total, the extended state."""
MODEL_PARAMETERS = ("mass", "length", "J_xx", "J_yy", "J_zz", "g")
"""The symbolic parameters p of :func:`dfl_expression`, in order [kg, m, kg m^2 (3), m/s^2]."""

_yab = Fields()
YAB_Y = _yab.vector(sum(DFL_RELATIVE_DEGREES))
"""y and its derivatives up to r - 1, output by output (phi, phi', ..., psi')."""
YAB_A = _yab.vector(16)
"""The decoupling matrix A = L_G L_f^{r-1} y, row-major 4x4."""
YAB_B = _yab.vector(4)
"""The drift b = L_f^r y."""
YAB_WIDTH = _yab.width
"""Length of the packed output yAb of :func:`dfl_expression`."""


def dfl_expression() -> tuple[ca.SX, ca.SX, ca.SX]:
    """(x (12), p (6), yAb (:data:`YAB_WIDTH`)) for the model of
    :mod:`tetherland.control.dfl`.

    yAb = [y and its derivatives up to r - 1 (:data:`YAB_Y`), A (4x4, row-major,
    :data:`YAB_A`), b (:data:`YAB_B`)], with the
    vehicle parameters p = (m, l, J_xx, J_yy, J_zz, g) symbolic, so that one compiled
    kernel (:mod:`tetherland.control.kernels.dfl_terms`, generated from this expression)
    serves every vehicle.
    """
    x = ca.SX.sym("x", 12)
    p = ca.SX.sym("p", len(MODEL_PARAMETERS))
    mass, length, g = p[0], p[1], p[5]
    J = ca.vertcat(p[2], p[3], p[4])
    u = ca.SX.sym("u", 4)
    phi, delta, dphi, ddelta, th, roll, psi = (x[i] for i in range(7))
    w = x[7:10]
    f, fd = x[10], x[11]
    cp, sp, cd, sd = ca.cos(phi), ca.sin(phi), ca.cos(delta), ca.sin(delta)
    z_B = ca.vertcat(ca.cos(roll) * ca.sin(th), -ca.sin(roll), ca.cos(roll) * ca.cos(th))
    y_L = ca.vertcat(cp * sd, cd, sp * sd)
    z_L = ca.vertcat(-sp, 0, cp)
    F = f * z_B
    u_y, u_z = ca.dot(y_L, F), ca.dot(z_L, F)
    ml = mass * length
    phi_dd = (u_z - mass * g * cp + 2 * ml * sd * dphi * ddelta) / (ml * cd)
    delta_dd = -u_y / ml + (g / length) * sp * sd - 0.5 * ca.sin(2 * delta) * dphi**2
    # Euler rates: omega = Rz^T Rx^T e_y th' + Rz^T e_x roll' + e_z psi'
    c_r, s_r, c_p, s_p = ca.cos(roll), ca.sin(roll), ca.cos(psi), ca.sin(psi)
    Rz_T = ca.vertcat(ca.horzcat(c_p, s_p, 0), ca.horzcat(-s_p, c_p, 0), ca.horzcat(0, 0, 1))
    E = ca.horzcat(Rz_T @ ca.vertcat(0, c_r, -s_r), Rz_T @ ca.vertcat(1, 0, 0), ca.vertcat(0, 0, 1))
    euler_rates = ca.solve(E, w)
    w_dot = (ca.vertcat(u[1], u[2], u[3]) - ca.cross(w, J * w)) / J  # J diagonal
    x_dot = ca.vertcat(dphi, ddelta, phi_dd, delta_dd, euler_rates, w_dot, fd, u[0])
    drift = ca.substitute(x_dot, u, ca.DM.zeros(4))
    G = ca.jacobian(x_dot, u)
    # outputs
    alpha = z_B - ca.dot(y_L, z_B) * y_L
    theta_A = ca.atan2(alpha[0], alpha[2])
    outputs = (phi, delta, theta_A, psi)
    derivs, rows_A, b = [], [], []
    for h, r in zip(outputs, DFL_RELATIVE_DEGREES, strict=True):
        e = h
        for _ in range(r):
            derivs.append(e)
            last = e
            e = ca.jtimes(e, x, drift)
        rows_A.append(ca.jacobian(last, x) @ G)
        b.append(e)
    A = ca.vertcat(*rows_A)
    # one packed output [y (12), A (16, row-major), b (4)]; common subexpressions merged
    return x, p, ca.cse(ca.vertcat(*derivs, ca.reshape(A.T, 16, 1), *b))


@lru_cache(maxsize=1)
def dfl_function() -> ca.Function:
    """The CasADi function (x, p) -> yAb of :func:`dfl_expression` (the reference of the
    compiled :func:`tetherland.control.kernels.dfl_terms.dfl_terms_into`)."""
    x, p, yAb = dfl_expression()
    return ca.Function("dfl", [x, p], [yAb], ["x", "p"], ["yAb"])


def model_parameters(
    mass: float, length: float, inertia: tuple[float, float, float], g: float = GRAVITY
) -> np.ndarray:
    """p of :func:`dfl_expression` for a vehicle [kg, m, kg m^2, m/s^2]."""
    return np.array([mass, length, *inertia, g], dtype=float)


