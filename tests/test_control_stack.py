"""A mission's controller stack with its free-flight ticks compiled as one call
(:class:`tetherland.control.stack.CompiledStack`) against its layers (believed rotor drag,
believed ground effect, switching controller): the same commands bit for bit and the same
controller state after every tick, through free flight near and far from the surface, the
ticks that go through the layers (tethered, motors off, torque, shed, spin-down, drag
already in the rows, a switch and back) and a heading that cannot be defined."""

from __future__ import annotations

import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.control import FreeFlightController, SwitchingController
from tetherland.control.ground_effect import GroundEffectCompensation
from tetherland.control.kernels.free_flight import PAR_TAN_MAX_TILT
from tetherland.control.rotor_drag import RotorDragCompensation
from tetherland.control.stack import CompiledStack, compiled_stack, with_aero_belief
from tetherland.control.tracking import FreeFlightTracker
from tetherland.errors import SingularityError
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import ControlMode, Feedforward, Reference, StateEstimate
from tetherland.rotations import rotation_from_z_and_yaw, rotmat_to_quat
from tetherland.state import LinkState, RigidBodyState

FREE, TETHERED, OFF = ControlMode.FREE_FLIGHT, ControlMode.TETHERED, ControlMode.MOTORS_OFF


def _estimate(t, p_W, R_WB, v_W, omega_B, link):
    body = RigidBodyState(
        p_W=np.asarray(p_W, float), v_W=np.asarray(v_W, float),
        q_WB=rotmat_to_quat(R_WB), omega_B=np.asarray(omega_B, float),
    )  # fmt: skip
    return StateEstimate(t=t, body=body, link=link, tension=3.0)


def _ticks(scenario, n=160, seed=7):
    """(t, estimate, reference) of a flight from 4 m above the believed landing point down
    to 5 cm above it (the believed ground-effect factors 1 beyond about 2 m, well above 1
    near the surface), with every kind of reference the supervisor hands out on the way."""
    geo = LandingGeometry.from_scenario(scenario)
    z_S = geo.surface.z_S
    rng = np.random.default_rng(seed)
    link = LinkState(geo.phi_star, 0.0, 0.0, 0.0)
    ff = Feedforward(omega_B=np.zeros(3), omega_dot_B=np.zeros(3),
                     f_R=scenario.vehicle.mass * 9.81)  # fmt: skip
    ticks = []
    for i in range(n):
        t = 0.002 * (i + 1)
        height = 4.0 - 3.95 * i / (n - 1)
        tilt = rng.normal(0.0, 0.05, 3)
        R = rotation_from_z_and_yaw(z_S + tilt, 0.1 * rng.normal())
        p = geo.p_L + height * z_S + rng.normal(0.0, 0.01, 3)
        est = _estimate(t, p, R, rng.normal(0.0, 0.3, 3) - 0.4 * z_S, rng.normal(0.0, 0.5, 3),
                        link)  # fmt: skip
        n_rows = (2, 3, 4, 5)[i % 4]
        rows = np.zeros((n_rows, 3))
        rows[0] = geo.p_L + height * z_S
        rows[1:] = rng.normal(0.0, 0.5, (n_rows - 1, 3))
        if i % 7 == 3:
            rows.setflags(write=False)  # a path's held rows are read-only
        ref = Reference(t, FREE, 2, rows, 0.2)
        if 60 <= i < 70:  # a tethered stretch, then back to free flight (hand-over)
            out = np.zeros((5, 4))
            out[0, 0] = geo.phi_star
            ref = Reference(t, TETHERED, 4, output=out, thrust_ff=9.0, feedforward=ff)
        elif 90 <= i < 93:
            ref = Reference(t, OFF, 8)
        elif i == 100:
            ref = Reference(t, FREE, 2, rows, 0.2, torque_ff_B=np.array([0.01, -0.02, 0.0]))
        elif i == 101:
            ref = Reference(t, FREE, 2, rows, 0.2, thrust_shed=0.3)
        elif i == 102:
            ref = Reference(t, FREE, 2, rows, 0.2, thrust_scale=0.5)
        elif i == 103:
            ref = Reference(t, FREE, 2, rows, 0.2, drag_in_rows=True)
        ticks.append((t, est, ref))
    return ticks


