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
    the link end p_A + (l + s) d~ (l + s from the anchor, in the fall-line plane; s = f_L
    l/EA the stretch of the elastic cable at the landed hover's tension (6.10))."""
    sc = load_scenario("slope50", [offset])
    geo = LandingGeometry.from_scenario(sc)
    l, EA = sc.tether.length, sc.tether.effective_axial_stiffness
    f_L = sc.vehicle.mass * 9.81 * math.sin(geo.surface.slope) / math.cos(geo.gamma)
    assert geo.stretch == pytest.approx(f_L * l / EA, rel=1e-12)
    assert geo.c == pytest.approx(geo.h_att / (l + geo.stretch), rel=1e-12)  # h_A = 0
    R_WB = landed_rotation(geo.surface.R_WS)
    p_att = geo.p_R_landed + R_WB @ np.asarray(sc.vehicle.cable_attachment)
    np.testing.assert_allclose(p_att, geo.p_att_landed, atol=1e-12)
    np.testing.assert_allclose(p_att, geo.p_A + (l + geo.stretch) * geo.d_tilde, atol=1e-12)
    assert np.linalg.norm(p_att - geo.p_A) == pytest.approx(geo.link_length, abs=1e-12)
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
        anchor=geo0.p_A, r_par_W=r_par, stretch=geo0.stretch,
    )  # fmt: skip
    np.testing.assert_allclose(geo.p_L, geo0.p_L - r_par, atol=1e-12)
    assert np.linalg.norm(geo.p_att_landed - geo.p_A) == pytest.approx(
        geo0.length + geo0.stretch, abs=1e-12
    )


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
    # placed exactly on the stretched link end, l + s
    assert D0 == pytest.approx(sc.tether.length + sl.stretch, abs=1e-9)
    plant.step(5000)
    D = np.linalg.norm(plant.attachment_point() - plant.layout.geometry.p_A)
    assert D == pytest.approx(sc.tether.length + sl.stretch, abs=1e-6)
    # it rests where the layout put it (5 um: the slope contact's softness; 6.3 mm with
    # nylon when the geometry was that of the unstretched cable)
    np.testing.assert_allclose(plant.attachment_point(), sl.geometry.p_att_landed, atol=5e-5)


# -- the exact 3D and planar models with an offset ---------------------------------------

from tetherland.geometry import link_direction, link_jacobian  # noqa: E402
from tetherland.models.integrators import rk4  # noqa: E402
from tetherland.models.planar import CASADI, NUMPY, PlanarParams, planar_offset_accelerations  # noqa: E402
from tetherland.models.tethered import (  # noqa: E402
    link_dynamics,
    offset_body_dynamics,
    tethered_body_rhs,
)
from tetherland.rotations import quat_to_rotmat, rotmat_to_quat, rotvec_to_quat  # noqa: E402

M, L, J3 = 1.0, 1.0, np.array([0.015, 0.017, 0.025])
R_WA = np.eye(3)


def _energy(x: np.ndarray, r: np.ndarray) -> float:
    """1/2 m |v_R|^2 + 1/2 w.J w + m g z_R with p_R = l d - R r (anchor at the origin)."""
    R = quat_to_rotmat(x[4:8])
    w = x[8:11]
    p_att = L * link_direction(x[0], x[1])
    v_att = link_jacobian(x[0], x[1], L) @ x[2:4]
    p_R = p_att - R @ r
    v_R = v_att - R @ np.cross(w, r)
    return 0.5 * M * v_R @ v_R + 0.5 * w @ (J3 * w) + M * 9.81 * p_R[2]


def test_offset_body_conserves_energy_without_inputs() -> None:
    """Unpowered, the cable constraint does no work: energy is conserved (the coupling
    terms omega x (omega x r) and d'' are right), to the RK4 error."""
    rng = np.random.default_rng(3)
    r = np.array([0.03, -0.02, -0.05])
    q = rotvec_to_quat(rng.normal(0, 0.4, 3))
    x = np.concatenate(([-0.9, 0.2, 0.8, -0.5], q, rng.normal(0, 2.0, 3)))
    E0 = _energy(x, r)

    def run(r_model: np.ndarray | None) -> np.ndarray:
        y = x.copy()

        def f(z: np.ndarray, _u: object) -> np.ndarray:
            return tethered_body_rhs(z, 0.0, np.zeros(3), M, L, J3, R_WA, r_att_B=r_model)

        for _ in range(1000):
            y = rk4(f, y, None, 1e-3)
            y[4:8] /= np.linalg.norm(y[4:8])
        return y

    assert abs(_energy(run(r), r) - E0) < 1e-7 * (abs(E0) + 1.0)
    # the chapter's model (no coupling terms) does not conserve the offset body's energy
    assert abs(_energy(run(None), r) - E0) > 1e-4


