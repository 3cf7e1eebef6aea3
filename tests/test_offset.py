"""The cable attachment offset r_att exact in the geometry and the models (issue 12;
docs/theory.md sections 3.4 and 4.6)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.geometry import (
    LandingGeometry,
    StretchedLanding,
    attachment_in_plane,
    landed_rotation,
    landing_geometry,
)
from tetherland.sim.plant import Plant

SIDEWAYS = "vehicle.cable_attachment=[0.03,0,-0.03]"
ACROSS = "vehicle.cable_attachment=[0,0.04,-0.03]"


@pytest.mark.parametrize("offset", [SIDEWAYS, ACROSS, "vehicle.cable_attachment=[-0.05,0.02,0]"])
def test_landed_attachment_point_is_one_cable_length_from_the_anchor(offset: str) -> None:
    """Landed at p_L with z_B = z_S, the real attachment point p_R + R_WB r_att lies on
    the link end p_A + l d~ (l from the anchor, in the fall-line plane)."""
    sc = load_scenario("slope50", [offset])
    geo = LandingGeometry.from_scenario(sc)
    R_WB = landed_rotation(geo.surface.R_WS)
    p_att = geo.p_R_landed + R_WB @ np.asarray(sc.vehicle.cable_attachment)
    np.testing.assert_allclose(p_att, geo.p_att_landed, atol=1e-12)
    np.testing.assert_allclose(p_att, geo.p_A + geo.length * geo.d_tilde, atol=1e-12)
    assert np.linalg.norm(p_att - geo.p_A) == pytest.approx(sc.tether.length, abs=1e-12)
    # the landing point is where the scenario asked for (the anchor moved instead)
    np.testing.assert_allclose(geo.p_L, geo.surface.project(geo.surface.origin), atol=1e-12)
    # and the in-plane part is the offset's x/y in F_S (heading 0: x_B = x_S)
    r = sc.vehicle.cable_attachment
    np.testing.assert_allclose(
        geo.r_par_W, r[0] * geo.surface.x_S + r[1] * geo.surface.y_S, atol=1e-15
    )


def test_explicit_anchor_moves_the_landing_point_by_the_in_plane_offset() -> None:
    sc = load_scenario("slope50")
    geo0 = LandingGeometry.from_scenario(sc)
    r_par = attachment_in_plane(geo0.surface.R_WS, (0.03, -0.02, -0.03), heading=0.4)
    # the heading turns the offset about z_S: its length stays, z_S part is dropped
    assert np.linalg.norm(r_par) == pytest.approx(math.hypot(0.03, 0.02), rel=1e-12)
    assert abs(r_par @ geo0.surface.z_S) < 1e-15
    geo = landing_geometry(
        geo0.surface, length=geo0.length, h_R=geo0.h_R, h_att=geo0.h_att, h_A=geo0.h_A,
        anchor=geo0.p_A, r_par_W=r_par,
    )  # fmt: skip
    np.testing.assert_allclose(geo.p_L, geo0.p_L - r_par, atol=1e-12)
    assert np.linalg.norm(geo.p_att_landed - geo.p_A) == pytest.approx(geo.length, abs=1e-12)


@pytest.mark.parametrize("extra", [[], ['tether.material="nylon"']])
def test_plant_landed_attachment_point_with_a_sideways_offset(extra: list[str]) -> None:
    """The MuJoCo plant, landed at the geometry's p_L (frictionless slope, motors off, the
    cable alone holds it): its attachment site is l (plus the stretch f_L l/EA) from the
    anchor, at the stretched geometry's landed attachment point. Before the exact
    geometry it came to rest 1.03 m from the anchor for l = 1 m with this offset."""
    sc = load_scenario("slope50", [SIDEWAYS, "surface.friction=0", *extra])
    plant = Plant(sc)
    sl = StretchedLanding.from_scenario(sc)
    start = plant.landed_state()
    plant.reset(start, cable_engaged=True)
    D0 = np.linalg.norm(plant.attachment_point() - plant.layout.geometry.p_A)
    assert D0 == pytest.approx(sc.tether.length, abs=1e-9)  # placed exactly on the link end
    plant.step(5000)
    D = np.linalg.norm(plant.attachment_point() - plant.layout.geometry.p_A)
    assert D == pytest.approx(sc.tether.length + sl.stretch, abs=3e-4)
    np.testing.assert_allclose(plant.attachment_point(), sl.geometry.p_att_landed, atol=3e-3)