def _state(stack):
    """The controller state a tick leaves behind (the layers' own attributes)."""
    sw = stack.inner.inner if isinstance(stack.inner, GroundEffectCompensation) else stack.inner
    ff = sw.free_flight
    last = sw.last
    return (
        ff.position.integral.tobytes(), ff._t_last, sw.mode,
        None if last is None else (np.asarray(last.rotor_speeds).tobytes(), last.thrust),
        [(s.t, s.from_mode, s.to_mode, s.thrust_jump, s.rotor_speed_jump) for s in sw.switches],
    )  # fmt: skip


def _command(cmd):
    torque = None if cmd.torque_B is None else np.asarray(cmd.torque_B).tobytes()
    return np.asarray(cmd.rotor_speeds).tobytes(), cmd.thrust, torque, dict(cmd.diagnostics)


@pytest.mark.parametrize("kind", ["hierarchical", "dfl"])
@pytest.mark.parametrize("ground_effect", [True, False])
def test_compiled_stack_commands_are_the_layers_bit_for_bit(kind, ground_effect):
    sc = load_scenario(
        "slope50", [f"controller.ground_effect_compensation={str(ground_effect).lower()}"]
    )
    layered = with_aero_belief(SwitchingController(sc, kind), sc, compiled=False)
    compiled = with_aero_belief(SwitchingController(sc, kind), sc)
    assert type(layered) is RotorDragCompensation
    assert type(compiled) is CompiledStack
    fused = divided = 0
    switching = compiled.layered.inner.inner if ground_effect else compiled.layered.inner
    for t, est, ref in _ticks(sc):
        a = layered.update(t, est, ref)
        b = compiled.update(t, est, ref)
        assert _command(a) == _command(b)
        assert _state(layered) == _state(compiled.layered)
        if ref.mode is FREE and ref.torque_ff_B is None and not ref.drag_in_rows:
            fused += 1
            # the ground effect acted on this tick: the speeds are not the mixer's
            divided += not np.array_equal(b.rotor_speeds, switching.last.rotor_speeds)
    assert fused > 100
    # with the layer, both of its outcomes were compared (divided near the surface)
    assert (10 < divided < fused) if ground_effect else divided == 0
    assert len(compiled.switches) == 4  # to tethered, to free, to motors off, to free


def test_a_heading_that_cannot_be_defined_raises_in_both():
    """A desired force along the heading x_C (the tilt limit lifted): the same error from
    the compiled call as from the layers."""
    sc = load_scenario("slope50")
    geo = LandingGeometry.from_scenario(sc)
    est = _estimate(0.002, geo.p_L + geo.surface.z_S, np.eye(3), np.zeros(3), np.zeros(3), None)
    rows = np.zeros((3, 3))
    rows[0] = est.body.p_W
    rows[2] = (1e12, 0.0, -9.81)  # F_d ~ m (1e12, 0, 0): z_B,d x x_C vanishes
    for stack in (with_aero_belief(SwitchingController(sc), sc, compiled=c) for c in (False, True)):
        stack.free_flight._par[PAR_TAN_MAX_TILT] = np.inf
        with pytest.raises(SingularityError, match="yaw undefined"):
            stack.update(0.002, est, Reference(0.002, FREE, 2, rows, 0.0))


def test_only_the_mission_composition_is_compiled():
    sc = load_scenario("slope50")
    # the contact-free tracker, a free-flight law alone, no rotor-drag layer: unchanged
    for ctrl in (FreeFlightTracker(sc), FreeFlightController(sc)):
        wrapped = with_aero_belief(ctrl, sc)
        assert type(wrapped) is RotorDragCompensation and wrapped is compiled_stack(wrapped)
    no_drag = load_scenario("slope50", ["controller.rotor_drag=[0.0, 0.0]"])
    assert type(with_aero_belief(SwitchingController(no_drag), no_drag)) is GroundEffectCompensation
    # the stack reaches the switching controller's attributes through its layers
    stack = with_aero_belief(SwitchingController(sc), sc)
    assert stack.switches is stack.layered.inner.inner.switches
