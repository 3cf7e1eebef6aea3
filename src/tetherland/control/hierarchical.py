"""Hierarchical tethered controller Gamma_HC^b for y^b = [phi, delta, theta_A, psi].

docs/theory.md section 7 (chapter 4.5.2, used in the experiments of 6.6). Outer loop on the
link angles (vectors in F_A, F_L components):

  v_phi   = phi_d''   + k_d (phi_d'   - phi')   + k_p (phi_d   - phi)
  v_delta = delta_d'' + k_d (delta_d' - delta') + k_p (delta_d - delta)

plus a clamped integral k_i int(e) on each (for model errors: thrust coefficient, mass),

  u_z = m l (cos(delta) v_phi - 2 sin(delta) phi' delta') + m g cos(phi)
  u_y = m g sin(phi) sin(delta) - m l (v_delta + sin(2 delta) phi'^2 / 2)
  u_x = u_z tan(phi + theta_A,d) / cos(delta)

which makes phi'' = v_phi and delta'' = v_delta in the taut-link model. The desired
thrust vector F_d = u_x x_L + u_y y_L + u_z z_L gives z_B,d = F_d/||F_d||, R_d from
(z_B,d, psi_d) in the parametrisation of :mod:`tetherland.models.flatness`, and the thrust
f_R = F_d . z_B on the actual axis. Inner loop: SO(3) attitude control with the planned
angular velocity as feed-forward, and the cable-offset torque cancelled (6.6.5).

Singular where cos(delta) = 0, u_z <= 0, cos(phi + theta_A,d) = 0 or F_d = 0: detected,
reported in the command's diagnostics (``singular`` = 1) and handled by holding the last
regular desired attitude and thrust; never a division by zero.
"""

from __future__ import annotations

import math

import numpy as np

from tetherland import GRAVITY
from tetherland.config import Scenario
from tetherland.control.attitude import AttitudeController, AttitudeGains
from tetherland.control.common import Mixer, attitude_from_thrust_axis, cable_torque, heading_of
from tetherland.geometry import LandingGeometry, link_frame, theta_A_from_z_B
from tetherland.interfaces import Command, Reference, StateEstimate
from tetherland.models.tethered import COS_DELTA_MIN

U_Z_MIN_FRACTION = 0.02
"""u_z below this fraction of m g counts as singular (the thrust must push across the link)."""
COS_SUM_MIN = 0.02
"""|cos(phi + theta_A,d)| below this is singular (thrust axis along the link)."""