def test_offset_body_reduces_to_the_chapter_model_at_zero_offset() -> None:
    rng = np.random.default_rng(5)
    for _ in range(5):
        q = rotvec_to_quat(rng.normal(0, 0.5, 3))
        x = np.concatenate((rng.uniform(-1, 1, 2), rng.normal(0, 1, 2), q, rng.normal(0, 1, 3)))
        f_R, tau = rng.uniform(5, 12), rng.normal(0, 0.1, 3)
        acc = offset_body_dynamics(x, f_R, tau, M, L, J3, R_WA, np.zeros(3))
        z_B = quat_to_rotmat(q)[:, 2]
        from tetherland.models.tethered import thrust_in_link_frame

        ref = link_dynamics(*x[:4], thrust_in_link_frame(f_R * z_B, x[0], x[1]), M, L)
        assert acc.phi_ddot == pytest.approx(ref.phi_ddot, abs=1e-12)
        assert acc.delta_ddot == pytest.approx(ref.delta_ddot, abs=1e-12)
        assert acc.tension == pytest.approx(ref.tension, abs=1e-12)
        w = x[8:11]
        np.testing.assert_allclose(acc.omega_dot_B, (tau - np.cross(w, J3 * w)) / J3, atol=1e-12)


@pytest.mark.parametrize("heading", [0.0, math.pi / 2])
def test_planar_offset_model_is_the_3d_model_in_the_fall_line_plane(heading: float) -> None:
    """delta = 0, no roll, rotation about y_A only: the closed-form planar accelerations
    (4.14)-(4.16) equal the 3D 6 x 6 solution, and the rotor torque about the other axes
    the 3D body needs to stay planar is the cable torque's (zero for an in-plane offset)."""
    rng = np.random.default_rng(7)
    J = np.array([0.015, 0.015, 0.025])
    r_B = np.array([0.03, 0.0, -0.03]) if heading == 0.0 else np.array([0.0, -0.03, -0.03])
    c_psi, s_psi = math.cos(heading), math.sin(heading)
    r0_A = np.array([[c_psi, -s_psi, 0], [s_psi, c_psi, 0], [0, 0, 1]]) @ r_B
    assert abs(r0_A[1]) < 1e-15  # in the plane
    params = PlanarParams.from_matrices(M, L, J, np.eye(4), heading=heading)
    for _ in range(5):
        phi, th, dphi, dth = rng.uniform(-1.2, -0.2), rng.uniform(0, 1), *rng.normal(0, 1, 2)
        F, tau_y = rng.uniform(4, 12), rng.normal(0, 0.05)
        pl = planar_offset_accelerations(phi, th, dphi, dth, F, tau_y, (r0_A[0], r0_A[2]),
                                         params, NUMPY)  # fmt: skip
        c_t, s_t = math.cos(th), math.sin(th)
        Ry = np.array([[c_t, 0, s_t], [0, 1, 0], [-s_t, 0, c_t]])
        Rz = np.array([[c_psi, -s_psi, 0], [s_psi, c_psi, 0], [0, 0, 1]])
        R_AB = Ry @ Rz
        e_B = R_AB.T @ np.array([0.0, 1.0, 0.0])
        w_B = dth * e_B
        x = np.concatenate(([phi, 0.0, dphi, 0.0], rotmat_to_quat(R_AB), w_B))
        acc = offset_body_dynamics(x, F, tau_y * e_B, M, L, J, R_WA, r_B)
        assert acc.phi_ddot == pytest.approx(pl["phi_ddot"], abs=1e-10)
        assert acc.tension == pytest.approx(pl["tension"], abs=1e-10)
        np.testing.assert_allclose(acc.omega_dot_B, pl["theta_ddot"] * e_B, atol=1e-10)
        assert acc.delta_ddot == pytest.approx(0.0, abs=1e-10)
    # symbolic backend: the same numbers
    import casadi as ca

    sym = ca.SX.sym("s", 6)
    out = planar_offset_accelerations(*[sym[i] for i in range(6)], (r0_A[0], r0_A[2]), params,
                                      CASADI)  # fmt: skip
    fn = ca.Function("f", [sym], [out["phi_ddot"], out["tension"]])
    vals = [float(v) for v in fn([phi, th, dphi, dth, F, tau_y])]
    assert vals == pytest.approx([pl["phi_ddot"], pl["tension"]], abs=1e-12)


