"""Runner.steps (one control tick at a time, commanded from outside) and bound observers."""

from __future__ import annotations

import numpy as np
import pytest

from tetherland.config import load_scenario
from tetherland.control import FreeFlightController
from tetherland.estimation import UkfEstimator
from tetherland.interfaces import Reference
from tetherland.models.quadrotor import RotorModel
from tetherland.sim import BoundObserver, ControlTick, Plant, Runner
from tetherland.sim.log import RunStatus
from tetherland.state import RigidBodyState


class Hold:
    def __init__(self, p):
        self.p = np.array([p, np.zeros(3), np.zeros(3)])

    def reference(self, t, est):
        return Reference(t=t, p_W=self.p)


class RowRecorder:
    """Bound observer: copies every row as it is written."""

    def __init__(self) -> None:
        self.rows: list[np.ndarray] = []
        self.runner = None

    def bind(self, runner, writer) -> None:
        self.runner, self.writer, self.rows = runner, writer, []

    def __call__(self, t, plant) -> None:
        self.rows.append(self.writer.last_row.copy())


@pytest.fixture(scope="module")
def setup():
    sc = load_scenario("slope50")
    plant = Plant(sc)
    target = plant.start_state().p_W + np.array([0.0, 0.0, 1.0])
    x0 = RigidBodyState.at_rest(target + np.array([0.02, 0.0, -0.01]))
    w0 = RotorModel.from_config(sc.vehicle).speed(np.full(4, sc.vehicle.mass * 9.81 / 4))

    def runner(observers=()):
        est = UkfEstimator(sc, x0, 0.0, rotor_speeds0=w0)
        return Runner(sc, FreeFlightController(sc), estimator=est, reference=Hold(target), seed=3,
                      plant=plant, observers=observers)  # fmt: skip

    return sc, x0, w0, runner


def test_steps_driven_by_the_same_controller_reproduce_run(setup):
    """Sending the controller's own commands through steps() gives run()'s log exactly."""
    sc, x0, w0, make = setup
    recorder = RowRecorder()
    assert isinstance(recorder, BoundObserver)
    log = make([recorder]).run(0.6, initial_state=x0, rotor_speeds=w0)
    runner = make()
    controller = FreeFlightController(sc)
    loop = runner.steps(0.6, initial_state=x0, rotor_speeds=w0)
    ticks = 0
    tick = next(loop)
    try:
        while True:
            assert isinstance(tick, ControlTick)
            assert tick.t == pytest.approx(ticks / sc.controller.rate_hz)
            ticks += 1
            tick = loop.send(controller.update(tick.t, tick.estimate, tick.reference))
    except StopIteration as done:
        stepped = done.value
    assert ticks == len(log) == 300
    assert stepped.status == log.status == RunStatus.COMPLETED
    np.testing.assert_array_equal(stepped.matrix, log.matrix)
    # the bound observer saw every row as written (derived columns are added at the end)
    assert recorder.runner is not None
    np.testing.assert_array_equal(np.array(recorder.rows), log.matrix[:, : len(recorder.rows[0])])


def test_steps_hold_the_command_sent(setup):
    """The command sent at tick k is what the plant holds from t_k + dt (motor lag aside)."""
    _, x0, w0, make = setup
    runner = make()
    loop = runner.steps(0.1, initial_state=x0, rotor_speeds=w0)
    next(loop)
    w = np.array([500.0, 550.0, 600.0, 650.0])  # below w_max = 775 rad/s
    from tetherland.interfaces import Command

    for _ in range(3):
        loop.send(Command(rotor_speeds=w))
    np.testing.assert_array_equal(runner.plant.commanded_speeds, w)
    loop.close()
