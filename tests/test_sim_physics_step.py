"""The plant's compiled physics step (sim/step_kernel.physics_step) against its Python path.

A plant with the elastic cable and the capture disk steps in one compiled call that calls
MuJoCo's ``mj_step1``/``mj_step2`` itself (sim/native.py); with ``compiled_step=False``
the same plant steps through the Python bindings. Both must give the same bits: the
state, the sensors, the actuators, the rotors, the hook's events and the contact peaks,
through hook crossings (caught and missed), a stretched cable, contacts of the landers and
of the frame, and a divergence.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.errors import SimulationError
from tetherland.rotations import quat_to_rotmat
from tetherland.sim.hook import HookEventKind
from tetherland.sim.plant import CONTACT_PEAK_WIDTH, ROTOR_STATE_WIDTH, Plant
from tetherland.state import RigidBodyState


def _twins(name: str, sets: list[str] | None = None) -> tuple[Plant, Plant]:
    sc = load_scenario(name, sets or [])
    compiled, plain = Plant(sc), Plant(sc, compiled_step=False)
    assert compiled.compiled_step and not plain.compiled_step
    return compiled, plain


def _same(a: Plant, b: Plant) -> None:
    d, e = a.data, b.data
    for field in ("qpos", "qvel", "qacc", "sensordata", "ctrl", "qfrc_applied", "site_xpos"):
        np.testing.assert_array_equal(getattr(d, field), getattr(e, field), err_msg=field)
    np.testing.assert_array_equal(a._rot, b._rot)
    assert a.time == b.time
    assert a.hook.engaged == b.hook.engaged
    assert [ev.as_dict() for ev in a.hook.events] == [ev.as_dict() for ev in b.hook.events]


def _peaks(p: Plant) -> np.ndarray:
    out = np.zeros(CONTACT_PEAK_WIDTH)
    p.contact_peaks_into(out)
    return out


def _through_the_plane(plant: Plant, offset_m: float, speed: float) -> RigidBodyState:
    """A state whose attachment point is ``5 mm`` before the capture plane and moves
    through it at ``speed`` [m/s], its hook point ``offset_m`` beside the anchor."""
    hook = plant.hook
    nx, ny, nz, _ = hook.plane
    n = np.array([nx, ny, nz])
    side = np.cross(n, [1.0, 0.0, 0.0] if abs(n[0]) < 0.9 else [0.0, 1.0, 0.0])
    side /= np.linalg.norm(side)
    p_att = plant.layout.geometry.p_A - hook.offset_W + offset_m * side - 0.005 * n
    q = plant.start_state().q_WB
    p_W = p_att - quat_to_rotmat(q) @ np.asarray(plant.scenario.vehicle.cable_attachment)
    return RigidBodyState(p_W=p_W, v_W=speed * n, q_WB=q, omega_B=np.zeros(3))


@pytest.mark.parametrize(
    "sets", [[], ["aero.ground_effect=false", "aero.rotor_drag=[0, 0]"]], ids=["aero", "no-aero"]
)
def test_the_compiled_step_gives_the_python_steps_bits(sets):
    a, b = _twins("slope50", sets)
    w_max = a.speed_limit
    rng = np.random.default_rng(3)
    landed = a.landed_state()
    z_S = a.layout.geometry.surface.z_S
    legs = [
        ("caught", _through_the_plane(a, 0.0, 0.5), False),
        ("missed", _through_the_plane(a, 0.5, 0.5), False),
        ("back out", _through_the_plane(a, 0.0, -0.5), True),
        ("landing, stretched", RigidBodyState.at_rest(landed.p_W + 0.02 * z_S, landed.q_WB), True),
        ("falling on the slope", RigidBodyState(
            p_W=landed.p_W + 0.05 * z_S, v_W=-1.5 * z_S, q_WB=landed.q_WB,
            omega_B=np.array([4.0, -3.0, 1.0])), True),
    ]  # fmt: skip
    seen = {}
    for name, start, engaged in legs:
        for p in (a, b):
            p.reset(start, rotor_speeds=np.full(4, 0.4 * w_max), cable_engaged=engaged)
        tension = 0.0
        for k in range(300):
            if k % 20 == 0:
                w = rng.uniform(0.0, 0.8, 4) * w_max
                a.command(w)
                b.command(w)
            a.step()
            b.step()
            _same(a, b)
            tension = max(tension, a.tension)
        peaks = _peaks(a)
        np.testing.assert_array_equal(peaks, _peaks(b), err_msg=name)
        rows = np.empty((2, ROTOR_STATE_WIDTH))
        a.rotor_state_into(rows[0])
        b.rotor_state_into(rows[1])
        np.testing.assert_array_equal(rows[0], rows[1])
        seen[name] = ([e.kind for e in a.hook.events], peaks, tension)
    # the legs did what they are there for: a catch and a miss at the capture plane, a
    # part of the frame in contact (a crash), the cable pulling, the landers loaded
    assert seen["caught"][0] == [HookEventKind.ENGAGED]
    assert seen["missed"][0] == [HookEventKind.MISSED]
    assert seen["missed"][1][8] > 0.0  # the largest force on a part of the frame [N]
    assert seen["landing, stretched"][2] > 1.0
    assert np.all(seen["falling on the slope"][1][0:4] > 0.0)  # every lander on the slope


def test_the_compiled_step_counts_steps_like_step_n():
    a, b = _twins("wall90")
    start = a.start_state()
    for p in (a, b):
        p.reset(start, rotor_speeds=np.full(4, 0.6 * a.speed_limit))
    a.step(25)
    for _ in range(25):
        b.step()
    _same(a, b)
    assert a.time == pytest.approx(25 * a.dt)


def test_a_diverging_compiled_step_raises_as_the_python_one():
    messages = []
    for p in _twins("slope50"):
        p.reset(p.start_state())
        p.data.qvel[0] = np.nan
        with pytest.raises(SimulationError) as err:
            p.step(3)
        messages.append(str(err.value))
        assert p.time == pytest.approx(p.dt)  # raised at the first step
    assert messages[0] == messages[1]
    assert "diverged at t = 0.0000 s" in messages[0]


@pytest.mark.parametrize(
    ("name", "sets", "compiled"),
    [
        ("slope50", [], True),
        ("wall90", [], True),
        ("slope50", ["mechanism.kind=bar"], False),
        ("wall90", ["mechanism.kind=magnet"], False),
        ("slope50", ['tether.material="ideal"'], False),
    ],
)
def test_which_plants_step_compiled(name, sets, compiled):
    # the compiled step covers the elastic cable with the capture disk (every scenario's
    # default); the contact mechanisms and the other cables step in Python
    assert Plant(load_scenario(name, sets)).compiled_step is compiled


@pytest.mark.parametrize("how", [copy.copy, copy.deepcopy, pickle.dumps])
def test_a_plant_is_neither_copied_nor_pickled(how):
    # a copy's views and address table would point into the original's MuJoCo data (its
    # steps would move the original): refused with one clear message
    with pytest.raises(TypeError, match="cannot be copied or pickled"):
        how(Plant(load_scenario("slope50")))
