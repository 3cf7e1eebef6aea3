"""Dynamic-feedback-linearising tethered controller Gamma_DFL^b (docs/theory.md section 7).

Model (taut link at the centre of mass, vectors in F_A), extended with two integrators on
the total thrust:

  x = [phi, delta, phi', delta', theta_e, roll, psi, omega_B (3), f_R, f_R']   (12)
  u = [f_R'', tau_B (3)]
  link: (phi'', delta'') from :func:`tetherland.models.tethered.link_dynamics` with
        F = f_R z_B, z_B = R_y(theta_e) R_x(roll) e_3;
  attitude: R_AB = R_y(theta_e) R_x(roll) R_z(psi), Euler rates = E^-1 omega_B,
            J omega' = tau_B - omega x J omega.

The outputs y^b = [phi, delta, theta_A, psi] have relative degrees {4, 4, 2, 2}: 12 in
total, the state dimension, so there are no zero dynamics. With A = L_G L_f^{r-1} y
(4x4) and b = L_f^r y, the input u = A^-1 (v - b) gives y^(r) = v, and
v = y_d^(r) + sum_j k_j (y_d^(j) - y^(j)) with (s + p)^r error dynamics; with
``dfl_integral`` a clamped integral of each error is added and the error dynamics are
(s + p)^(r+1), so a constant model error leaves no steady offset. The extension knows
f_R', so the command leads the motor lag along it. The Lie
derivatives are derived symbolically with CasADi once per vehicle and compiled.

The extension states f_R, f_R' live in the controller and are integrated at the control
rate; :meth:`DflController.reset` starts them at a given thrust (bumpless switching).
Singular where A is (nearly) singular, i.e. its Hadamard ratio is below HADAMARD_MIN (the
hierarchical controller's singularities plus roll = 90 deg): detected, reported in the
diagnostics and handled by holding f_R'' = 0 and the last torque.
"""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca
import numpy as np

from tetherland import GRAVITY
from tetherland.config import Scenario
from tetherland.control.common import Mixer, cable_torque
from tetherland.geometry import LandingGeometry, link_frame
from tetherland.interfaces import Command, Reference, StateEstimate

_RELATIVE_DEGREES = (4, 4, 2, 2)
_SLICES = ((0, 4), (4, 4), (8, 2), (10, 2))  # (start, r) of each output's derivatives
_ERROR_NAMES = ("e_phi", "e_delta", "e_theta_A", "e_psi")
HADAMARD_MIN = 1e-9
"""|det A| / prod(||row_i||) below which the decoupling matrix counts as singular (the ratio
is 1 for orthogonal rows and 0 for dependent ones; cheaper than a condition number)."""


@lru_cache(maxsize=8)
def _dfl_function(
    mass: float, length: float, inertia: tuple[float, float, float], g: float
) -> ca.Function:
    """x (12) -> [y derivatives (12), A (4x4), b (4)] for the model in the module docstring."""
    x = ca.SX.sym("x", 12)
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
    J = ca.DM(np.diag(inertia))
    w_dot = ca.solve(J, ca.vertcat(u[1], u[2], u[3]) - ca.cross(w, J @ w))
    x_dot = ca.vertcat(dphi, ddelta, phi_dd, delta_dd, euler_rates, w_dot, fd, u[0])
    drift = ca.substitute(x_dot, u, ca.DM.zeros(4))
    G = ca.jacobian(x_dot, u)
    # outputs
    alpha = z_B - ca.dot(y_L, z_B) * y_L
    theta_A = ca.atan2(alpha[0], alpha[2])
    outputs = (phi, delta, theta_A, psi)
    derivs, rows_A, b = [], [], []
    for h, r in zip(outputs, _RELATIVE_DEGREES, strict=True):
        e = h
        for _ in range(r):
            derivs.append(e)
            last = e
            e = ca.jtimes(e, x, drift)
        rows_A.append(ca.jacobian(last, x) @ G)
        b.append(e)
    # one packed output [y (12), A (16, row-major), b (4)]: one conversion per call
    A = ca.vertcat(*rows_A)
    return ca.Function(
        "dfl", [x], [ca.vertcat(*derivs, ca.reshape(A.T, 16, 1), *b)], ["x"], ["yAb"]
    )


def _poly_gains(pole: float, order: int) -> np.ndarray:
    """Coefficients k_0..k_{r-1} of (s + p)^r = s^r + k_{r-1} s^{r-1} + ... + k_0."""
    coeffs = np.poly(np.full(order, -pole))  # [1, k_{r-1}, ..., k_0]
    return coeffs[1:][::-1].real


