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
f_R', so the command leads the motor lag along it. The Lie derivatives are derived
symbolically with CasADi (:mod:`tetherland.control.kernels.dfl_model`, the vehicle
parameters symbolic too) and generated into a numba kernel,
:mod:`tetherland.control.kernels.dfl_terms`.

What it neglects of the cable attachment offset r_att (docs/theory.md section 4.6): the
model's link ends at the centre of mass. With an offset the link ends at the attachment
point, whose acceleration adds R_AB(alpha x r + omega x (omega x r)) to the centre of
mass's (4.10); since alpha = J^-1 tau_B, phi'' and delta'' would then depend on the
torque input directly, all four rows of L_G L_f y at order 2 would carry only the three
torque columns, and the decoupling matrix of the relative degrees {4, 4, 2, 2} would be
singular: no static state feedback on this extension linearises the offset model
exactly. The controller keeps the chapter's model and cancels the offset's cable moment
r x (-f_L R_BA d) with the estimated tension (``offset_compensation``, section 7.7); the
neglected coupling force m |alpha x r + omega x (omega x r)| peaks at 0.06 N on
``slope50`` (under 1 % of m g, section 6.7), which the feedback (and ``dfl_integral``)
absorbs. The planner counts it exactly (section 6.7), and it is the elastic cable's
stretch the DFL also neglects: the link length is l, not l + f_L/k (about 1 cm for
nylon at l = 1 m, a 1 % error in the l of phi'').

