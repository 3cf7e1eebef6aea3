"""A scenario: every parameter of one experiment, validated across sections."""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field, field_validator, model_validator

from tetherland import surface as geo
from tetherland.config.aero import AeroConfig
from tetherland.config.base import Section
from tetherland.config.checks import (
    check_name,
    check_rates,
    check_tension_threshold,
    check_timing,
)
from tetherland.config.control import ControllerConfig
from tetherland.config.estimation import EstimatorConfig
from tetherland.config.faults import FaultsConfig
from tetherland.config.mechanism import MechanismConfig
from tetherland.config.mission import MissionConfig
from tetherland.config.perching import PerchingConfig
from tetherland.config.perturbation import PerturbationConfig
from tetherland.config.physical import AnchorConfig, SurfaceConfig, TetherConfig, VehicleConfig
from tetherland.config.planning import PlannerConfig
from tetherland.config.sensors import SensorsConfig
from tetherland.config.simulation import SimConfig
from tetherland.config.verdict import VerdictConfig, spin_down_time

ON_SURFACE_TOL = 1e-3
"""Tolerance for a point to count as lying on (or at height h_A above) the surface [m]."""


MAGNET_CABLE_C_DT = 0.8
"""Largest c dt / m of the elastic cable's damping c on the magnet of mass m [-]."""
MAGNET_CABLE_W_DT = 1.5
"""Largest sqrt(k/m) dt of the elastic cable's stiffness k on the magnet of mass m [-]."""


