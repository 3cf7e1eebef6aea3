"""Margins of a design when the robot's belief is off by the campaign's error bounds.

A campaign run (:mod:`tetherland.campaign.perturb`) flies a belief whose surface is tilted
(slope, azimuth) and moved along its normal, whose anchor is off along x_S, y_S and in
height h_A, and whose mass and rotor thrust coefficient are off, each by up to the
``[perturbation]`` half-widths. The robot flies the hooking pass of its belief; the plant's
surface is the true one. This module bounds what is left of the design's margins:

* :func:`robust_pass_clearance`: the least distance of the vehicle from the *true* surface
  along the pass the robot plans from a believed anchor height and mass at the corners of
  their bounds (:func:`~tetherland.campaign.perturb.apply_perturbation`, exactly as a
  campaign builds its belief), with the true surface tilted, moved and the pass shifted
  along the surface at the corners of the other bounds (:func:`true_surfaces`).
  The vehicle does not fly the pass exactly: the campaign's wind gusts push it off, so
  the clearance is also shifted horizontally towards the surface by
  :func:`gust_deviation`, the largest deviation of the free-flight position loop under
  the largest gust (with the believed mass and thrust coefficient at their corners).
* :func:`robust_rotor_margin`: the rotor margin when the commanded thrusts scale with the
  believed mass and thrust coefficient (:meth:`BeliefBounds.thrust_scale`).
* :func:`believed_hover_margin`: the rotor margin of the maneuvers' boundary hovers (the
  taut start hover and the landed inclined hover) as the robot computes them from its
  belief, at the corners of the mass, slope and anchor-height errors: the robot plans only
  when they keep the control margin (the plan's precheck), so a design whose landed hover
  sits just above the rotor floor is refused by the robot on part of its beliefs.

The errors are small, so each margin is extreme at a corner of the error box (to first
order the distances are linear in the errors); the corners are what is evaluated.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

from tetherland.analysis.clearance import level_vehicle_distance
from tetherland.campaign.perturb import Perturbation, apply_perturbation
from tetherland.config import Scenario
from tetherland.errors import SingularityError
from tetherland.geometry import LandingGeometry
from tetherland.mission.hooking import PIPE_SAMPLES, HookingPass, hooking_pass
from tetherland.planning.maneuver import Maneuver, ManeuverSpec
from tetherland.surface import Surface, surface_frame_from_slope


@dataclass(frozen=True)
class BeliefBounds:
    """Half-widths of the belief errors a campaign draws (the scenario's ``[perturbation]``).

    Attributes
    ----------
    mass_rel, thrust_coefficient_rel : float
        Relative errors of the believed mass and rotor thrust coefficient [-].
    slope_error_deg, azimuth_error_deg : float
        Errors of the believed slope and downhill azimuth [deg].
    anchor_error : float
        Error of the believed anchor along x_S, y_S and in height h_A [m].
    surface_offset_error : float
        Error of the believed surface position along its normal [m].
    pipe_radius_error : float
        Error of the believed pipe radius [m] (a pipe only).
    wind_gust_force : float
        Largest peak horizontal gust force on the vehicle [N] (0: no gusts).
    wind_gust_duration : float
        Duration of one raised-cosine gust [s].
    """

    mass_rel: float = 0.0
    thrust_coefficient_rel: float = 0.0
    slope_error_deg: float = 0.0
    azimuth_error_deg: float = 0.0
    anchor_error: float = 0.0
    surface_offset_error: float = 0.0
    pipe_radius_error: float = 0.0
    wind_gust_force: float = 0.0
    wind_gust_duration: float = 0.5

    @classmethod
    def from_scenario(cls, scenario: Scenario) -> BeliefBounds:
        """The bounds of ``scenario``'s ``[perturbation]`` section."""
        c = scenario.perturbation
        return cls(
            mass_rel=c.mass_rel, thrust_coefficient_rel=c.thrust_coefficient_rel,
            slope_error_deg=c.slope_error_deg, azimuth_error_deg=c.azimuth_error_deg,
            anchor_error=c.anchor_error, surface_offset_error=c.surface_offset_error,
            pipe_radius_error=c.pipe_radius_error,
            wind_gust_force=c.wind_gust_force if c.wind_gust_rate > 0 else 0.0,
            wind_gust_duration=c.wind_gust_duration,
        )  # fmt: skip

    def thrust_scale(self) -> tuple[float, float]:
        """Least and largest ratio of a commanded to the nominal rotor thrust [-].

        The robot plans and feeds forward with its believed mass m (1 + e_m) and converts
        thrusts to rotor speeds with its believed coefficient c_f (1 + e_k): to produce the
        thrust f that the true vehicle needs it commands about f (1 + e_m)(1 + e_k), and its
        limits [f_min, f_max] apply to that command.
        """
        m, k = self.mass_rel, self.thrust_coefficient_rel
        return ((1.0 - m) * (1.0 - k), (1.0 + m) * (1.0 + k))


def robust_rotor_margin(f_low: float, f_high: float, f_min: float, f_max: float,
                        bounds: BeliefBounds) -> float:  # fmt: skip
    """Rotor margin of thrusts in [f_low, f_high] [N] commanded with the belief's errors.

    min(s_lo f_low - f_min, f_max - s_hi f_high) [N] with (s_lo, s_hi) =
    :meth:`BeliefBounds.thrust_scale`: the closest a command comes to either limit.
    """
    s_lo, s_hi = bounds.thrust_scale()
    return float(min(s_lo * f_low - f_min, f_max - s_hi * f_high))


def believed_hover_margin(scenario: Scenario, bounds: BeliefBounds) -> float:
    """Least rotor margin of the landing's boundary hovers over the belief corners [N].

    For every corner of the believed mass (1 +- ``mass_rel``), slope (+- ``slope_error_deg``),
    anchor height (+- ``anchor_error``) and, on a pipe, radius (+- ``pipe_radius_error``),
    built as a campaign builds its belief
    (:func:`~tetherland.campaign.perturb.apply_perturbation`), the rotor commands of the
    taut start hover and the landed inclined hover of the landing plan
    (:class:`~tetherland.planning.maneuver.ManeuverSpec`, the believed ground effect and
    the cable-offset torque included; the takeoff flies the same two hovers) and their
    margin min(f_i - (f_min + control_margin), f_max - control_margin - f_i). The plan's
    precheck (:func:`~tetherland.planning.maneuver.precheck`) refuses a belief whose margin
    is below 0: the robot does not fly. (The surface's offset along its normal and the
    anchor's error along the surface move the belief without changing these hovers.)
    ``-inf`` when a corner's hover does not exist.
    """

    def corners(half: float) -> tuple[float, ...]:
        return (0.0,) if half == 0 else (-half, half)

    radii = corners(bounds.pipe_radius_error) if scenario.surface.kind == "pipe" else (0.0,)
    least = math.inf
    for dm, ds, dh, dr in itertools.product(
        corners(bounds.mass_rel), corners(bounds.slope_error_deg), corners(bounds.anchor_error),
        radii,
    ):  # fmt: skip
        p = Perturbation(mass_factor=1.0 + dm, slope_error_deg=ds, anchor_error_S=(0.0, 0.0, dh),
                         pipe_radius_error=dr)  # fmt: skip
        belief = apply_perturbation(scenario, p)[1]
        spec = ManeuverSpec.from_scenario(belief, Maneuver.LANDING)
        for which in ("start", "final"):
            try:
                f_R, f_L = spec.hover(which)
                phi, theta = spec.outputs(which)
                thrusts = spec.hover_rotor_thrusts(which)[None, :]
            except SingularityError:
                return -math.inf
            if f_R <= 0.0 or f_L < 0.0:
                return -math.inf
            command = spec.rotor_commands(thrusts, phi, theta)[0]
            least = min(least, float(command.min()) - spec.f_lo, spec.f_hi - float(command.max()))
    return least


def gust_deviation(scenario: Scenario, bounds: BeliefBounds, dt: float = 1e-3) -> float:
    """Largest deviation [m] of the free-flight position loop from its reference under the
    largest wind gust of ``bounds``.

    The loop of :class:`tetherland.control.position.PositionController` (the scenario's
    ``controller.free_flight`` gains: k_x = w_n^2, k_v = 2 zeta w_n, k_i) commands the
    force m_b (-k_x e - k_v de/dt - k_i int e) with the believed mass m_b; the rotors
    produce it scaled by the thrust-coefficient error, and the true mass m accelerates
    under it and under the gust force f(t), the raised cosine of peak ``wind_gust_force``
    over ``wind_gust_duration`` (as a campaign draws it,
    :class:`tetherland.campaign.perturb.Gust`). Along the gust, with x = (int e, e, de/dt),

        dx/dt = (x_2, x_3, -rho (k_i x_1 + k_x x_2 + k_v x_3) + f(t) / m)

    with rho = (m_b / m)(true-to-commanded thrust), to first order in the errors within
    :meth:`BeliefBounds.thrust_scale` (both ends are flown). The largest |e| over the
    gust and its decay is returned (the linear loop discretised exactly with a zero-order
    hold of f over ``dt`` [s]); the attitude loop is taken as instantaneous.
    """
    force = bounds.wind_gust_force
    if force <= 0.0:
        return 0.0
    gains = scenario.controller.free_flight
    wn, zeta = gains.position_frequency, gains.position_damping
    k_x, k_v, k_i = wn * wn, 2.0 * zeta * wn, gains.position_integral
    mass, duration = scenario.vehicle.mass, bounds.wind_gust_duration
    horizon = duration + 12.0 / (zeta * wn)  # the gust and the decay of its error
    steps = math.ceil(horizon / dt)
    t_mid = (np.arange(steps) + 0.5) * dt
    wave = 0.5 * force * (1.0 - np.cos(2.0 * np.pi * t_mid / duration))
    f = np.where(t_mid < duration, wave, 0.0)
    worst = 0.0
    for rho in sorted(set(bounds.thrust_scale())):
        A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [-rho * k_i, -rho * k_x, -rho * k_v]])
        M = np.zeros((4, 4))
        M[:3, :3], M[2, 3] = A * dt, dt / mass
        E = expm(M)
        Phi, gamma = E[:3, :3], E[:3, 3]
        x = np.zeros(3)
        for fk in f:
            x = Phi @ x + gamma * fk
            worst = max(worst, abs(float(x[1])))
    return worst


