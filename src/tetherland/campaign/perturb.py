"""Seeded perturbations: the plant's truth versus the robot's belief (issue 7, item 2).

The scenario as given is the truth that the plant simulates. Each run draws model and
pose errors; the *belief* scenario (used by the planner, controllers and estimator) has
them. Sensor noise, mocap dropouts and wind gusts act on the plant. The errors come from
the run's ``perturbation`` stream, the gusts from its ``wind`` stream
(:mod:`tetherland.randomness`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from tetherland.config import PerturbationConfig, Scenario, scenario_from_dict
from tetherland.geometry import LandingGeometry
from tetherland.randomness import RandomSource
from tetherland.surface import normal_from_slope, surface_frame


@dataclass(frozen=True)
class Gust:
    """A horizontal wind gust: raised-cosine force profile in F_W.

    Attributes
    ----------
    t_start : float
        Start time [s].
    duration : float
        Length [s].
    force_W : (float, float)
        Peak horizontal force (x, y) [N].
    """

    t_start: float
    duration: float
    force_W: tuple[float, float]

    def force(self, t: float) -> tuple[float, float]:
        """Gust force at time ``t`` [N] (zero outside the gust)."""
        s = (t - self.t_start) / self.duration
        if not 0.0 <= s <= 1.0:
            return (0.0, 0.0)
        k = 0.5 * (1.0 - math.cos(2.0 * math.pi * s))
        return (k * self.force_W[0], k * self.force_W[1])


@dataclass(frozen=True)
class Perturbation:
    """One draw of everything that goes wrong (belief = truth x factor, + offsets).

    Attributes
    ----------
    mass_factor, inertia_factor, thrust_coefficient_factor, motor_time_constant_factor
        Believed / true parameter ratios [-].
    slope_error_deg, azimuth_error_deg
        Believed minus true surface orientation [deg].
    anchor_error_S : (float, float, float)
        Believed minus true anchor position along x_S, y_S (of the true surface) and its
        believed minus true height h_A above the (believed) surface [m].
    surface_offset : float
        Believed minus true position of the surface along its believed normal [m].
    pipe_radius_error : float
        Believed minus true pipe radius (0 for a plane) [m].
    noise_scale : float
        Plant sensor-noise multiplier [-].
    mocap_dropout_rate, mocap_dropout_duration
        Plant mocap dropouts [1/s], [s].
    gusts : tuple of Gust
    """

    mass_factor: float = 1.0
    inertia_factor: float = 1.0
    thrust_coefficient_factor: float = 1.0
    motor_time_constant_factor: float = 1.0
    slope_error_deg: float = 0.0
    azimuth_error_deg: float = 0.0
    anchor_error_S: tuple[float, float, float] = (0.0, 0.0, 0.0)
    surface_offset: float = 0.0
    pipe_radius_error: float = 0.0
    noise_scale: float = 1.0
    mocap_dropout_rate: float = 0.0
    mocap_dropout_duration: float = 0.0
    gusts: tuple[Gust, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """Flat JSON-ready record (gusts summarised by count and peak force)."""
        d = asdict(self)
        gusts = d.pop("gusts")
        d["anchor_error_x_S"], d["anchor_error_y_S"], d["anchor_error_z_S"] = d.pop(
            "anchor_error_S"
        )
        d["gust_count"] = len(gusts)
        d["gust_peak_N"] = max((math.hypot(*g["force_W"]) for g in gusts), default=0.0)
        return d


def sample_gusts(
    c: PerturbationConfig, rng: np.random.Generator, horizon: float = 120.0
) -> tuple[Gust, ...]:
    """Wind gusts over ``horizon`` [s]: Poisson start times, uniform peak force and heading.

    Drawn in time order, so a longer horizon keeps every gust of a shorter one and adds
    the later ones."""
    gusts = []
    if c.wind_gust_rate > 0 and c.wind_gust_force > 0:
        t = float(rng.exponential(1.0 / c.wind_gust_rate))
        while t < horizon:
            magnitude = float(rng.uniform(0.0, c.wind_gust_force))
            heading = float(rng.uniform(0.0, 2.0 * math.pi))
            gusts.append(
                Gust(
                    t,
                    c.wind_gust_duration,
                    (magnitude * math.cos(heading), magnitude * math.sin(heading)),
                )
            )
            t += c.wind_gust_duration + float(rng.exponential(1.0 / c.wind_gust_rate))
    return tuple(gusts)


def sample_perturbation(
    scenario: Scenario, random: RandomSource, horizon: float | None = None
) -> Perturbation:
    """Draw one perturbation from the scenario's ``[perturbation]`` ranges.

    The gusts come from ``random``'s ``wind`` stream (over ``horizon`` [s]; None: the
    whole run, ``mission.time_limit``), everything else from its ``perturbation``
    stream, so that the wind settings leave the model errors of a seed unchanged. Within
    the stream the errors added later are drawn last, so that a seed keeps its earlier
    draws.
    """
    c = scenario.perturbation
    span = scenario.mission.time_limit if horizon is None else horizon
    gusts = sample_gusts(c, random.stream("wind"), span)
    rng = random.stream("perturbation")

    def rel(half: float) -> float:
        return float(1.0 + rng.uniform(-half, half))

    def sym(half: float) -> float:
        return float(rng.uniform(-half, half))

    mass, inertia = rel(c.mass_rel), rel(c.inertia_rel)
    thrust, motor = rel(c.thrust_coefficient_rel), rel(c.motor_time_constant_rel)
    slope, azimuth = sym(c.slope_error_deg), sym(c.azimuth_error_deg)
    anchor_x, anchor_y = sym(c.anchor_error), sym(c.anchor_error)
    noise = float(rng.uniform(c.noise_scale_min, c.noise_scale_max))
    anchor_z = sym(c.anchor_error)
    offset = sym(c.surface_offset_error)
    pipe = sym(c.pipe_radius_error) if scenario.surface.kind == "pipe" else 0.0
    return Perturbation(
        mass_factor=mass,
        inertia_factor=inertia,
        thrust_coefficient_factor=thrust,
        motor_time_constant_factor=motor,
        slope_error_deg=slope,
        azimuth_error_deg=azimuth,
        anchor_error_S=(anchor_x, anchor_y, anchor_z),
        surface_offset=offset,
        pipe_radius_error=pipe,
        noise_scale=noise,
        mocap_dropout_rate=c.mocap_dropout_rate,
        mocap_dropout_duration=c.mocap_dropout_duration,
        gusts=gusts,
    )


def apply_perturbation(truth: Scenario, p: Perturbation) -> tuple[Scenario, Scenario]:
    """Return (plant scenario, belief scenario) for a perturbation.

    The plant scenario is ``truth`` with the plant-side disturbances (noise scale, mocap
    dropouts); the belief has the model errors and a surface and anchor estimated with
    errors in every direction: the believed surface is tilted (slope, azimuth) about the
    true origin and moved ``surface_offset`` along its normal, a pipe's radius is off by
    ``pipe_radius_error``, and the believed anchor is off along x_S and y_S and lies at
    h_A + ``anchor_error_S[2]`` above the believed surface. A believed anchor is never
    behind the believed surface (the mechanism stands on it): a height below zero is
    believed zero. With ``mechanism.kind = "bar"`` the anchor is the bar's axis, so the
    believed bar's ``standoff`` is the believed h_A (at least ``bar_radius + 2 hook_radius``
    + 1 mm); the plant keeps the true bar. With ``mechanism.kind = "magnet"`` the anchor is
    the cable's eye on the held magnet, ``plate_thickness + magnet_thickness`` above the
    surface: the robot knows its own magnet, so the error is the plate's, whose believed
    thickness is the believed h_A less the magnet (at least 1 mm); the plant keeps the
    true plate.
    """
    plant = truth.model_dump(mode="python")
    sensors = plant["sensors"]
    sensors["noise_scale"] = truth.sensors.noise_scale * p.noise_scale
    sensors["mocap"]["dropout_rate"] = p.mocap_dropout_rate
    sensors["mocap"]["dropout_duration"] = p.mocap_dropout_duration

    belief = truth.model_dump(mode="python")
    v = belief["vehicle"]
    v["mass"] = truth.vehicle.mass * p.mass_factor
    v["inertia"] = tuple(j * p.inertia_factor for j in truth.vehicle.inertia)
    v["thrust_coefficient"] = truth.vehicle.thrust_coefficient * p.thrust_coefficient_factor
    v["motor_time_constant"] = truth.vehicle.motor_time_constant * p.motor_time_constant_factor

    geo = LandingGeometry.from_scenario(truth)
    beta = min(max(math.degrees(geo.surface.slope) + p.slope_error_deg, 0.0), 180.0)
    az = truth.surface.azimuth_deg + p.azimuth_error_deg
    if truth.surface.normal is not None:
        n = np.asarray(truth.surface.normal, float)
        az = math.degrees(math.atan2(n[1], n[0])) + p.azimuth_error_deg
    s = belief["surface"]
    s["normal"] = None
    s["slope_deg"], s["azimuth_deg"] = beta, ((az + 180.0) % 360.0) - 180.0
    R_WS = surface_frame(normal_from_slope(math.radians(beta), math.radians(s["azimuth_deg"])))
    z_S = R_WS[:, 2]
    origin = np.asarray(truth.surface.origin, float) + p.surface_offset * z_S
    s["origin"] = tuple(origin)
    if truth.surface.kind == "pipe":
        s["pipe_radius"] = truth.surface.pipe_radius + p.pipe_radius_error
    e_x, e_y, e_h = p.anchor_error_S
    p_A = geo.p_A + geo.surface.x_S * e_x + geo.surface.y_S * e_y
    # the believed anchor at its believed height above the believed surface
    h_A = max(truth.anchor.h_A + e_h, 0.0)
    # the bar's standoff or the magnet's plate is what gives the believed height
    h_A, fields = truth.mechanism.anchor_height_fields(h_A)
    belief["mechanism"].update(fields)
    p_A = p_A - (z_S @ (p_A - origin) - h_A) * z_S
    belief["anchor"] = {"position": tuple(p_A), "landing_point": None, "h_A": h_A}
    return scenario_from_dict(plant, truth.name), scenario_from_dict(belief, truth.name)