The extension states f_R, f_R' live in the controller and are integrated at the control
rate; :meth:`DflController.reset` starts them at a given thrust (bumpless switching).
Singular where A is (nearly) singular, i.e. its Hadamard ratio is below
:data:`tetherland.control.kernels.dfl.HADAMARD_MIN` (the hierarchical controller's
singularities plus roll = 90 deg): detected, reported in the diagnostics and handled by
holding f_R'' = 0 and the last torque.
"""

from __future__ import annotations

import math

import numpy as np

from tetherland import GRAVITY
from tetherland.config import Scenario
from tetherland.control.kernels import dfl as kernel
from tetherland.control.kernels.dfl_model import (
    DFL_RELATIVE_DEGREES,
    MODEL_PARAMETERS,
    dfl_expression,
    dfl_function,
    model_parameters,
)
from tetherland.control.kernels.mixer import OUT_SATURATION
from tetherland.control.mixer import Mixer, command_from
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import Command, Reference, StateEstimate

_ERROR_NAMES = ("e_phi", "e_delta", "e_theta_A", "e_psi")


def _poly_gains(pole: float, order: int) -> np.ndarray:
    """Coefficients k_0..k_{r-1} of (s + p)^r = s^r + k_{r-1} s^{r-1} + ... + k_0."""
    coeffs = np.poly(np.full(order, -pole))  # [1, k_{r-1}, ..., k_0]
    return coeffs[1:][::-1].real


class DflController:
    """Gamma_DFL^b for y^b = [phi, delta, theta_A, psi] (implements Controller).

    The update is one compiled call, :func:`tetherland.control.kernels.dfl.dfl_into`, with
    the Lie derivatives generated from :func:`dfl_expression` (plain reference beside it,
    with the CasADi function: ``dfl_reference``).

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
        # The taut link stretched at the landed hover's tension, l + s (theory 4.2).
        self.model = model_parameters(v.mass, geo.link_length, tuple(v.inertia))
        poles = (gains.dfl_link_pole,) * 2 + (gains.dfl_attitude_pole,) * 2
        self.integral = gains.dfl_integral
        self.integral_max = gains.dfl_integral_max
        extra = 1 if self.integral else 0
        degrees = zip(poles, DFL_RELATIVE_DEGREES, strict=True)
        full = [_poly_gains(p, r + extra) for p, r in degrees]
        # v = y_d^(r) + k_I int(e) + k . (e, e', ..., e^(r-1)): (s + p)^(r+1) with the integral
        k_int = [float(k[0]) if extra else 0.0 for k in full]
        self.mixer = Mixer(v)
        self.control_dt = (
            control_dt if control_dt is not None else 1.0 / scenario.controller.rate_hz
        )
        self._par = kernel.pack_dfl(
            self.mass, self.integral, self.integral_max, self.compensate_offset, self.control_dt,
            self.r_att_B, self.R_WA, [k[extra:] for k in full], k_int,
            self.mixer.layout.allocation_inverse[:, 0],  # dF_i/df_R: the thrust share
            self.model,
        )  # fmt: skip
        # thrust extension, last update time, last input, error integrals (kernel.STATE_*)
        self._state = kernel.dfl_state()
        # load the compiled law now (numba's cache, once per process), not at the first
        # tethered tick of a mission: a call on scratch arrays
        scratch = kernel.dfl_state()
        scratch[kernel.STATE_THRUST] = self.mass * GRAVITY
        kernel.dfl_into(
            0.0, np.array([0.5, 0.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3),
            np.zeros((5, 4)), 0.0, scratch, self._par, self.mixer.packed,
            np.empty(kernel.OUT_WIDTH),
        )  # fmt: skip

    def reset(self, thrust: float | None = None, thrust_rate: float = 0.0) -> None:
        """Restart the thrust extension at ``thrust`` [N] and ``thrust_rate`` [N/s]
        (None: the reference's nominal thrust at the next update)."""
        state = self._state
        last_u = state[kernel.STATE_U].copy()  # the held torque survives a restart
        state[:] = kernel.dfl_state()
        state[kernel.STATE_U] = last_u
        if thrust is not None:
            state[kernel.STATE_THRUST] = thrust
        state[kernel.STATE_THRUST_RATE] = thrust_rate

    @property
    def extension(self) -> tuple[float | None, float]:
        """The thrust extension state (f_R, f_R') [N, N/s]."""
        f = float(self._state[kernel.STATE_THRUST])
        return (None if math.isnan(f) else f), float(self._state[kernel.STATE_THRUST_RATE])

    def update(self, t: float, estimate: StateEstimate, reference: Reference) -> Command:
        """Rotor commands: u = A^-1 (v - b), then integrate f_R'' into the thrust."""
        link = estimate.link
        Y = reference.output
        if link is None or Y is None or Y.shape[0] < 5:
            raise ValueError(
                "the DFL controller needs estimate.link and 5 rows of reference.output"
            )
        ff = reference.feedforward
        state = self._state
        if math.isnan(state[kernel.STATE_THRUST]):  # start at the plan's nominal thrust
            state[kernel.STATE_THRUST] = ff.f_R if ff is not None else self.mass * GRAVITY
            state[kernel.STATE_THRUST_RATE] = ff.f_R_dot if ff is not None else 0.0
        tension = estimate.tension if estimate.tension is not None else (ff.tension if ff else 0.0)
        body = estimate.body
        out = np.empty(kernel.OUT_WIDTH)
        kernel.dfl_into(
            t, np.array((link.phi, link.delta, link.phi_dot, link.delta_dot)), body.q_WB,
            body.omega_B, Y, float(tension), state, self._par, self.mixer.packed, out,
        )  # fmt: skip
        diag = dict(zip(_ERROR_NAMES, out[kernel.OUT_ERRORS].tolist(), strict=True))
        diag["singular"] = float(out[kernel.OUT_SINGULAR])
        diag["decoupling_ratio"] = float(out[kernel.OUT_RATIO])
        diag["ff_tension"] = ff.tension if ff is not None else math.nan
        diag["saturation"] = float(out[OUT_SATURATION])
        return command_from(out, diag)


__all__ = [
    "MODEL_PARAMETERS",
    "DflController",
    "dfl_expression",
    "dfl_function",
    "model_parameters",
]