class HierarchicalController:
    """Gamma_HC^b: link-angle outer loop, SO(3) attitude inner loop (implements Controller).

    Parameters
    ----------
    scenario : Scenario
        The believed scenario: mass, cable length, anchor, inertia, rotors, gains
        (``controller.tethered``).
    """

    def __init__(self, scenario: Scenario):
        v = scenario.vehicle
        gains = scenario.controller.tethered
        geo = LandingGeometry.from_scenario(scenario)
        self.mass = v.mass
        self.length = scenario.tether.length
        self.g = GRAVITY
        self.R_WA = geo.R_WA
        self.r_att_B = np.asarray(v.cable_attachment, dtype=float)
        self.compensate_offset = gains.offset_compensation and bool(np.any(self.r_att_B))
        wn, zeta = gains.link_frequency, gains.link_damping
        self.k_p = wn * wn
        self.k_d = 2.0 * zeta * wn
        self.k_i = gains.link_integral
        self.integral_max = gains.link_integral_max
        self._integral = np.zeros(2)  # integral of the (phi, delta) errors [rad s]
        self._t_last: float | None = None
        self.attitude = AttitudeController(v.inertia, AttitudeGains.from_config(gains))
        self.mixer = Mixer(v)
        self._last_R_d: np.ndarray | None = None
        self._last_F: float = self.mass * self.g

    def reset(self) -> None:
        """Forget the last regular attitude and the link integral (on activation)."""
        self._last_R_d = None
        self._integral[:] = 0.0
        self._t_last = None

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        """Rotor commands tracking ``reference.output`` (rows y_d, y_d', y_d'', ...)."""
        link = estimate.link
        Y = reference.output
        if link is None or Y is None:
            raise ValueError("the tethered controller needs estimate.link and reference.output")
        phi, delta, dphi, ddelta = link.phi, link.delta, link.phi_dot, link.delta_dot
        yd = Y[0]
        yd1 = Y[1] if Y.shape[0] > 1 else np.zeros(4)
        yd2 = Y[2] if Y.shape[0] > 2 else np.zeros(4)
        m, l, g = self.mass, self.length, self.g
        if self._t_last is not None and self.k_i > 0.0:
            bound = self.integral_max / self.k_i
            dt = t - self._t_last
            self._integral[0] = min(max(self._integral[0] + (yd[0] - phi) * dt, -bound), bound)
            self._integral[1] = min(max(self._integral[1] + (yd[1] - delta) * dt, -bound), bound)
        self._t_last = t
        i_phi, i_delta = self.k_i * self._integral
        v_phi = yd2[0] + self.k_d * (yd1[0] - dphi) + self.k_p * (yd[0] - phi) + i_phi
        v_delta = yd2[1] + self.k_d * (yd1[1] - ddelta) + self.k_p * (yd[1] - delta) + i_delta
        cp, sp, cd, sd = math.cos(phi), math.sin(phi), math.cos(delta), math.sin(delta)
        u_z = m * l * (cd * v_phi - 2.0 * sd * dphi * ddelta) + m * g * cp
        u_y = m * g * sp * sd - m * l * (v_delta + 0.5 * math.sin(2.0 * delta) * dphi * dphi)
        cos_sum = math.cos(phi + yd[2])
        margin = min(abs(cd) / 0.1, u_z / (U_Z_MIN_FRACTION * m * g), abs(cos_sum) / COS_SUM_MIN)
        R = estimate.body.R_WB
        singular = (
            abs(cd) < COS_DELTA_MIN or u_z < U_Z_MIN_FRACTION * m * g or abs(cos_sum) < COS_SUM_MIN
        )
        if not singular:
            u_x = u_z * math.tan(phi + yd[2]) / cd
            R_AL = link_frame(phi, delta)
            F_A = R_AL @ np.array([u_x, u_y, u_z])
            F_norm = float(np.linalg.norm(F_A))
            singular = F_norm < 1e-6 * m * g
        if singular:
            R_d = self._last_R_d if self._last_R_d is not None else R
            f_R = self._last_F
        else:
            R_d = self.R_WA @ attitude_from_thrust_axis(F_A / F_norm, yd[3])
            f_R = float((self.R_WA @ F_A) @ R[:, 2])
            self._last_R_d, self._last_F = R_d, f_R
        ff = reference.feedforward
        if ff is not None:
            tau = self.attitude.torque(R, estimate.body.omega_B, R_d, ff.omega_B, ff.omega_dot_B)
        else:
            tau = self.attitude.torque(R, estimate.body.omega_B, R_d)
        tension = estimate.tension if estimate.tension is not None else (ff.tension if ff else 0.0)
        if self.compensate_offset and tension > 0.0:
            d_B = R.T @ (self.R_WA @ link_frame(phi, delta)[:, 0])
            tau = tau - cable_torque(self.r_att_B, tension, d_B)
        z_B_A = self.R_WA.T @ R[:, 2]
        theta_A = theta_A_from_z_B(z_B_A, phi, delta)
        psi = heading_of(self.R_WA.T @ R)
        diag = {
            "e_phi": yd[0] - phi,
            "e_delta": yd[1] - delta,
            "e_theta_A": yd[2] - theta_A,
            "e_psi": math.remainder(yd[3] - psi, 2.0 * math.pi),
            "singular": float(singular),
            "singularity_margin": margin,
            "ff_tension": ff.tension if ff is not None else math.nan,
        }
        return self.mixer.command(max(f_R, 0.0), tau, diag)