# -- OCP plans re-simulated on the exact 3D model -----------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize(
    ("name", "extra"),
    [("slope50", []), ("steep70", []), ("slope50", [SIDEWAYS])],
)
def test_ocp_plan_resimulated_on_the_3d_offset_model(name: str, extra: list[str]) -> None:
    """The planned net wrench (f_R, tau_y e_B) drives the exact 3D tethered body with the
    offset (the rotors also cancelling the cable moment at the 3D model's own tension,
    (4.22)): it meets the final conditions, and the physical rotor thrusts
    Gamma^-1 [f_R, tau_B + r x (f_L R^T d)] stay within the planned bounds."""
    from tetherland.models.quadrotor import RotorLayout
    from tetherland.planning import Planner
    from tetherland.planning.maneuver import ManeuverSpec

    sc = load_scenario(name, extra)
    result = Planner().plan(sc)
    traj = result.require()
    spec = ManeuverSpec.from_scenario(sc)
    p = spec.params
    r = np.asarray(sc.vehicle.cable_attachment, dtype=float)
    J = np.asarray(sc.vehicle.inertia, dtype=float)
    Gamma_inv = np.linalg.inv(RotorLayout.from_config(sc.vehicle).allocation)
    dt = 2e-3
    n = round(traj.duration / dt)
    s = traj.sample(np.linspace(0.0, traj.duration, 2 * n + 1))
    f_R = s.f_R
    tau = s.thrusts @ p.torque_row
    e_B = p.e_B
    x = np.concatenate(([s.phi[0, 0], 0.0, s.phi[0, 1], 0.0],
                        rotmat_to_quat(_R_AB(s.theta_A[0, 0])), s.theta_A[0, 1] * e_B))  # fmt: skip

    def rhs(y: np.ndarray, k: int) -> np.ndarray:
        acc = offset_body_dynamics(y, f_R[k], tau[k] * e_B, p.mass, p.length, J, R_WA, r,
                                   p.gravity, cancel_cable_torque=True)  # fmt: skip
        w = y[8:11]
        from tetherland.rotations import quat_multiply

        q_dot = 0.5 * quat_multiply(y[4:8], np.concatenate(([0.0], w)))
        return np.concatenate(([y[2], y[3], acc.phi_ddot, acc.delta_ddot], q_dot, acc.omega_dot_B))

    worst_lo, worst_hi = np.inf, -np.inf
    for i in range(n):
        k = 2 * i
        k1 = rhs(x, k)
        k2 = rhs(x + 0.5 * dt * k1, k + 1)
        k3 = rhs(x + 0.5 * dt * k2, k + 1)
        k4 = rhs(x + dt * k3, k + 2)
        x = x + dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        x[4:8] /= np.linalg.norm(x[4:8])
        acc = offset_body_dynamics(x, f_R[k + 2], tau[k + 2] * e_B, p.mass, p.length, J, R_WA,
                                   r, p.gravity, cancel_cable_torque=True)  # fmt: skip
        R = quat_to_rotmat(x[4:8])
        d = link_direction(x[0], x[1])
        tau_rot = tau[k + 2] * e_B + acc.tension * np.cross(r, R.T @ d)
        f = Gamma_inv @ np.concatenate(([f_R[k + 2]], tau_rot))
        worst_lo, worst_hi = min(worst_lo, f.min()), max(worst_hi, f.max())
    R = quat_to_rotmat(x[4:8])
    theta = math.atan2(R[0, 2], R[2, 2])  # tilt of z_B towards x_A
    omega_A = R @ x[8:11]
    assert x[0] == pytest.approx(spec.phi_final, abs=1e-4)
    assert theta == pytest.approx(spec.theta_final, abs=1e-4)
    assert abs(x[2]) < 1e-4 and abs(omega_A[1]) < 1e-4
    assert abs(x[1]) < 1e-9 and np.linalg.norm(omega_A[[0, 2]]) < 1e-9  # stays planar
    assert worst_lo >= spec.f_lo - 1e-4 and worst_hi <= spec.f_hi + 1e-4
    # the offset torque matters: the rotor thrusts differ from the planner's net thrusts
    assert np.max(np.abs(s.thrusts.min() - worst_lo)) > 1e-3


def _R_AB(theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def test_offset_puts_the_torque_into_the_link_accelerations() -> None:
    """Why the DFL (relative degrees {4, 4, 2, 2}) cannot be exact with an offset: in the
    exact model (4.12) phi'' and delta'' depend on tau_B directly (through alpha x r),
    with the sensitivity m r / (J l (1 + ...)) of the lever arm; at zero offset they do
    not. Derivatives by central differences at random states."""
    rng = np.random.default_rng(17)
    r = np.array([0.0, 0.0, -0.03])
    for _ in range(5):
        q = rotvec_to_quat(rng.normal(0, 0.3, 3))
        x = np.concatenate((rng.uniform(-1, -0.2, 1), rng.uniform(-0.3, 0.3, 1),
                            rng.normal(0, 0.5, 2), q, rng.normal(0, 0.5, 3)))  # fmt: skip
        f_R, tau = rng.uniform(6, 12), rng.normal(0, 0.05, 3)

        def link_acc(
            tau_B: np.ndarray, r_B: np.ndarray, x: np.ndarray = x, f_R: float = f_R
        ) -> np.ndarray:
            a = offset_body_dynamics(x, f_R, tau_B, M, L, J3, R_WA, r_B)
            return np.array([a.phi_ddot, a.delta_ddot])

        for r_B, expect_coupled in ((r, True), (np.zeros(3), False)):
            D = np.column_stack([
                (link_acc(tau + 1e-6 * e, r_B) - link_acc(tau - 1e-6 * e, r_B)) / 2e-6
                for e in np.eye(3)
            ])  # fmt: skip
            if expect_coupled:
                # order of magnitude |r| / (J l): 0.03 / (0.015..0.025) = 1.2..2 per N m
                assert np.linalg.norm(D) > 0.5
            else:
                assert np.linalg.norm(D) < 1e-8