class Scenario(Section):
    """One experiment: vehicle, tether, surface, anchor, sensors, planner, controller,
    mission and simulation settings. Load it with :func:`tetherland.config.load_scenario`."""

    name: str = Field("custom", min_length=1, max_length=100)
    """Short identifier of the scenario: a label (output folders are named after it), no
    path separators, ``.``, ``..`` or control characters."""
    description: str = ""
    """One-line description."""
    vehicle: VehicleConfig = VehicleConfig()
    tether: TetherConfig = TetherConfig()
    surface: SurfaceConfig = SurfaceConfig()
    anchor: AnchorConfig = AnchorConfig()
    sensors: SensorsConfig = SensorsConfig()
    planner: PlannerConfig = PlannerConfig()
    controller: ControllerConfig = ControllerConfig()
    estimator: EstimatorConfig = EstimatorConfig()
    """What the robot's state estimator models (its belief of the rotors near surfaces)."""
    mission: MissionConfig = MissionConfig()
    sim: SimConfig = SimConfig()
    perturbation: PerturbationConfig = PerturbationConfig()
    perching: PerchingConfig = PerchingConfig()
    verdict: VerdictConfig = VerdictConfig()
    faults: FaultsConfig = FaultsConfig()
    """Injected faults (the plant's truth; the robot's belief never has them)."""
    aero: AeroConfig = AeroConfig()
    """Rotors near surfaces and rotor drag (the plant's truth)."""
    mechanism: MechanismConfig = MechanismConfig()
    """The hook and the anchoring mechanism (docs/mechanism.md)."""

    @model_validator(mode="after")
    def _hook_within_reach(self) -> Scenario:
        # the point hook's drop and capture disk (the disk and the bar's hook point); the
        # magnet has neither: its boom is checked against the cable below
        t = self.tether
        if self.mechanism.kind != "magnet" and t.hook_drop + t.capture_radius >= t.length:
            raise ValueError(
                f"tether.hook_drop + capture_radius = {t.hook_drop + t.capture_radius:g} m must "
                f"be < length = {t.length} m (the cable must be slack when the hook catches)"
            )
        return self

    @model_validator(mode="after")
    def _magnet_mechanism(self) -> Scenario:
        m = self.mechanism
        if m.kind != "magnet":
            return self
        if abs(self.anchor.h_A - m.magnet_eye_height) > 1e-9:
            raise ValueError(
                f"anchor.h_A = {self.anchor.h_A:g} m must equal mechanism.plate_thickness + "
                f"magnet_thickness = {m.magnet_eye_height:g} m for mechanism.kind = "
                '"magnet" (the anchor is the cable\'s eye on the held magnet; h_A = 0 is '
                "replaced by it)"
            )
        t = self.tether
        if t.stiffness is None or t.segments > 0:
            raise ValueError(
                'mechanism.kind = "magnet" needs the massless elastic cable: a tether.material '
                "other than ideal (or tether.axial_stiffness) and tether.segments = 0"
            )
        # the massless elastic cable pulls the magnet explicitly (sim.cable.ElasticCable):
        # a step must resolve the magnet bouncing on it (a 20 g magnet on the default
        # line diverged while it hung on it)
        dt, k = self.sim.timestep, t.stiffness
        c_dt = t.damping(self.vehicle.mass) * dt / m.magnet_mass
        w_dt = math.sqrt(k / m.magnet_mass) * dt
        if c_dt > MAGNET_CABLE_C_DT or w_dt > MAGNET_CABLE_W_DT:
            raise ValueError(
                f"mechanism.magnet_mass = {m.magnet_mass:g} kg is too light for the cable at "
                f"sim.timestep = {dt:g} s: c dt / m = {c_dt:.2f} (at most "
                f"{MAGNET_CABLE_C_DT:g}) and sqrt(k/m) dt = {w_dt:.2f} (at most "
                f"{MAGNET_CABLE_W_DT:g}), k and c the tether's stiffness and damping"
            )
        if m.boom_length >= t.length:
            raise ValueError(
                f"mechanism.boom_length = {m.boom_length:g} m must be < tether.length = "
                f"{t.length:g} m (the cable from the attachment to the clipped magnet is slack)"
            )
        # the boom's reach beyond the airframe needs the airframe's geometry
        # (tetherland.models): checked by the plan stage (mission.plan.plan_mission)
        return self

    @model_validator(mode="after")
    def _bar_mechanism(self) -> Scenario:
        m = self.mechanism
        if m.kind != "bar":
            return self
        if abs(self.anchor.h_A - m.standoff) > 1e-9:
            raise ValueError(
                f"anchor.h_A = {self.anchor.h_A:g} m must equal mechanism.standoff = "
                f"{m.standoff:g} m for mechanism.kind = \"bar\" (the anchor is the bar's axis; "
                "h_A = 0 is replaced by the standoff)"
            )
        n = self.tether.approach_direction
        if abs(n[0]) + abs(n[1]) > 1e-9 or n[2] >= 0.0:
            raise ValueError(
                f"tether.approach_direction = {list(n)} must be straight down (0, 0, -1) for "
                'mechanism.kind = "bar": the hanging hook is lowered beside the bar'
            )
        return self

    @field_validator("name")
    @classmethod
    def _label(cls, value: str) -> str:
        return check_name(value)

    @model_validator(mode="after")
    def _rates(self) -> Scenario:
        check_rates(self)  # first: the checks below count in control periods and steps
        return self

    @model_validator(mode="after")
    def _consistent_geometry(self) -> Scenario:
        v, s, a, l = self.vehicle, self.surface, self.anchor, self.tether.length
        h_R = v.h_R
        if s.kind == "pipe":
            if v.lander_half_width >= s.pipe_radius:
                raise ValueError(
                    f"surface.pipe_radius = {s.pipe_radius} m must be > "
                    f"vehicle.lander_half_width = {v.lander_half_width} m (landers must fit)"
                )
            h_R -= geo.pipe_sag(s.pipe_radius, v.lander_half_width, v.lander_radius)
        h_att = h_R + v.cable_attachment[2]
        if h_att <= 0:
            raise ValueError(
                f"vehicle.cable_attachment z = {v.cable_attachment[2]} m puts the attachment "
                f"point below the landers plane (must be > -h_R = {-h_R:g} m)"
            )
        if abs(h_att - a.h_A) >= l:
            raise ValueError(
                f"tether.length = {l} m must be > |h_att - anchor.h_A| = {abs(h_att - a.h_A):g} m, "
                "h_att = h_R + cable_attachment z (inclined hovering needs |c| < 1, eq. 6.9)"
            )
        surface = geo.Surface(
            origin=np.asarray(s.origin, dtype=float),
            R_WS=geo.surface_frame_of(s.normal, math.radians(s.slope_deg),
                                      math.radians(s.azimuth_deg)),
        )  # fmt: skip
        if a.position is not None:
            off = surface.height(a.position) - a.h_A
            if abs(off) > ON_SURFACE_TOL:
                raise ValueError(
                    f"anchor.position must lie at height anchor.h_A = {a.h_A} m above the "
                    f"surface (within {ON_SURFACE_TOL} m); it is {off:+.3g} m off"
                )
        if a.landing_point is not None:
            off = surface.height(a.landing_point)
            if abs(off) > ON_SURFACE_TOL:
                raise ValueError(
                    f"anchor.landing_point must lie on the surface (within {ON_SURFACE_TOL} m); "
                    f"it is {off:+.3g} m off"
                )
        return self

    @model_validator(mode="after")
    def _rest_long_enough(self) -> Scenario:
        # The judge needs the true thrust below the motors-off level for min_rest_time: the
        # motors are off for deploy_time (rest_time) from the command, less the spin-down
        # and up to a control period at each end before the log shows the change.
        need = (
            self.verdict.min_rest_time + spin_down_time(self.vehicle)
            + 2.0 / self.controller.rate_hz
        )  # fmt: skip
        for field, value in (
            ("mission.deploy_time", self.mission.deploy_time),
            ("perching.rest_time", self.perching.rest_time),
        ):
            if value < need:
                raise ValueError(
                    f"{field} = {value:g} s must be >= {need:.3g} s: verdict.min_rest_time = "
                    f"{self.verdict.min_rest_time:g} s of rest with the true thrust below the "
                    "motors-off level, plus the rotors' spin-down and two control periods"
                )
        return self

    @model_validator(mode="after")
    def _stable_tether(self) -> Scenario:
        # The elastic cable force is explicit in the plant's semi-implicit Euler step: with
        # w = sqrt(k/m_eff), stable while w dt < 2 (sqrt(zeta^2 + 1) - zeta); we keep half.
        k = self.tether.stiffness
        if k is None:
            return self
        v, t, dt = self.vehicle, self.tether, self.sim.timestep
        r2 = sum(x * x for x in v.cable_attachment)
        m_eff = 1.0 / (1.0 / v.mass + r2 / min(v.inertia))
        w_dt = (k / m_eff) ** 0.5 * dt
        zeta = t.damping_ratio
        limit = (zeta * zeta + 1.0) ** 0.5 - zeta
        if w_dt > limit:
            raise ValueError(
                f"tether.axial_stiffness: EA = {t.effective_axial_stiffness:g} N (k = EA/l = "
                f"{k:g} N/m) is too stiff for sim.timestep = {dt:g} s: sqrt(k/m) dt = "
                f"{w_dt:.3g} must be <= {limit:.3g} at damping_ratio {zeta:g}; use a smaller "
                'sim.timestep, a softer cable or tether.material = "ideal"'
            )
        return self

    @model_validator(mode="after")
    def _cross_checks(self) -> Scenario:
        check_timing(self)  # tetherland.config.checks
        check_tension_threshold(self)
        return self