def _slope_azimuth(surface: Surface) -> tuple[float, float]:
    """Slope beta and downhill azimuth of ``surface`` [rad] (x_S gives it on the level)."""
    z = surface.z_S
    beta = math.acos(max(-1.0, min(1.0, float(z[2]))))
    x = surface.x_S if math.hypot(z[0], z[1]) < 1e-9 else z
    return beta, math.atan2(float(x[1]), float(x[0]))


def true_surfaces(believed: Surface, bounds: BeliefBounds) -> list[Surface]:
    """The true surfaces at the corners of the surface errors, seen from the belief.

    The true surface is the believed one tilted by -/+ the slope and azimuth errors about
    its origin, moved by -/+ the offset error along its normal (a pipe's radius by -/+ its
    error): 2 x 2 x 2 (x 2) corners.
    """
    beta, az = _slope_azimuth(believed)
    d_beta, d_az = math.radians(bounds.slope_error_deg), math.radians(bounds.azimuth_error_deg)
    radii = [believed.pipe_radius]
    if believed.kind == "pipe":
        radii = [believed.pipe_radius + s * bounds.pipe_radius_error for s in (-1.0, 1.0)]
    out = []
    for sb, sa, so, radius in itertools.product((-1.0, 1.0), (-1.0, 1.0), (-1.0, 1.0), radii):
        R_WS = surface_frame_from_slope(min(max(beta + sb * d_beta, 0.0), math.pi), az + sa * d_az)
        origin = believed.origin + so * bounds.surface_offset_error * R_WS[:, 2]
        out.append(Surface(origin, R_WS, believed.kind, radius, believed.friction,
                           believed.f_N_min))  # fmt: skip
    return out