class DflController:
    """Gamma_DFL^b for y^b = [phi, delta, theta_A, psi] (implements Controller).

    Parameters
    ----------
    scenario : Scenario
        Believed vehicle, cable, anchor and gains (``controller.tethered``).
    control_dt : float, optional
        Period of :meth:`update` calls used to integrate the thrust extension [s]
        (default: 1/controller.rate_hz). Calls at other spacings use the actual spacing.
    """

    def __init__(self, scenario: Scenario, control_dt: float | None = None):
        v = scenario.vehicle
        gains = scenario.controller.tethered
        geo = LandingGeometry.from_scenario(scenario)
        self.mass = v.mass
        self.R_WA = geo.R_WA
        self.r_att_B = np.asarray(v.cable_attachment, dtype=float)
        self.compensate_offset = gains.offset_compensation and bool(np.any(self.r_att_B))
        self._fn = _dfl_function(v.mass, scenario.tether.length, tuple(v.inertia), GRAVITY)
        poles = (gains.dfl_link_pole,) * 2 + (gains.dfl_attitude_pole,) * 2
        self.integral = gains.dfl_integral
        self.integral_max = gains.dfl_integral_max
        extra = 1 if self.integral else 0
        full = [_poly_gains(p, r + extra) for p, r in zip(poles, _RELATIVE_DEGREES, strict=True)]
        # v = y_d^(r) + k_I int(e) + k . (e, e', ..., e^(r-1)): (s + p)^(r+1) with the integral
        self._k_int = [float(k[0]) if extra else 0.0 for k in full]
        self._k = [k[extra:] for k in full]
        self._e_int = [0.0] * 4
        self.mixer = Mixer(v)
        self._thrust_share = self.mixer.layout.allocation_inverse[:, 0].copy()  # dF_i/df_R
        self.control_dt = (
            control_dt if control_dt is not None else 1.0 / scenario.controller.rate_hz
        )
        self._f: float | None = None
        self._fd = 0.0
        self._t_last: float | None = None
        self._last_u = np.zeros(4)

    def reset(self, thrust: float | None = None, thrust_rate: float = 0.0) -> None:
        """Restart the thrust extension at ``thrust`` [N] and ``thrust_rate`` [N/s]
        (None: the reference's nominal thrust at the next update)."""
        self._f = thrust
        self._fd = thrust_rate
        self._t_last = None
        self._e_int = [0.0] * 4

    @property
    def extension(self) -> tuple[float | None, float]:
        """The thrust extension state (f_R, f_R') [N, N/s]."""
        return self._f, self._fd

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        """Rotor commands: u = A^-1 (v - b), then integrate f_R'' into the thrust."""
        link = estimate.link
        Y = reference.output
        if link is None or Y is None or Y.shape[0] < 5:
            raise ValueError(
                "the DFL controller needs estimate.link and 5 rows of reference.output"
            )
        ff = reference.feedforward
        if self._f is None:
            self._f = ff.f_R if ff is not None else self.mass * GRAVITY
            self._fd = ff.f_R_dot if ff is not None else 0.0
        dt = 0.0
        if self._t_last is not None:
            dt = t - self._t_last
            u0 = self._last_u[0]
            self._f += self._fd * dt + 0.5 * u0 * dt * dt
            self._fd += u0 * dt
        self._t_last = t
        R = estimate.body.R_WB
        R_AB = self.R_WA.T @ R
        zx, zy, zz = R_AB[0, 2], R_AB[1, 2], R_AB[2, 2]
        ax, ay, az = R_AB[0, 0], R_AB[1, 0], R_AB[2, 0]
        theta_e = math.atan2(zx, zz)
        roll = math.atan2(-zy, math.hypot(zx, zz))
        c_t, s_t, c_r, s_r = math.cos(theta_e), math.sin(theta_e), math.cos(roll), math.sin(roll)
        # psi from R_AB = M R_z(psi), M = R_y(theta_e) R_x(roll): columns 0, 1 of M dotted with
        # the first column of R_AB
        psi = math.atan2(s_t * s_r * ax + c_r * ay + c_t * s_r * az, c_t * ax - s_t * az)
        w = estimate.body.omega_B
        x = np.array(
            [link.phi, link.delta, link.phi_dot, link.delta_dot, theta_e, roll, psi,
             w[0], w[1], w[2], self._f, self._fd]
        )  # fmt: skip
        packed = self._fn(x).full().ravel()
        y_all, A, b = packed[:12], packed[12:28].reshape(4, 4), packed[28:32]
        v = np.empty(4)
        e0 = [0.0] * 4
        for j, (i, r) in enumerate(_SLICES):
            e = Y[:r, j] - y_all[i : i + r]
            if j == 3:
                e[0] = math.remainder(e[0], 2 * math.pi)
            v[j] = Y[r, j] + self._k[j] @ e
            e0[j] = float(e[0])
        errors = dict(zip(_ERROR_NAMES, e0, strict=True))
        if self.integral:
            lim = self.integral_max
            e_int = self._e_int
            extra = [0.0] * 4
            for j in range(4):
                e_int[j] = min(lim, max(-lim, e_int[j] + e0[j] * dt))
                extra[j] = self._k_int[j] * e_int[j]
            v += extra
        ratio = abs(np.linalg.det(A)) / float(np.prod(np.sqrt((A * A).sum(axis=1))))
        singular = not ratio >= HADAMARD_MIN
        u = np.array([0.0, *self._last_u[1:]]) if singular else np.linalg.solve(A, v - b)
        self._last_u = u
        tau = u[1:4].copy()
        tension = estimate.tension if estimate.tension is not None else (ff.tension if ff else 0.0)
        if self.compensate_offset and tension > 0.0:
            d_B = R.T @ (self.R_WA @ link_frame(link.phi, link.delta)[:, 0])
            tau = tau - cable_torque(self.r_att_B, tension, d_B)
        diag = {
            **errors,
            "singular": float(singular),
            "decoupling_ratio": float(ratio),
            "ff_tension": ff.tension if ff is not None else math.nan,
        }
        # the rotors hold the command for one period: send the mean of the thrust polynomial
        # over it, f + f' h/2 + f'' h^2/6, so the hold adds no first-order error
        h = self.control_dt
        thrust = self._f + 0.5 * self._fd * h + u[0] * h * h / 6.0
        # the extension knows f_R': lead the motor lag along it (torques are not led)
        rates = self._thrust_share * (self._fd + 0.5 * u[0] * h)
        return self.mixer.command(max(thrust, 0.0), tau, diag, thrust_rates=rates)
