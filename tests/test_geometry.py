"""Frames and landing geometry (docs/theory.md section 3): analytic values and properties."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tetherland.errors import SingularityError
from tetherland.geometry import (
    anchor_for_landing_point,
    anchor_frame,
    hover_cosine,
    inclined_hover_direction,
    inclined_landing_point,
    landing_geometry,
    link_angles,
    link_direction,
    link_frame,
    link_jacobian,
    theta_A_from_z_B,
)
from tetherland.surface import (
    Surface,
    normal_from_slope,
    pipe_sag,
    surface_frame,
    surface_frame_from_slope,
)

angles = st.floats(-math.pi, math.pi, allow_nan=False)
slopes = st.floats(0.0, math.pi, allow_nan=False)  # walls at pi/2, overhangs beyond
coords = st.floats(-5.0, 5.0, allow_nan=False)
unit_c = st.floats(-0.95, 0.95, allow_nan=False)


def assert_rotation(R: np.ndarray) -> None:
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-12)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-12)


def test_surface_frame_of_50_degree_slope():
    beta = math.radians(50)
    R = surface_frame(normal_from_slope(beta))
    x_S, y_S, z_S = R.T
    assert x_S[2] == pytest.approx(-math.sin(beta))  # x_S points downhill
    assert z_S[2] == pytest.approx(math.cos(beta))
    assert y_S[2] == pytest.approx(0.0)
    np.testing.assert_allclose(x_S, [math.cos(beta), 0, -math.sin(beta)], atol=1e-15)


def test_horizontal_surface_frame_is_world():
    np.testing.assert_array_equal(surface_frame([0, 0, 3.0]), np.eye(3))
    np.testing.assert_array_equal(surface_frame_from_slope(0.0, 0.0), np.eye(3))


def test_a_downward_normal_is_a_ceiling_not_flipped_up():
    """n_S is the outward normal: -z_W is a ceiling (slope pi), the limit of azimuth 0."""
    R = surface_frame([0, 0, -2.0])
    np.testing.assert_array_equal(R, np.diag([-1.0, 1.0, -1.0]))
    np.testing.assert_allclose(R, surface_frame_from_slope(math.pi, 0.0), atol=1e-15)
    assert Surface(origin=np.zeros(3), R_WS=R).slope == pytest.approx(math.pi)


@pytest.mark.parametrize("beta_deg", [90.0, 100.0, 135.0])
def test_surface_frame_past_vertical(beta_deg: float):
    """A wall faces horizontally, an overhang faces down; x_S still points down the surface."""
    beta, az = math.radians(beta_deg), math.radians(30.0)
    R = surface_frame_from_slope(beta, az)
    x_S, y_S, z_S = R.T
    assert_rotation(R)
    assert z_S[2] == pytest.approx(math.cos(beta), abs=1e-15)  # < 0 past vertical
    assert x_S[2] == pytest.approx(-math.sin(beta), abs=1e-15)
    assert y_S[2] == 0.0
    horizontal = np.array([math.cos(az), math.sin(az), 0.0])
    assert z_S @ horizontal == pytest.approx(math.sin(beta))  # faces out along the azimuth
    assert x_S @ horizontal == pytest.approx(math.cos(beta))  # <= 0: recedes under past 90
    np.testing.assert_allclose(R, surface_frame(normal_from_slope(beta, az)), atol=1e-12)
    assert Surface(origin=np.zeros(3), R_WS=R).slope == pytest.approx(beta, abs=1e-12)


@pytest.mark.parametrize("azimuth_deg", [0.0, -70.0, 145.0])
def test_surface_and_anchor_frames_are_continuous_through_vertical(azimuth_deg: float):
    """F_S turns about y_S by the slope change (||dR||_F = sqrt(2) dbeta); F_A is the same
    frame for every slope of one azimuth (it depends only on y_S)."""
    az = math.radians(azimuth_deg)
    betas = np.linspace(0.0, math.pi, 1801)
    frames = np.array([surface_frame_from_slope(b, az) for b in betas])
    steps = np.linalg.norm(np.diff(frames, axis=0), axis=(1, 2))
    np.testing.assert_allclose(steps, math.sqrt(2) * 2 * math.sin((betas[1] - betas[0]) / 2))
    anchors = np.array([anchor_frame(R) for R in frames])
    np.testing.assert_allclose(anchors, np.broadcast_to(anchors[0], anchors.shape), atol=1e-15)
    y_S = [-math.sin(az), math.cos(az), 0.0]
    np.testing.assert_allclose(anchors[0], np.column_stack(([y_S[1], -y_S[0], 0], y_S, [0, 0, 1])))


@settings(max_examples=200, deadline=None)
@given(st.floats(1e-6, math.pi - 1e-6), angles)
def test_frame_from_normal_equals_frame_from_slope(beta: float, azimuth: float):
    np.testing.assert_allclose(
        surface_frame(normal_from_slope(beta, azimuth)),
        surface_frame_from_slope(beta, azimuth),
        atol=1e-9,
    )


def test_zero_normal_is_singular():
    with pytest.raises(SingularityError):
        surface_frame([0.0, 0.0, 0.0])


@settings(max_examples=200, deadline=None)
@given(slopes, angles)
def test_surface_and_anchor_frames_are_rotations(beta: float, azimuth: float):
    R_WS = surface_frame_from_slope(beta, azimuth)
    R_WA = anchor_frame(R_WS)
    assert_rotation(R_WS)
    assert_rotation(R_WA)
    assert R_WS[2, 0] <= 1e-12  # x_S never points uphill
    assert R_WS[2, 2] == pytest.approx(math.cos(beta))  # z_S . z_W = cos(beta), < 0 past 90
    np.testing.assert_allclose(R_WA[:, 2], [0, 0, 1])
    np.testing.assert_allclose(R_WA[:, 1], R_WS[:, 1])
    assert R_WA[2, 0] == pytest.approx(0.0, abs=1e-12)  # x_A horizontal
    assert R_WA[:, 0] @ R_WS[:, 0] == pytest.approx(math.cos(beta))  # downhill below 90 deg
    assert R_WA[:, 0] @ R_WS[:, 2] == pytest.approx(math.sin(beta))  # x_A points off the surface


@settings(max_examples=200, deadline=None)
@given(angles, st.floats(-1.5, 1.5))
def test_link_frame_is_rotation_with_design_derivatives(phi: float, delta: float):
    R = link_frame(phi, delta)
    assert_rotation(R)
    np.testing.assert_allclose(R[:, 0], link_direction(phi, delta), atol=1e-15)
    h = 1e-6
    d_phi = (link_direction(phi + h, delta) - link_direction(phi - h, delta)) / (2 * h)
    d_delta = (link_direction(phi, delta + h) - link_direction(phi, delta - h)) / (2 * h)
    np.testing.assert_allclose(d_phi, math.cos(delta) * R[:, 2], atol=1e-8)
    np.testing.assert_allclose(d_delta, -R[:, 1], atol=1e-8)
    np.testing.assert_allclose(
        link_jacobian(phi, delta, 2.0), 2.0 * np.column_stack((d_phi, d_delta)), atol=1e-7
    )


def test_link_jacobian_matches_chapter_expression():
    phi, delta, l = 0.3, -0.4, 1.7
    cp, sp, cd, sd = math.cos(phi), math.sin(phi), math.cos(delta), math.sin(delta)
    J_chapter = np.array(
        [[-l * cd * sp, -l * cp * sd], [0.0, -l * cd], [l * cd * cp, -l * sd * sp]]
    )
    np.testing.assert_allclose(link_jacobian(phi, delta, l), J_chapter, atol=1e-15)


@settings(max_examples=200, deadline=None)
@given(angles, st.floats(-1.5, 1.5))
def test_link_angles_invert_link_direction(phi: float, delta: float):
    p, d = link_angles(link_direction(phi, delta))
    assert math.cos(p - phi) == pytest.approx(1.0, abs=1e-10)
    assert d == pytest.approx(delta, abs=1e-10)


@settings(max_examples=100, deadline=None)
@given(st.floats(-1.4, 1.4), st.floats(-1.2, 1.2), st.floats(-1.2, 1.2))
def test_theta_A_recovers_tilt_in_link_plane(phi: float, delta: float, theta: float):
    # alpha in span(x_L, z_L) with atan2(x_A.alpha, z_A.alpha) = theta; z_B adds a y_L part
    x_L, y_L, z_L = link_frame(phi, delta).T
    target = np.array([math.sin(theta), 0.0, math.cos(theta)])
    basis = np.column_stack((x_L, z_L))
    coeffs, *_ = np.linalg.lstsq(basis[[0, 2]], target[[0, 2]], rcond=None)
    alpha = basis @ coeffs
    z_B = alpha + 0.3 * y_L
    assert theta_A_from_z_B(z_B, phi, delta) == pytest.approx(
        math.atan2(alpha[0], alpha[2]), abs=1e-10
    )
    if abs(delta) < 1e-12:
        assert theta_A_from_z_B(z_B, phi, delta) == pytest.approx(theta, abs=1e-10)


def test_worked_example_of_design():
    """docs/theory.md section 4: m = 1, l = 1, h_R = 0.1, h_A = 0, beta = 50 deg."""
    beta = math.radians(50)
    surface = Surface(origin=np.zeros(3), R_WS=surface_frame(normal_from_slope(beta)))
    geo = landing_geometry(surface, length=1.0, h_R=0.1, h_A=0.0)
    assert math.degrees(geo.gamma) == pytest.approx(5.739, abs=1e-3)
    assert math.degrees(geo.phi_star) == pytest.approx(-44.261, abs=1e-3)
    assert geo.phi_star == pytest.approx(geo.gamma - beta, abs=1e-12)
    assert geo.delta_star == pytest.approx(0.0, abs=1e-12)
    assert geo.theta_A_star == pytest.approx(beta, abs=1e-12)
    np.testing.assert_allclose(geo.p_L, np.zeros(3), atol=1e-12)


@settings(max_examples=200, deadline=None)
@given(slopes, angles, coords, coords, unit_c, st.floats(0.2, 3.0), st.floats(0.0, 0.3))
def test_inclined_landing_point_properties(beta, azimuth, x, y, c, length, h_R):
    R_WS = surface_frame(normal_from_slope(beta, azimuth))
    origin = np.array([0.3, -0.2, 0.1])
    surface = Surface(origin=origin, R_WS=R_WS)
    d = inclined_hover_direction(R_WS, c)
    assert np.linalg.norm(d) == pytest.approx(1.0, abs=1e-12)
    assert d @ R_WS[:, 2] == pytest.approx(c, abs=1e-12)  # (6.9)
    assert d @ R_WS[:, 1] == pytest.approx(0.0, abs=1e-12)  # (6.11): no y_S component
    # anchor placed by (6.13) for a desired point on the surface ...
    p_star = surface.project(np.array([x, y, 0.0]))
    p_A = anchor_for_landing_point(p_star, R_WS, c, length, h_R)
    h_A = surface.height(p_A)
    assert h_A == pytest.approx(h_R - c * length, abs=1e-9)
    # ... gives back p~_L = p*_L, on the surface, at cable length from the anchor
    p_L = inclined_landing_point(p_A, R_WS, c, length, h_R)
    np.testing.assert_allclose(p_L, p_star, atol=1e-9)
    assert surface.height(p_L) == pytest.approx(0.0, abs=1e-9)
    assert np.linalg.norm(p_L + h_R * R_WS[:, 2] - p_A) == pytest.approx(length, abs=1e-9)


@settings(max_examples=100, deadline=None)
@given(st.floats(0.01, 3.1), st.floats(0.0, 0.5), st.floats(0.0, 0.5), st.floats(0.6, 2.0))
def test_landing_geometry_from_anchor_and_from_point_agree(beta, h_R, h_A, length):
    surface = Surface(origin=np.zeros(3), R_WS=surface_frame_from_slope(beta, 0.4))
    by_point = landing_geometry(
        surface, length=length, h_R=h_R, h_A=h_A, landing_point=[1.0, 2.0, 0.0]
    )
    by_anchor = landing_geometry(surface, length=length, h_R=h_R, h_A=h_A, anchor=by_point.p_A)
    np.testing.assert_allclose(by_anchor.p_L, by_point.p_L, atol=1e-9)
    assert surface.height(by_point.p_A) == pytest.approx(h_A, abs=1e-9)
    # the final output reproduces d~ through the link parametrisation
    d_A = link_direction(by_point.phi_star, by_point.delta_star)
    np.testing.assert_allclose(by_point.R_WA @ d_A, by_point.d_tilde, atol=1e-12)
    np.testing.assert_allclose(
        by_point.link_end(by_point.phi_star, 0.0), by_point.p_att_landed, atol=1e-9
    )
    # phi* = gamma - beta and theta_A* = beta on every slope, overhangs included
    assert by_point.phi_star == pytest.approx(by_point.gamma - beta, abs=1e-12)
    assert by_point.theta_A_star == pytest.approx(beta, abs=1e-12)
    z_B_A = [math.sin(by_point.theta_A_star), 0.0, math.cos(by_point.theta_A_star)]
    np.testing.assert_allclose(by_point.R_WA @ z_B_A, surface.z_S, atol=1e-12)


@pytest.mark.parametrize("beta_deg", [90.0, 100.0])
def test_inclined_hover_landing_point_on_a_wall_and_an_overhang(beta_deg: float):
    """(6.8)-(6.13) past vertical: cable at the CoM, l = 0.4 m, h_R = 0.1 m, h_A = 0:
    gamma = asin(0.25) = 14.48 deg, phi* = gamma - beta, d~ at gamma above the surface."""
    beta = math.radians(beta_deg)
    surface = Surface(origin=np.zeros(3), R_WS=surface_frame_from_slope(beta))
    geo = landing_geometry(surface, length=0.4, h_R=0.1, h_A=0.0)
    gamma = math.asin(0.25)
    assert math.degrees(geo.gamma) == pytest.approx(14.4775, abs=1e-4)
    assert geo.phi_star == pytest.approx(gamma - beta, abs=1e-12)
    # d~ in F_W (the plane x_W-z_W): elevation gamma - beta from the horizontal x_A = x_W
    np.testing.assert_allclose(
        geo.d_tilde, [math.cos(gamma - beta), 0.0, math.sin(gamma - beta)], atol=1e-12
    )
    assert geo.d_tilde @ surface.z_S == pytest.approx(math.sin(gamma), abs=1e-12)
    # the anchor sits on the surface, uphill of the landing point at cable length
    assert surface.height(geo.p_A) == pytest.approx(0.0, abs=1e-12)
    assert geo.p_A[2] > geo.p_L[2]
    assert np.linalg.norm(geo.p_att_landed - geo.p_A) == pytest.approx(0.4, abs=1e-12)


def test_hover_cosine_rejects_long_offsets():
    assert hover_cosine(0.1, 0.0, 1.0) == pytest.approx(0.1)
    with pytest.raises(SingularityError, match=r"must be < l"):
        hover_cosine(1.1, 0.0, 1.0)
    with pytest.raises(SingularityError):
        hover_cosine(0.0, 1.0, 1.0)


def test_pipe_sag():
    assert pipe_sag(0.25, 0.15) == pytest.approx(0.05)  # point tips: 0.25 - 0.20
    # spherical tips of radius 1 cm: centres at R + r from the axis
    assert pipe_sag(0.25, 0.15, 0.01) == pytest.approx(0.26 - math.sqrt(0.26**2 - 0.15**2))
    with pytest.raises(SingularityError):
        pipe_sag(0.1, 0.15)


def test_attachment_offset_moves_the_anchor(slope50):
    from tetherland.config import load_scenario
    from tetherland.geometry import LandingGeometry

    rigid = 'tether.material="ideal"'  # the inextensible cable: the link is l = 1 m
    centred = LandingGeometry.from_scenario(
        load_scenario("slope50", ["vehicle.cable_attachment=[0, 0, 0]", rigid])
    )
    offset = LandingGeometry.from_scenario(load_scenario("slope50", [rigid]))
    assert centred.c == pytest.approx(0.1)
    assert offset.h_att == pytest.approx(0.07)
    assert offset.c == pytest.approx(0.07)
    # with the offset, the attachment point (not the CoM) is at cable length from the anchor
    assert np.linalg.norm(offset.p_att_landed - offset.p_A) == pytest.approx(1.0, abs=1e-12)
    assert np.linalg.norm(offset.p_R_landed - offset.p_A) != pytest.approx(1.0, abs=1e-4)
    # the default elastic cable: the same at l + s, s = f_L l/EA at f_L of (6.10)
    elastic = LandingGeometry.from_scenario(slope50)
    EA = slope50.tether.effective_axial_stiffness
    f_L = slope50.vehicle.mass * 9.81 * math.sin(elastic.surface.slope) / math.cos(elastic.gamma)
    assert elastic.stretch == pytest.approx(f_L / EA, rel=1e-12)
    assert elastic.c == pytest.approx(0.07 / (1.0 + elastic.stretch), rel=1e-12)
    assert np.linalg.norm(elastic.p_att_landed - elastic.p_A) == pytest.approx(
        1.0 + elastic.stretch, abs=1e-12
    )


def test_pipe_geometry_uses_sag(pipe60):
    from tetherland.geometry import LandingGeometry

    geo = LandingGeometry.from_scenario(pipe60)
    sag = 0.26 - math.sqrt(0.26**2 - 0.15**2)
    assert geo.h_R == pytest.approx(0.10 - sag)
    assert geo.h_att == pytest.approx(0.10 - sag - 0.03)
    assert geo.surface.slope == pytest.approx(math.radians(60))