PassOf = Callable[[Scenario], tuple[LandingGeometry, HookingPass]]
"""The hooking pass a scenario flies, with the geometry it is planned on."""


def scenario_pass(scenario: Scenario) -> tuple[LandingGeometry, HookingPass]:
    """``scenario``'s own hooking pass (:func:`~tetherland.mission.hooking.hooking_pass`)."""
    geo = LandingGeometry.from_scenario(scenario)
    return geo, hooking_pass(scenario, geo)


def belief_corners(scenario: Scenario, bounds: BeliefBounds) -> list[Scenario]:
    """Believed scenarios at the corners of the anchor-height and mass errors, built as a
    campaign builds its belief (:func:`~tetherland.campaign.perturb.apply_perturbation`);
    only the mass of an elastic cable changes the pass (its stretch)."""
    masses = (1.0,)
    if scenario.tether.effective_axial_stiffness is not None and bounds.mass_rel > 0:
        masses = (1.0 - bounds.mass_rel, 1.0 + bounds.mass_rel)
    heights = (0.0,) if bounds.anchor_error == 0 else (-bounds.anchor_error, bounds.anchor_error)
    return [
        apply_perturbation(scenario, Perturbation(mass_factor=m, anchor_error_S=(0.0, 0.0, e)))[1]
        for m in masses
        for e in heights
    ]


