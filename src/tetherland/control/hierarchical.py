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
from tetherland.control.kernels import hierarchical as kernel
from tetherland.control.kernels.mixer import OUT_SATURATION
from tetherland.control.mixer import Mixer, command_from
from tetherland.errors import SingularityError
from tetherland.geometry import LandingGeometry, link_frame
from tetherland.interfaces import Command, Reference, StateEstimate
from tetherland.rotations import quat_to_rotmat
from tetherland.state import LinkState

_ZERO3 = np.zeros(3)


class HierarchicalController:
    """Gamma_HC^b: link-angle outer loop, SO(3) attitude inner loop (implements Controller).

    The update is one compiled call,
    :func:`tetherland.control.kernels.hierarchical.hierarchical_into` (plain reference beside
    it, with the equations of the module docstring: ``hierarchical_reference``).

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
        self.length = geo.link_length  # l + s: the taut link stretched at f_L (theory 4.2)
        self.g = GRAVITY
        self.R_WA = geo.R_WA
        self.r_att_B = np.asarray(v.cable_attachment, dtype=float)
        self.compensate_offset = gains.offset_compensation and bool(np.any(self.r_att_B))
        wn, zeta = gains.link_frequency, gains.link_damping
        self.k_p = wn * wn
        self.k_d = 2.0 * zeta * wn
        self.k_i = gains.link_integral
        self.lateral_damping = gains.lateral_damping
        self.integral_max = gains.link_integral_max
        self.attitude = AttitudeController(v.inertia, AttitudeGains.from_config(gains))
        self.mixer = Mixer(v)
        att = self.attitude
        self._par = kernel.pack_hierarchical(
            self.mass, self.length, self.g, self.k_p, self.k_d, self.k_i, self.integral_max,
            self.compensate_offset, self.r_att_B, self.R_WA, att.J, att.gains.k_R,
            att.gains.k_w,
        )  # fmt: skip
        # integral of the (phi, delta) errors [rad s], last update time, last regular
        # thrust and attitude (held through singularities)
        self._state = kernel.hierarchical_state(self.mass, self.g)
        self._lateral_free = False  # the last reference left the link azimuth to gravity
        self._lean_limit = 0.0  # the lean limit in state (Reference.lean_limit) [rad]
        # load the compiled law now (numba's cache, once per process), not at the first
        # tethered tick of a mission: a call on scratch arrays
        kernel.hierarchical_into(
            0.0, np.array([0.5, 0.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3),
            np.zeros((5, 4)), np.zeros(3), np.zeros(3), True, 0.0, self._state.copy(),
            self._par, self.mixer.packed, np.empty(kernel.OUT_WIDTH),
        )  # fmt: skip

    def reset(self) -> None:
        """Forget the last regular attitude and the link integral (on activation)."""
        last_thrust = self._state[kernel.STATE_THRUST]
        self._state[:] = kernel.hierarchical_state(self.mass, self.g)
        self._state[kernel.STATE_THRUST] = last_thrust
        self._lateral_free = False
        self._lean_limit = 0.0

    def hand_over(self, estimate: StateEstimate, reference: Reference, thrust: float) -> None:
        """Take over from the free-flight law that commanded ``thrust`` [N] along the
        estimated z_B: the link integral starts where this law's first command continues
        the last one across the link (its z_L and y_L components; along the link the
        cable takes the difference).

        With an empty integral the model error the free-flight law held (its position
        integral: a believed mass or thrust coefficient a few per cent off) is dropped and
        integrated again while the vehicle swings towards the surface: the link lags the
        plan, then the integral carries it past it, and it reaches the surface early and
        fast (wall90 with the magnet: 2 deg ahead at 4.5 cm/s, then a bounce). Solving
        u_z = m l (cos(delta) v_phi - ...) + m g cos(phi) and u_y = ... - m l v_delta for
        the integral terms k_i int(e) that make (u_y, u_z) the last command's components,
        clamped as the integral is."""
        self.reset()
        link, Y = estimate.link, reference.output
        if link is None or Y is None or not math.isfinite(thrust) or self.k_i <= 0.0:
            return
        F_W = thrust * quat_to_rotmat(estimate.body.q_WB)[:, 2]
        F_L = link_frame(link.phi, link.delta).T @ (self.R_WA.T @ F_W)
        rows = np.zeros((3, 4))
        rows[: min(3, Y.shape[0])] = Y[:3]
        m, l, g = self.mass, self.length, self.g
        v_phi = rows[2, 0] + self.k_d * (rows[1, 0] - link.phi_dot) + self.k_p * (
            rows[0, 0] - link.phi)  # fmt: skip
        v_delta = rows[2, 1] + self.k_d * (rows[1, 1] - link.delta_dot) + self.k_p * (
            rows[0, 1] - link.delta)  # fmt: skip
        u_y, u_z = kernel.link_force_components(
            m, l, g, link.phi, link.delta, link.phi_dot, link.delta_dot, v_phi, v_delta)
        cd = math.cos(link.delta)
        bound = self.integral_max / self.k_i
        integral = self._state[kernel.STATE_INTEGRAL]
        i_phi = (F_L[2] - u_z) / (m * l * cd * self.k_i)
        i_delta = -(F_L[1] - u_y) / (m * l * self.k_i)
        integral[0] = min(max(i_phi, -bound), bound)
        integral[1] = min(max(i_delta, -bound), bound)

    def _delta_free(self, Y: np.ndarray, link: LinkState) -> np.ndarray:
        """``Y`` with the delta rows that leave the link azimuth to gravity
        (``Reference.lateral_free``): delta_d = delta, delta_d' = (1 - c) delta' and
        delta_d'' = g sin(phi) sin(delta)/l - sin(2 delta) phi'^2/2 - k_i int(e_delta), so
        that in u_y the gravity, centripetal and integral terms cancel and the sideways
        force is the damping c m l k_d delta' alone, c = ``lateral_damping`` (the integral
        is kept, not updated: its error is 0; the first held tick after free ones drops
        it, :meth:`update`)."""
        out = np.zeros((max(Y.shape[0], 3), 4))
        out[: Y.shape[0]] = Y
        out[0, 1] = link.delta
        out[1:, 1] = 0.0
        out[1, 1] = (1.0 - self.lateral_damping) * link.delta_dot
        out[2, 1] = (
            self.g * math.sin(link.phi) * math.sin(link.delta) / self.length
            - 0.5 * math.sin(2.0 * link.delta) * link.phi_dot**2
            - self.k_i * self._state[kernel.STATE_INTEGRAL][1]
        )
        return out

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        """Rotor commands tracking ``reference.output`` (rows y_d, y_d', y_d'', ...)."""
        link = estimate.link
        Y = reference.output
        if link is None or Y is None:
            raise ValueError("the tethered controller needs estimate.link and reference.output")
        if reference.lateral_free:
            Y = self._delta_free(Y, link)
        elif self._lateral_free:
            # the azimuth is taken back (the lateral lock at the first sign of contact):
            # the free rows cancelled the delta integral, so the sideways force had none of
            # it; kept, it would return in one tick as a sideways step (about 0.09 N after
            # an approach held off the true plumb plane), rolling the frame just above the
            # surface. The hold starts from no integral, as the free hang applied none.
            self._state[kernel.STATE_INTEGRAL][1] = 0.0
        self._lateral_free = reference.lateral_free
        lean = reference.lean_limit
        if lean != self._lean_limit:  # (tan once per change, not per tick)
            self._lean_limit = lean
            self._state[kernel.STATE_LEAN_TAN] = math.tan(lean) if lean > 0.0 else 0.0
        ff = reference.feedforward
        tension = estimate.tension if estimate.tension is not None else (ff.tension if ff else 0.0)
        body = estimate.body
        out = np.empty(kernel.OUT_WIDTH)
        kernel.hierarchical_into(
            t, np.array((link.phi, link.delta, link.phi_dot, link.delta_dot)), body.q_WB,
            body.omega_B, Y, _ZERO3 if ff is None else ff.omega_B,
            _ZERO3 if ff is None else ff.omega_dot_B, ff is not None, float(tension),
            self._state, self._par, self.mixer.packed, out,
        )  # fmt: skip
        if out[kernel.OUT_THETA_UNDEFINED]:
            raise SingularityError(
                "thrust axis is perpendicular to the link plane: theta_A undefined"
            )
        e_phi, e_delta, e_theta, e_psi = out[kernel.OUT_ERRORS].tolist()
        diag = {
            "e_phi": e_phi,
            "e_delta": e_delta,
            "e_theta_A": e_theta,
            "e_psi": e_psi,
            "singular": float(out[kernel.OUT_SINGULAR]),
            "singularity_margin": float(out[kernel.OUT_MARGIN]),
            "ff_tension": ff.tension if ff is not None else math.nan,
            "saturation": float(out[OUT_SATURATION]),
        }
        return command_from(out, diag)
