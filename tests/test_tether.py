"""The real tether (issue 12): config, the elastic and the massive cable in the plant.

Every expected value is derived here: static stretch m g/k, the longitudinal frequency of
the discrete scheme against sqrt(k/m), the energy balance, the discrete hanging chain and
its convergence to the catenary, and the touchdown point of the stretched cable.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest
from scipy.optimize import brentq, curve_fit

from tetherland import GRAVITY
from tetherland.analysis.statics import landing_hover, tethered_rest_tension
from tetherland.cli import main
from tetherland.config import TETHER_MATERIALS, CableModel, load_scenario
from tetherland.control import SwitchingController
from tetherland.control.stack import with_aero_belief
from tetherland.errors import ConfigError
from tetherland.estimation import UkfEstimator, elastic_tension
from tetherland.estimation.tension import (
    TENSION_FILTER_FAST,
    TENSION_FILTER_SLOW,
    tension_filter_time_constant,
)
from tetherland.geometry import (
    LandingGeometry,
    StretchedLanding,
    cable_stretch,
    landing_geometry,
    link_direction,
    link_frame,
    stretched_landing,
)
from tetherland.models.quadrotor import RotorModel
from tetherland.planning import Planner
from tetherland.planning.start import plan_start_state
from tetherland.planning.tracking import TrajectoryTrack
from tetherland.rotations import quat_multiply, quat_to_rotmat, rotvec_to_quat
from tetherland.runs import run_mission
from tetherland.sim.cable import ChainCable, ElasticCable, chain_nodes, joint_quaternions
from tetherland.sim.mjcf import (
    ChainSpec,
    _fmt,
    _sub,
    add_chain,
    chain_armature,
)
from tetherland.sim.plant import Plant
from tetherland.sim.runner import Runner
from tetherland.state import RigidBodyState, link_kernel

AT_COM = "vehicle.cable_attachment=[0,0,0]"
"""Cable at the centre of mass: the vehicle is a point mass on the cable (no torque)."""
NYLON = 'tether.material="nylon"'
IDEAL = 'tether.material="ideal"'


# -- configuration ------------------------------------------------------------------------


def test_presets_resolve_and_explicit_fields_override():
    t = load_scenario("slope50").tether
    assert t.material == "dyneema" and t.cable_model is CableModel.ELASTIC  # the default
    assert t.effective_axial_stiffness == TETHER_MATERIALS["dyneema"].axial_stiffness
    assert t.stiffness == pytest.approx(t.effective_axial_stiffness / t.length)
    assert t.mass_per_length == 0.0  # segments = 0: massless
    assert t.damping(2.0) == pytest.approx(2 * t.damping_ratio * math.sqrt(t.stiffness * 2.0))
    ideal = load_scenario("slope50", ['tether.material="ideal"']).tether
    assert ideal.cable_model is CableModel.IDEAL and ideal.stiffness is None
    assert ideal.stretch(8.0) == 0.0 and ideal.damping(1.0) == 0.0
    chain = load_scenario("slope50", [NYLON, "tether.segments=6"]).tether
    assert chain.cable_model is CableModel.CHAIN
    assert chain.mass_per_length == TETHER_MATERIALS["nylon"].linear_density
    custom = load_scenario(
        "steep70",
        [NYLON, "tether.axial_stiffness=3000", "tether.segments=3", "tether.linear_density=0.01"],
    ).tether
    assert custom.stiffness == pytest.approx(3000 / 1.2) and custom.mass_per_length == 0.01
    assert custom.stretch(6.0) == pytest.approx(6.0 * 1.2 / 3000)
    # an explicit EA turns the ideal preset elastic
    assert load_scenario("slope50", ['tether.material="ideal"', "tether.axial_stiffness=500"]
                         ).tether.cable_model is CableModel.ELASTIC  # fmt: skip


def test_presets_give_millimetres_for_dyneema_and_about_a_centimetre_for_nylon():
    """At f_L = 8 N and l = 1 m (docs/theory.md section 13)."""
    stretch = {m: cable_stretch(8.0, 1.0, p.axial_stiffness) for m, p in TETHER_MATERIALS.items()}
    assert stretch["ideal"] == 0.0
    assert stretch["steel"] < stretch["dyneema"] < 1e-3
    assert 4e-3 < stretch["nylon"] < 1.5e-2
    for p in TETHER_MATERIALS.values():  # 1 mm lines weigh grams per metre
        assert 0.0 <= p.linear_density < 5e-3


@pytest.mark.parametrize(
    ("override", "expected"),
    [
        (["tether.axial_stiffness=-5"], "tether.axial_stiffness: Input should be greater than 0"),
        (["tether.linear_density=0.01"], "tether.linear_density = 0.01 kg/m needs segments >= 1"),
        (['tether.material="ideal"', "tether.segments=4"], "tether.segments = 4 needs a linear"),
        (['tether.material="kevlar"'], "tether.material: Input should be 'ideal', 'dyneema'"),
        (["tether.damping_ratio=3"], "tether.damping_ratio: Input should be less than or equal"),
        (["tether.damping_ratio=-0.1"], "allowed range [0, 2]"),
        (["tether.segments=51"], "allowed range [0, 50]"),
        (["tether.axial_stiffness=1e6"], "tether.axial_stiffness: EA = 1e+06 N"),
    ],
)
def test_bad_tether_input_is_one_line_naming_the_field(override, expected):
    with pytest.raises(ConfigError) as err:
        load_scenario("slope50", override)
    text = str(err.value)
    assert expected in text and "\n" not in text


def test_bad_tether_input_exits_2_on_the_cli(capsys):
    code = main(["analyze", "slope50", "--set", "tether.segments=0", "--set",
                 "tether.linear_density=0.002"])  # fmt: skip
    _, err = capsys.readouterr()
    assert code == 2
    assert err.strip().count("\n") == 0 and "tether.linear_density" in err


def test_stiffness_limit_is_the_explicit_step_stability_bound():
    """sqrt(k/m_eff) dt <= sqrt(zeta^2 + 1) - zeta, half the symplectic-Euler limit
    2 (sqrt(zeta^2 + 1) - zeta) of a damped oscillator; m_eff includes the offset."""
    zeta, dt, m = 0.05, 1e-3, 1.0
    limit = math.sqrt(zeta**2 + 1) - zeta
    m_eff = 1.0 / (1.0 / m + 0.03**2 / 0.015)  # default offset 3 cm, J_min 0.015
    ea_max = (limit / dt) ** 2 * m_eff  # at l = 1 m
    load_scenario("slope50", [f"tether.axial_stiffness={0.99 * ea_max}"])
    with pytest.raises(ConfigError, match=r"too stiff for sim\.timestep"):
        load_scenario("slope50", [f"tether.axial_stiffness={1.01 * ea_max}"])
    load_scenario("slope50", [f"tether.axial_stiffness={1.01 * ea_max}", "sim.timestep=0.0005"])


# -- the massless elastic cable -----------------------------------------------------------


def _hanging(plant: Plant, extra: float = 0.0, v0=(0.0, 0.0, 0.0)) -> float:
    """Engaged, motors off, hanging straight below the anchor at the static stretch
    + ``extra``; returns the static stretch m g/k [m]."""
    sc = plant.scenario
    s_static = sc.tether.stretch(sc.vehicle.mass * GRAVITY)
    p = plant.layout.geometry.p_A - np.array([0.0, 0.0, sc.tether.length + s_static + extra])
    plant.reset(RigidBodyState(p, np.asarray(v0, dtype=float), np.array([1.0, 0, 0, 0]),
                               np.zeros(3)), cable_engaged=True)  # fmt: skip
    return s_static


@pytest.mark.parametrize("material", ["dyneema", "nylon", "steel"])
def test_static_stretch_of_a_hanging_vehicle_is_mg_over_k(material):
    sc = load_scenario("slope50", [AT_COM, f'tether.material="{material}"'])
    plant = Plant(sc)
    s_static = _hanging(plant, extra=0.2 * sc.tether.stretch(10.0))
    plant.step(6000)  # 6 s: the zeta = 0.05 transient decays below 1e-6 of the start
    k, m = sc.tether.stiffness, sc.vehicle.mass
    assert s_static == pytest.approx(m * GRAVITY / k)
    assert plant.data.ncon == 0  # hanging free: under the thin surface patch
    assert plant.tension == pytest.approx(m * GRAVITY, rel=1e-5)
    D = np.linalg.norm(plant.attachment_point() - plant.layout.geometry.p_A)
    assert D - sc.tether.length == pytest.approx(s_static, rel=1e-4)


def _discrete_oscillator(w: float, zeta: float, h: float) -> tuple[float, float]:
    """(omega, zeta) of the continuous oscillator whose samples the plant's scheme
    reproduces: v' = v + h (-w^2 x - 2 zeta w v), x' = x + h v' has eigenvalues
    r exp(+-i theta) with r^2 = 1 - 2 zeta w h, 2 r cos(theta) = 2 - (w h)^2 - 2 zeta w h."""
    r = math.sqrt(1.0 - 2.0 * zeta * w * h)
    theta = math.acos((2.0 - (w * h) ** 2 - 2.0 * zeta * w * h) / (2.0 * r))
    sigma, wd = -math.log(r) / h, theta / h
    w_eq = math.hypot(wd, sigma)
    return w_eq, sigma / w_eq


@pytest.mark.parametrize(("material", "zeta"), [("nylon", 0.0), ("nylon", 0.05), ("dyneema", 0.1)])
def test_longitudinal_frequency_and_damping_of_a_mass_on_the_cable(material, zeta):
    """Vertical oscillation of the hanging vehicle: the scheme's (omega, zeta) from its
    eigenvalues, within (w h)^2/24 + zeta w h (+ higher orders) of sqrt(k/m) and the
    configured zeta."""
    sc = load_scenario("slope50", [AT_COM, f'tether.material="{material}"',
                                   f"tether.damping_ratio={zeta}"])  # fmt: skip
    plant = Plant(sc)
    k, m, h = sc.tether.stiffness, sc.vehicle.mass, plant.dt
    w0 = math.sqrt(k / m)
    s_static = _hanging(plant, extra=0.0)
    amp = 0.4 * s_static  # stays taut: k x + c x' > 0 throughout
    _hanging(plant, extra=amp)
    n = round(6 * 2 * math.pi / w0 / h)  # six periods
    z = np.empty(n)
    for i in range(n):
        plant.step()
        z[i] = plant.qpos[2]
    t = h * np.arange(1, n + 1)
    z_eq = plant.layout.geometry.p_A[2] - sc.tether.length - s_static

    def model(t, A, w, zt, ph):
        return z_eq + A * np.exp(-zt * w * t) * np.cos(w * math.sqrt(1 - zt * zt) * t + ph)

    (A, w, zt, _), _ = curve_fit(model, t, z, p0=[-amp, w0, zeta + 1e-3, 0.0])
    w_num, zeta_num = _discrete_oscillator(w0, zeta, h)
    assert w == pytest.approx(w_num, rel=2e-5)
    assert zt == pytest.approx(zeta_num, abs=2e-5)
    assert abs(w_num / w0 - 1) < (w0 * h) ** 2 / 20 + zeta * w0 * h  # (w h)^2/24 + O(h^4)
    assert abs(zeta_num - zeta) < zeta * w0 * h + 1e-12
    assert abs(A) == pytest.approx(amp, rel=0.02)


def test_the_force_is_the_unilateral_spring_damper_at_each_step():
    """f_L = max(0, k x + c x') while x = L - l > 0 and 0 while slack, at the step's start
    state; the cable never pushes (a fast approach while taut clamps it to 0)."""
    sc = load_scenario("slope50", [AT_COM, NYLON, "tether.damping_ratio=1.5"])
    plant = Plant(sc)
    cable = plant.cable
    assert isinstance(cable, ElasticCable)
    _hanging(plant, extra=0.01, v0=(0.0, 0.3, 0.8))  # stretched, moving up fast and sideways
    d = plant.data
    seen = {"taut": 0, "slack": 0, "clamped": 0}
    for _ in range(1500):
        plant.step()
        L, rate = float(d.ten_length[0]), float(d.ten_velocity[0])  # at t_k (mj_step1)
        x = L - sc.tether.length
        spring = cable.k * x + cable.c * rate
        expected = max(0.0, spring) if x > 0 else 0.0
        assert plant.tension == pytest.approx(expected, rel=1e-12, abs=1e-12)
        assert plant.cable_length == pytest.approx(L, rel=1e-12)
        seen["taut" if expected > 0 else ("clamped" if x > 0 else "slack")] += 1
    assert min(seen.values()) > 0, seen


def _energy(plant: Plant) -> float:
    """Kinetic + gravity + cable spring energy [J] (no rotation with the cable at the CoM)."""
    sc = plant.scenario
    v, m = plant.qvel[0:3], sc.vehicle.mass
    w = plant.qvel[3:6]
    kinetic = 0.5 * m * float(v @ v) + 0.5 * float(w @ (np.asarray(sc.vehicle.inertia) * w))
    D = float(np.linalg.norm(plant.attachment_point() - plant.layout.geometry.p_A))
    x = max(0.0, D - sc.tether.length)
    return kinetic + m * GRAVITY * float(plant.qpos[2]) + 0.5 * sc.tether.stiffness * x * x


@pytest.mark.parametrize("zeta", [0.0, 0.2])
def test_energy_balance_of_the_elastic_pendulum(zeta):
    """A 3D swing that stretches and goes slack: E conserved undamped, E + W = E0 damped
    with W the work of the damping part of the force, both within the symplectic-Euler
    bound |E - E~| <= h |F.v| (E~ the scheme's conserved energy, to first order in h)."""
    sc = load_scenario("slope50", [AT_COM, NYLON, f"tether.damping_ratio={zeta}"])
    plant = Plant(sc)
    _hanging(plant, extra=0.02, v0=(0.9, 0.4, 0.0))
    d = plant.data
    k, l = sc.tether.stiffness, sc.tether.length
    E0 = _energy(plant)
    work, worst, bound, taut_steps, slack_steps = 0.0, 0.0, 0.0, 0, 0
    for _ in range(5000):
        plant.step()
        x = float(d.ten_length[0]) - l  # at t_k; the force of the step was set from it
        rate = float(d.ten_velocity[0])
        f = plant.tension
        work += plant.dt * (f - k * max(x, 0.0)) * rate  # dissipated by the damping part
        taut_steps += f > 0
        slack_steps += x < 0
        power = (f + sc.vehicle.mass * GRAVITY) * float(np.linalg.norm(plant.qvel[0:3]))
        bound = max(bound, plant.dt * power)
        worst = max(worst, abs(_energy(plant) + work - E0))
    assert taut_steps > 1000 and slack_steps > 20  # both regimes were visited
    assert worst < bound, (worst, bound)
    if zeta > 0:
        assert work > 4 * bound  # the dissipated work is resolved by the balance


# -- the massive cable: the hanging chain -------------------------------------------------


def _discrete_chain(n: int, rho: float, length: float, span: float) -> tuple[float, float]:
    """Sag and end tension of n uniform rigid links hanging between two points at equal
    height: each link lies along the mean force on it, tan(theta_i) = w_s (n/2 - i - 1/2)/H
    (weight w_s at its middle), with H from sum l_s cos(theta_i) = span."""
    l_s = length / n
    w_s = rho * l_s * GRAVITY
    i = np.arange(n)

    def theta(H):
        return np.arctan(w_s * (n / 2 - i - 0.5) / H)

    H = brentq(lambda H: l_s * np.cos(theta(H)).sum() - span, 1e-9, 1e6)
    sag = float(np.sum(l_s * np.sin(theta(H))[: n // 2]))
    return sag, math.hypot(H, n * w_s / 2)


def _catenary(rho: float, length: float, span: float) -> tuple[float, float]:
    """Sag a (cosh(D/2a) - 1) and end tension w a cosh(D/2a), l = 2 a sinh(D/2a)."""
    a = brentq(lambda a: 2 * a * math.sinh(span / (2 * a)) - length, 1e-3, 1e3)
    return a * (math.cosh(span / (2 * a)) - 1), rho * GRAVITY * a * math.cosh(span / (2 * a))


def _settled_chain(n: int, rho: float, length: float, span: float) -> tuple[float, float, float]:
    """The plant's chain (mjcf.add_chain) between the anchor and a fixed point at equal
    height, laid out at rest by the plant (cable.chain_nodes), pushed out of it and
    settled again with joint damping; (sag, T_end, T_anchor) as MuJoCo holds it."""
    dt = 1e-3
    root = ET.Element("mujoco")
    _sub(root, "option", timestep=f"{dt}", integrator="implicitfast", jacobian="dense",
         solver="Newton")  # fmt: skip
    world = _sub(root, "worldbody")
    p_A = np.array([0.0, 0.0, 2.0])
    p_B = p_A + np.array([span, 0.0, 0.0])
    _sub(world, "site", name="fixed_end", pos=_fmt(p_B))
    l_s, m_s = length / n, rho * length / n
    spec = ChainSpec(n, l_s, m_s, chain_armature(1.0, l_s, m_s, dt), joint_damping=1e-3)
    add_chain(world, root, p_A, spec, solref="0.004 1", end_site="fixed_end")
    model = mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))
    data = mujoco.MjData(model)
    nodes, excess = chain_nodes(p_A, p_B, length, n, np.array([1.0, 0.0, 0.0]))
    assert excess == 0.0 and np.allclose(nodes[-1], p_B)
    sag_layout = p_A[2] - nodes[:, 2].min()
    assert sag_layout == pytest.approx(_discrete_chain(n, rho, length, span)[0], rel=1e-9)
    for i, q in enumerate(joint_quaternions(nodes)):
        data.qpos[4 * i : 4 * i + 4] = q
    mujoco.mj_kinematics(model, data)
    np.testing.assert_allclose(data.site_xpos[model.site("cable_end").id], p_B, atol=1e-12)
    data.eq_active[0] = 1
    for i in range(1, n):  # bend it in its plane (about the links' y = y_W), out of rest
        bend = rotvec_to_quat([0.0, 0.15 * (-1) ** i, 0.0])
        data.qpos[4 * i : 4 * i + 4] = quat_multiply(data.qpos[4 * i : 4 * i + 4].copy(), bend)
    for _ in range(6000):
        mujoco.mj_step(model, data)
    assert np.abs(data.qvel).max() < 1e-3  # at rest
    mujoco.mj_rnePostConstraint(model, data)
    lowest = min(data.xpos[b][2] for b in range(1, n + 1))
    t_end = float(np.linalg.norm(data.efc_force[:3]))
    t_anchor = float(np.linalg.norm(data.cfrc_int[model.body("cable_link0").id][3:]))
    return p_A[2] - lowest, t_end, t_anchor


def test_hanging_chain_matches_its_discrete_equilibrium_and_converges_to_the_catenary():
    rho, length, span = 0.05, 1.0, 0.8
    sag_c, t_c = _catenary(rho, length, span)
    errors = []
    for n in (4, 8, 16):
        sag, t_end, t_anchor = _settled_chain(n, rho, length, span)
        sag_d, t_d = _discrete_chain(n, rho, length, span)
        assert sag == pytest.approx(sag_d, rel=1e-4)  # MuJoCo's statics of the same chain
        assert t_end == pytest.approx(t_d, rel=1e-4) and t_anchor == pytest.approx(t_d, rel=1e-4)
        errors.append((sag - sag_c, t_end - t_c))
    (s4, f4), (s8, f8), (s16, f16) = errors
    assert s4 > s8 > s16 > 0 and f4 < f8 < f16 < 0  # more sag, less tension than the catenary
    assert 3.5 < s4 / s8 < 4.5 and 3.5 < s8 / s16 < 4.5  # O(1/N^2)
    assert 3.5 < f4 / f8 < 4.5 and 3.5 < f8 / f16 < 4.5
    assert abs(s16) < 1e-3 * length and abs(f16) < 1e-3 * t_c


def test_chain_layout_is_exact_and_untwisted():
    rng = np.random.default_rng(3)
    for n in (3, 4, 7):
        p_A = rng.normal(size=3)
        p_B = p_A + 0.6 * rng.normal(size=3) / 2
        nodes, excess = chain_nodes(p_A, p_B, 1.0, n, np.array([1.0, 0.0, 0.0]))
        links = np.linalg.norm(np.diff(nodes, axis=0), axis=1)
        D = np.linalg.norm(p_B - p_A)
        if D < 1.0 and (n % 2 == 0 or D >= 1.0 / n):
            np.testing.assert_allclose(links, 1.0 / n, rtol=1e-12)
            np.testing.assert_allclose(nodes[-1], p_B, atol=1e-12)
            assert excess == 0.0
    nodes, excess = chain_nodes(np.zeros(3), [0.0, 1.2, 0.0], 1.0, 5, np.array([1.0, 0, 0]))
    assert excess == pytest.approx(0.2)  # taut beyond l: straight, the rest is stretch
    np.testing.assert_allclose(nodes[-1], [0.0, 1.0, 0.0], atol=1e-12)


def test_massive_cable_holds_a_hanging_vehicle_and_carries_its_own_weight():
    """Vertical chain: tension at the attachment m g, at the anchor (m + rho l) g; the
    elongation m g/k added quasi-statically."""
    sc = load_scenario("slope50", [AT_COM, 'tether.material="steel"', "tether.segments=8"])
    plant = Plant(sc)
    assert isinstance(plant.cable, ChainCable)
    s_static = _hanging(plant)
    plant.step(3000)
    m, mc = sc.vehicle.mass, plant.cable.total_mass
    assert mc == pytest.approx(sc.tether.mass_per_length * sc.tether.length)
    assert plant.tension == pytest.approx(m * GRAVITY, rel=1e-4)
    mujoco.mj_rnePostConstraint(plant.model, plant.data)
    anchor = plant.data.cfrc_int[plant.model.body("cable_link0").id][3:]
    assert np.linalg.norm(anchor) == pytest.approx((m + mc) * GRAVITY, rel=1e-4)
    assert plant.cable.stretch == pytest.approx(s_static, rel=1e-6)
    D = np.linalg.norm(plant.attachment_point() - plant.layout.geometry.p_A)
    assert D - sc.tether.length == pytest.approx(s_static, abs=1e-5)  # + the hook's compliance
    link = plant.link_state()  # from the vehicle's state, not the chain's joints
    assert link.phi == pytest.approx(-math.pi / 2, abs=1e-6)
    assert abs(link.phi_dot) < 1e-6 and abs(link.delta_dot) < 1e-6
    assert plant.qpos.shape == (7,) and plant.qvel.shape == (6,)
    nodes = [plant.data.xpos[plant.model.body(f"cable_link{i}").id] for i in range(8)]
    off = [np.linalg.norm((p - plant.layout.geometry.p_A)[:2]) for p in nodes]
    assert max(off) < 1e-6  # straight down


def test_massive_cable_drapes_when_slack_and_is_taken_up():
    """As in the mission: hooked at rest (hook point 5 cm past the anchor), then drifting
    away downhill on hover thrust tilted by 2 deg. The slack chain hangs below the anchor
    (laid out as a V, the attachment being straight above the anchor, it swings into its
    rest shape) pulling with a few times its weight at most; the vehicle then takes it
    up to a thousand times that."""
    sc = load_scenario("slope50", [AT_COM, "tether.segments=6"])  # 1 mm Dyneema, 0.6 g
    plant = Plant(sc)
    geo = plant.layout.geometry
    tilt = math.radians(2.0)
    w = math.sqrt(sc.vehicle.mass * GRAVITY / math.cos(tilt) / 4 / sc.vehicle.thrust_coefficient)
    start = geo.p_A + np.array([0.0, 0.0, sc.tether.hook_drop - 0.05])
    q = rotvec_to_quat(tilt * geo.R_WA[:, 1])  # thrust tilted towards x_A (downhill)
    plant.reset(RigidBodyState.at_rest(start, q), rotor_speeds=np.full(4, w), cable_engaged=True)
    weight = sc.tether.mass_per_length * sc.tether.length * GRAVITY
    end, att = plant.model.site("cable_end").id, plant.model.site("attachment").id
    gap, final_gap = 0.0, 0.0
    lowest, slack_max, peak = 0.0, 0.0, 0.0
    for _ in range(3000):
        plant.step()
        D = np.linalg.norm(plant.attachment_point() - geo.p_A)
        if D < 0.8 * sc.tether.length:
            z = [plant.data.xpos[plant.model.body(f"cable_link{i}").id][2] for i in range(6)]
            lowest = min(lowest, min(z) - geo.p_A[2])
            slack_max = max(slack_max, plant.tension)
        peak = max(peak, plant.tension)
        final_gap = np.linalg.norm(plant.data.site_xpos[end] - plant.data.site_xpos[att])
        gap = max(gap, final_gap)
    assert lowest < -0.1  # draped below the anchor
    assert slack_max < 5 * weight
    assert peak > 1000 * weight and plant.cable_engaged
    # The hook stays on the vehicle: the soft connection (time constant hook_timeconst)
    # lets the chain end lag by about a centimetre while the straightening chain cannot
    # follow the vehicle, millimetres otherwise.
    assert gap < 0.02 and final_gap < 3e-3


# -- the touchdown point of the stretched cable -----------------------------------------


def test_stretched_landing_solves_the_stretch_at_the_landed_hover_tension():
    sc = load_scenario("slope50", [NYLON])
    geo = LandingGeometry.from_scenario(load_scenario("slope50", [IDEAL]))  # rigid, length l
    assert geo.stretch == 0.0 and geo.axial_stiffness is None
    EA = sc.tether.effective_axial_stiffness
    l, m = sc.tether.length, sc.vehicle.mass
    sl = stretched_landing(geo, m, EA)  # the elastic cable on the rigid geometry's anchor
    _, f_L = landing_hover(geo.surface.slope, sl.geometry.c, m)  # the analysis module's (6.14)
    assert sl.tension == pytest.approx(f_L, rel=1e-12)
    assert sl.stretch == pytest.approx(f_L * l / EA, rel=1e-12)
    assert sl.geometry.length == l
    assert sl.geometry.link_length == pytest.approx(l + sl.stretch)
    np.testing.assert_allclose(sl.geometry.p_A, geo.p_A)
    # the touchdown point moves along the surface, downhill, by s/cos(gamma) to first
    # order (exactly sqrt((l + s)^2 - h^2) - sqrt(l^2 - h^2)): s along the cable
    h = geo.h_att - geo.h_A
    along = math.sqrt((l + sl.stretch) ** 2 - h * h) - math.sqrt(l * l - h * h)
    assert np.linalg.norm(sl.shift_W) == pytest.approx(along, rel=1e-9)
    assert along == pytest.approx(sl.stretch / math.cos(geo.gamma), rel=1e-2)
    assert sl.shift_W @ geo.d_tilde == pytest.approx(sl.stretch, rel=1e-2)
    assert sl.shift_W @ geo.surface.x_S > 0 and abs(geo.surface.height(sl.geometry.p_L)) < 1e-12
    # the compensated anchor lands the stretched cable on p*_L
    moved = landing_geometry(geo.surface, length=l + sl.stretch, h_R=geo.h_R, h_A=geo.h_A,
                             h_att=geo.h_att, anchor=sl.anchor_for_p_L)  # fmt: skip
    np.testing.assert_allclose(moved.p_L, geo.p_L, atol=1e-12)
    ideal = stretched_landing(geo, m, None)
    assert ideal.stretch == 0.0 and np.allclose(ideal.geometry.p_L, geo.p_L)
    # the scenario's own geometry is that compensated one: anchor moved, touchdown on p*_L
    own = LandingGeometry.from_scenario(sc)
    assert own.stretch == pytest.approx(sl.stretch, rel=1e-12)
    np.testing.assert_allclose(own.p_A, sl.anchor_for_p_L, atol=1e-12)
    np.testing.assert_allclose(own.p_L, geo.p_L, atol=1e-12)
    assert own.phi_star == pytest.approx(sl.geometry.phi_star, abs=1e-15)
    np.testing.assert_allclose(StretchedLanding.from_scenario(sc).shift_W, 0.0, atol=1e-12)


def test_plant_rests_at_the_stretched_landing_point():
    """Frictionless 50 deg slope, motors off: the elastic cable alone holds the vehicle,
    at the tension (6.14) of the stretched geometry, its attachment point l + s from p_A."""
    sc = load_scenario("slope50", [NYLON, "surface.friction=0"])
    plant = Plant(sc)
    sl = StretchedLanding.from_scenario(sc)
    plant.reset(plant.landed_state(), cable_engaged=True)
    plant.step(5000)
    expected = tethered_rest_tension(sl.geometry.surface, sl.geometry.d_tilde, sc.vehicle.mass)
    assert expected == pytest.approx(sl.tension, rel=1e-9)  # rest and hover: the same f_L
    assert plant.tension == pytest.approx(expected, rel=2e-3)
    np.testing.assert_allclose(plant.attachment_point(), sl.geometry.p_att_landed, atol=3e-4)
    np.testing.assert_allclose(plant.layout.geometry.p_att_landed, sl.geometry.p_att_landed)
    # the inextensible cable's link end on the same anchor is s (along d~) short of it
    geo = sl.geometry
    rigid = landing_geometry(geo.surface, length=geo.length, h_R=geo.h_R, h_A=geo.h_A,
                             h_att=geo.h_att, anchor=geo.p_A).p_att_landed  # fmt: skip
    assert np.linalg.norm(plant.attachment_point() - rigid) > 0.8 * sl.stretch


# -- estimation with an elastic cable ----------------------------------------------------


def test_tension_filter_follows_the_cable_axial_mode():
    slow, fast = TENSION_FILTER_SLOW, TENSION_FILTER_FAST
    assert tension_filter_time_constant(None, 1.0) == slow
    k_nylon = TETHER_MATERIALS["nylon"].axial_stiffness  # l = 1 m
    assert tension_filter_time_constant(k_nylon, 1.0) == pytest.approx(0.2 / math.sqrt(k_nylon))
    assert math.atan(tension_filter_time_constant(k_nylon, 1.0) * math.sqrt(k_nylon)) < 0.2
    assert tension_filter_time_constant(1e9, 1.0) == fast
    assert tension_filter_time_constant(1.0, 1.0) == slow
    est = UkfEstimator(load_scenario("slope50", [NYLON]), RigidBodyState.at_rest(np.zeros(3)))
    assert est.tension_time_constant == pytest.approx(0.2 / math.sqrt(k_nylon))


def test_link_rates_of_a_stretched_cable_use_its_real_length():
    """At distance l + s the link rates are v_t/(l + s): the estimate assumes no length."""
    rng = np.random.default_rng(7)
    R_WA = np.eye(3)
    p_A = np.array([0.2, -0.1, 1.0])
    for _ in range(5):
        phi, delta = rng.uniform(-1.2, 1.2), rng.uniform(-0.6, 0.6)
        dphi, ddelta = rng.normal(size=2)
        D = 1.0 + rng.uniform(0.0, 0.05)  # stretched
        d, R_AL = link_direction(phi, delta), link_frame(phi, delta)
        dd = math.cos(delta) * R_AL[:, 2] * dphi - R_AL[:, 1] * ddelta
        x = np.concatenate((p_A + D * d, [1.0, 0, 0, 0], D * dd + 0.3 * d, np.zeros(3)))
        out, d_B = link_kernel(x, np.zeros(3), p_A, R_WA)  # 0.3 m/s of stretch rate too
        np.testing.assert_allclose(out, [phi, delta, dphi, ddelta], atol=1e-12)
        np.testing.assert_allclose(d_B, d, atol=1e-12)


def test_cable_estimate_of_a_known_pose():
    sc = load_scenario("slope50", [NYLON])
    geo = LandingGeometry.from_scenario(sc)
    r_att = np.asarray(sc.vehicle.cable_attachment)
    p_att = geo.p_A + (sc.tether.length + 0.004) * geo.d_tilde
    est = UkfEstimator(sc, RigidBodyState.at_rest(p_att - r_att), 0.0)
    c = est.cable()
    assert c.distance == pytest.approx(sc.tether.length + 0.004, abs=1e-12)
    assert c.stretch == pytest.approx(0.004, abs=1e-12)
    assert c.elastic_tension == pytest.approx(sc.tether.stiffness * 0.004, rel=1e-9)
    assert elastic_tension(0.9, 1.0, 1e3) == 0.0  # slack
    ideal = UkfEstimator(load_scenario("slope50", ['tether.material="ideal"']),
                         RigidBodyState.at_rest(p_att - r_att), 0.0)  # fmt: skip
    assert ideal.cable().elastic_tension is None


@pytest.mark.slow
def test_nylon_tethered_landing_with_the_ukf_in_the_loop():
    """The planned 50 deg landing on 1 m of nylon (k = 1200 N/m), UKF in the loop: the
    tension estimate within 10 % while taut, the estimated distance within 1.5 mm of the
    true l + s (so k (D - l) within 1.8 N), and touchdown within the stretch of p*_L."""
    sc = load_scenario("slope50", [NYLON])
    traj = Planner().plan(sc, "landing").require()
    track = TrajectoryTrack(traj, 0.0, 500.0)

    class Track:
        def reference(self, t, est):
            return track.reference(t)

    # the plan's link is l + s (s at the landed f_L); the cable starts at the plan's start
    # tension T instead, l (1 + T/EA) along the planned link
    x0, w0 = plan_start_state(traj, sc)
    est = UkfEstimator(sc, x0, 0.0, rotor_speeds0=w0)
    plant = Plant(sc)
    rows = []

    def watch(t, plant):
        if 0.3 < t < traj.duration - 0.2:
            D = float(np.linalg.norm(plant.attachment_point() - plant.layout.geometry.p_A))
            rows.append((est.cable().distance, D))

    # as the mission composes it: the believed ground effect and rotor drag modelled
    ctrl = with_aero_belief(SwitchingController(sc), sc)
    log = Runner(sc, ctrl, estimator=est, reference=Track(), seed=4,
                 plant=plant, observers=[watch]).run(
        traj.duration + 0.5, initial_state=x0, rotor_speeds=w0, cable_engaged=True)  # fmt: skip
    t = log["t"]
    taut = (t > 0.3) & (t < traj.duration - 0.2) & (log["tension"] > 0.5)
    rel = np.abs(log["est_tension"][taut] - log["tension"][taut]) / log["tension"][taut]
    assert rel.max() < 0.10
    est_D, true_D = np.array(rows).T
    assert np.abs(est_D - true_D).max() < 1.5e-3
    assert np.max(true_D) - sc.tether.length > 0.8 * sc.tether.stretch(log["tension"][taut].max())
    sl = StretchedLanding.from_scenario(sc)
    p_att_end = plant.attachment_point()
    assert np.linalg.norm(p_att_end - sl.geometry.p_att_landed) < 3e-3


@pytest.mark.slow
def test_nylon_mission_lands_on_the_desired_point_despite_the_stretch():
    """The full closed loop (MuJoCo, sensors, UKF, planner, supervisor) on nylon: the
    landing geometry, the plan and the feed-forward are those of the landed link l + s
    (docs/theory.md section 13.2), so the touchdown lands on p*_L to 2 mm, far less than
    the stretch s = f_L l/EA (6.3 mm, which the unstretched geometry landed beyond p*_L)."""
    sc = load_scenario("slope50", [NYLON])
    geo = LandingGeometry.from_scenario(sc)
    f_L = sc.vehicle.mass * GRAVITY * math.sin(geo.surface.slope) / math.cos(geo.gamma)
    s = f_L * sc.tether.length / sc.tether.effective_axial_stiffness
    assert geo.stretch == pytest.approx(s, rel=1e-12) and s > 5e-3
    summary = run_mission(sc, seed=0).summary
    assert summary["success"], summary
    err = summary["landing"]["position_error_m"]
    assert err < 2e-3 and err < s / 3


def test_plan_start_state_holds_the_planned_start_tension():
    """The plant starts on the planned link direction, l (1 + T/EA) from the anchor for the
    plan's start tension T (the plan's link is l + s, s at the landed f_L > T): the
    elastic cable pulls T at once, for Dyneema and nylon alike."""
    for material in ("dyneema", "nylon"):
        sc = load_scenario("slope50", [f'tether.material="{material}"'])
        traj = Planner().plan(sc, "landing").require()
        nom = traj.nominal(0.0)
        x0, w0 = plan_start_state(traj, sc)
        geo = LandingGeometry.from_scenario(sc)
        p_att = x0.p_W + quat_to_rotmat(x0.q_WB) @ np.asarray(sc.vehicle.cable_attachment)
        D = np.linalg.norm(p_att - geo.p_A)
        T = float(nom.tension)
        assert T == pytest.approx(sc.planner.start_tension, rel=1e-6)
        EA = sc.tether.effective_axial_stiffness
        assert D == pytest.approx(sc.tether.length * (1.0 + T / EA), abs=1e-12)
        assert geo.link_length - D > 0.5 * geo.stretch  # shorter than the landed link
        direction = (nom.p_W - geo.p_A) / np.linalg.norm(nom.p_W - geo.p_A)
        np.testing.assert_allclose((p_att - geo.p_A) / D, direction, atol=1e-12)
        thrusts = RotorModel.from_config(sc.vehicle).thrust(w0)
        np.testing.assert_allclose(thrusts, nom.rotor_thrusts, rtol=1e-9)
        plant = Plant(sc)
        plant.reset(x0, cable_engaged=True)
        plant.step(1)
        assert plant.tension == pytest.approx(T, rel=2e-2)