def robust_pass_clearance(
    scenario: Scenario, bounds: BeliefBounds, pass_of: PassOf = scenario_pass
) -> float:
    """Least distance of the vehicle from the true surface along the hooking pass the robot
    flies when its belief is off by ``bounds`` [m] (negative: it would touch).

    For every believed anchor height and mass (:func:`belief_corners`) the believed pass
    (``pass_of``) is shifted by -/+ ``anchor_error`` along x_S and y_S (the believed anchor's
    lateral error) and its points' distance from every corner of :func:`true_surfaces`
    is taken with the vehicle's collision shape
    (:func:`~tetherland.analysis.clearance.level_vehicle_distance`), with the vehicle also
    pushed horizontally towards the surface by the gust deviation (:func:`gust_deviation`).
    """
    clearance = math.inf
    gust = gust_deviation(scenario, bounds)
    for belief in belief_corners(scenario, bounds):
        geo, hooking = pass_of(belief)
        count = PIPE_SAMPLES if geo.surface.kind == "pipe" else 2
        points = hooking.points(count)
        e = bounds.anchor_error
        signs = ((-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)) if e > 0 else ((0.0, 0.0),)
        shifts = [e * (sx * geo.surface.x_S + sy * geo.surface.y_S) for sx, sy in signs]
        for truth in true_surfaces(geo.surface, bounds):
            pushes = [gust * h for h in _towards(truth)] if gust > 0 else [np.zeros(3)]
            for shift in shifts:
                for push in pushes:
                    for p in points:
                        q = p + shift + push
                        clearance = min(
                            clearance, level_vehicle_distance(scenario, truth, q, hooking.yaw)
                        )
    return float(clearance)


def _towards(surface: Surface) -> list[np.ndarray]:
    """Horizontal unit directions in which a gust pushes the vehicle closest to ``surface``:
    against a plane's normal (the distance from a plane is linear in the push, so that
    direction is the worst), else every 45 deg."""
    z = surface.z_S
    h = np.array([-z[0], -z[1], 0.0])
    if surface.kind == "plane":
        n = float(np.linalg.norm(h))
        return [h / n] if n > 1e-9 else [np.zeros(3)]
    angles = np.radians(np.arange(0.0, 360.0, 45.0))
    return [np.array([math.cos(a), math.sin(a), 0.0]) for a in angles]
