"""Multi-rate closed loop: plant 1 kHz, IMU 1 kHz, mocap 120 Hz (late), control 500 Hz.

Every rate is scheduled on the integer physics tick k (t_k = k dt), so nothing drifts:
the IMU samples every ``N/f_imu`` ticks, the controller runs every ``N/f_ctrl`` ticks, and
mocap sample j is taken at the first tick at or after j/f_mocap (exact rational arithmetic,
so 120 Hz on a 1 kHz plant alternates 8- and 9-tick gaps) and delivered
``round(latency/dt)`` ticks later. At tick k:

1. the plant steps from t_k to t_{k+1} with the held command (sensors read at t_k);
2. IMU tick: a sample stamped t_k goes to ``estimator.predict`` (to an ``ImuBatchAware``
   estimator as a row, the rows handed over before the next update or estimate: the
   same order, without a record per sample);
3. mocap tick: the pose at t_k is measured and queued; due samples go to ``estimator.update``;
4. control tick: ``estimate()``, ``reference(t_k, est)``, ``controller.update(t_k, est, ref)``;
   the command is held from t_{k+1} on (one physics step of compute/transport delay, then
   the motor lag), and one log row is written with everything at t_k.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Callable, Generator, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from fractions import Fraction
from typing import Any, Protocol, runtime_checkable

import numpy as np

from tetherland.config import Scenario
from tetherland.config.checks import mocap_rate, ticks_per_sample
from tetherland.errors import ConfigError, SimulationError, TetherlandError
from tetherland.geometry import FloatArray
from tetherland.interfaces import (
    Command,
    CommandAware,
    Controller,
    Estimator,
    EventSource,
    ImuBatchAware,
    InnerLoop,
    MagnetCommander,
    MocapSample,
    Reference,
    ReferenceSource,
    StateEstimate,
)
from tetherland.provenance import provenance
from tetherland.randomness import RandomSource
from tetherland.sim.baselines import ConstantReference, TruthEstimator
from tetherland.sim.faults import FaultInjector, mocap_outage
from tetherland.sim.log import BASE_COLUMNS, LogWriter, RunStatus, SimLog, diagnostic_columns
from tetherland.sim.log_row import LogRow
from tetherland.sim.mjcf import FRAME_PARTS, SENSOR_SLICES
from tetherland.sim.plant import Plant, link_state_of
from tetherland.sim.sensors import Imu, Mocap
from tetherland.state import RigidBodyState

Observer = Callable[[float, Plant], None]
"""Called at every control tick after the command, with (t_k, plant); e.g. a video recorder."""


@runtime_checkable
class BoundObserver(Protocol):
    """Optional observer capability: bound to the runner and its log writer before a run.

    :meth:`bind` is called once at the start of each run; the observer may then read the
    row just written (``writer.last_row``) when it is called at each control tick.
    """

    def bind(self, runner: Runner, writer: LogWriter) -> None:
        """The run is about to start: ``runner`` and the ``writer`` of its log."""
        ...

    def __call__(self, t: float, plant: Plant) -> None: ...


@dataclass(frozen=True, slots=True)
class ControlTick:
    """What :meth:`Runner.steps` yields at each control tick (before the command).

    Attributes
    ----------
    t : float
        Time of the control tick t_k [s].
    estimate : StateEstimate
        The estimator's output at t_k.
    reference : Reference
        The reference source's output at t_k.
    """

    t: float
    estimate: StateEstimate
    reference: Reference


@dataclass(frozen=True)
class Schedule:
    """Integer-tick schedule of every rate (validated against the physics rate).

    Attributes
    ----------
    steps_per_second : int
        Physics rate N = 1/dt [Hz].
    imu_every, control_every : int
        Physics ticks per IMU sample and per control update.
    mocap_rate : Fraction
        Mocap rate as an exact fraction [Hz].
    mocap_latency_ticks : int
        Mocap delivery delay in physics ticks.
    """

    steps_per_second: int
    imu_every: int
    control_every: int
    mocap_rate: Fraction
    mocap_latency_ticks: int

    @classmethod
    def from_scenario(cls, scenario: Scenario) -> Schedule:
        # the scenario's own rate rules (tetherland.config.checks): a Scenario that
        # validated has rates that fit; a ValueError here is one built unvalidated
        N = scenario.sim.steps_per_second
        imu, mocap, control = scenario.sensors.imu, scenario.sensors.mocap, scenario.controller
        try:
            return cls(
                steps_per_second=N,
                imu_every=ticks_per_sample(imu.rate_hz, N, "sensors.imu.rate_hz"),
                control_every=ticks_per_sample(control.rate_hz, N, "controller.rate_hz"),
                mocap_rate=mocap_rate(mocap.rate_hz, N),
                mocap_latency_ticks=round(mocap.latency * N),
            )
        except ValueError as err:
            raise ConfigError(str(err)) from None

    def mocap_tick(self, j: int) -> int:
        """Physics tick of mocap sample j: the first tick at or after j / f_mocap."""
        num = j * self.steps_per_second * self.mocap_rate.denominator
        return -(-num // self.mocap_rate.numerator)

    def as_dict(self) -> dict[str, Any]:
        return {
            "physics_hz": self.steps_per_second,
            "imu_hz": self.steps_per_second / self.imu_every,
            "control_hz": self.steps_per_second / self.control_every,
            "mocap_hz": float(self.mocap_rate),
            "mocap_latency_s": self.mocap_latency_ticks / self.steps_per_second,
        }


class Runner:
    """Runs a controller, an estimator and a reference source against the plant.

    Parameters
    ----------
    scenario : Scenario
        Everything physical, the sensor settings and all rates.
    controller : Controller
    estimator : Estimator, optional
        Default: :class:`TruthEstimator` (the ground truth at each control tick, with the
        true cable tension, and the true link state while the cable is engaged).
    reference : ReferenceSource, optional
        Default: hold the initial position in free flight.
    seed : int
        Seed of the sensor noise: the ``imu`` and ``mocap`` streams of ``RandomSource(seed)``
        (:mod:`tetherland.randomness`), unless :meth:`run` is given a random source.
    plant : Plant, optional
        Reuse an existing plant (it is reset at each :meth:`run`).
    diagnostic_keys : sequence of str
        ``Command.diagnostics`` entries to record as ``diag.<key>`` columns.
    observers : sequence of callables
        Called as ``observer(t_k, plant)`` after every control tick.
    inner_loop : InnerLoop, optional
        A flight controller between the controller and the rotors: it gets each command
        as a setpoint and each IMU sample, and its output is what the rotors are held at.
    """

    def __init__(
        self,
        scenario: Scenario,
        controller: Controller,
        *,
        estimator: Estimator | None = None,
        reference: ReferenceSource | None = None,
        seed: int = 0,
        plant: Plant | None = None,
        diagnostic_keys: Sequence[str] = (),
        observers: Sequence[Observer] = (),
        inner_loop: InnerLoop | None = None,
    ) -> None:
        if not isinstance(controller, Controller):
            raise TypeError(f"{type(controller).__name__} does not implement Controller.update")
        if estimator is not None and not isinstance(estimator, Estimator):
            raise TypeError(f"{type(estimator).__name__} does not implement the Estimator protocol")
        if reference is not None and not isinstance(reference, ReferenceSource):
            raise TypeError(f"{type(reference).__name__} does not implement ReferenceSource")
        if plant is not None and plant.scenario != scenario:
            raise ValueError("the plant was built for another scenario than the runner's")
        self.scenario = scenario
        self.schedule = Schedule.from_scenario(scenario)
        self.plant = Plant(scenario) if plant is None else plant
        self.controller = controller
        self.estimator = TruthEstimator(self._truth_estimate) if estimator is None else estimator
        self.reference = reference
        self.seed = int(seed)
        self.diagnostic_keys = tuple(diagnostic_keys)
        self.observers = tuple(observers)
        if inner_loop is not None and not isinstance(inner_loop, InnerLoop):
            raise TypeError(f"{type(inner_loop).__name__} does not implement InnerLoop")
        self.inner_loop = inner_loop
        if scenario.faults.active:  # the plant-side faults of [faults] (sim/faults.py)
            self.observers += (FaultInjector(scenario.faults),)
        self._snap = np.zeros(13)  # [qpos (7), qvel (6)] at the control tick
        self._t_snap = 0.0
        geo = self.plant.layout.geometry
        self._r_att = np.asarray(scenario.vehicle.cable_attachment, dtype=float)
        self._p_A, self._R_WA = geo.p_A, geo.R_WA
        self._cable_force_index = SENSOR_SLICES["cable_force"].start
        self._accelerometer = SENSOR_SLICES["accelerometer"]
        self._provenance: dict[str, Any] | None = None

    def _truth_estimate(self) -> StateEstimate:
        """Ground truth at the current tick; the link state only while the cable is engaged."""
        s = self._snap.copy()
        plant = self.plant
        engaged = plant.hook.engaged
        external_B = self.scenario.vehicle.mass * plant.sensordata[self._accelerometer]
        external_B[2] -= float(plant.rotor_thrusts.sum())
        return StateEstimate(
            t=self._t_snap,
            body=RigidBodyState(s[0:3], s[7:10], s[3:7], s[10:13]),
            link=link_state_of(s, self._r_att, self._p_A, self._R_WA) if engaged else None,
            tension=plant.sensordata[self._cable_force_index].item(),
            external_force_B=external_B,
        )

    def run(
        self,
        duration: float,
        *,
        initial_state: RigidBodyState | None = None,
        rotor_speeds: FloatArray | None = None,
        cable_engaged: bool = False,
        random: RandomSource | None = None,
    ) -> SimLog:
        """Simulate ``duration`` seconds (or until the reference asks to terminate).

        Parameters
        ----------
        duration
            Simulated time [s]; rounded down to whole control periods.
        initial_state
            Vehicle state at t = 0 (default: on the start pad).
        rotor_speeds
            Initial rotor speeds and held command (default: stopped) [rad/s].
        cable_engaged
            Start hooked.
        random
            Random source of the sensor noise, its ``imu`` and ``mocap`` streams (default:
            ``RandomSource(seed)``, :mod:`tetherland.randomness`).

        Returns
        -------
        SimLog
            One row per control tick; ``log.status`` tells how the run ended.
        """
        loop = self._loop(duration, initial_state, rotor_speeds, cable_engaged, random, False)
        try:
            next(loop)
        except StopIteration as done:
            return done.value
        raise AssertionError("the loop yielded a control tick with the controller in charge")

    def steps(
        self,
        duration: float,
        *,
        initial_state: RigidBodyState | None = None,
        rotor_speeds: FloatArray | None = None,
        cable_engaged: bool = False,
        random: RandomSource | None = None,
    ) -> Generator[ControlTick, Command, SimLog]:
        """The loop of :meth:`run`, one control tick at a time, commanded from outside.

        The generator yields a :class:`ControlTick` at each control tick; ``send(command)``
        holds ``command`` (instead of calling the runner's controller) and advances to the
        next control tick. It returns the :class:`SimLog` (``StopIteration.value``) when
        the duration is over, the reference terminates or the run fails. Arguments as for
        :meth:`run`.
        """
        return self._loop(duration, initial_state, rotor_speeds, cable_engaged, random, True)

    def _loop(
        self,
        duration: float,
        initial_state: RigidBodyState | None,
        rotor_speeds: FloatArray | None,
        cable_engaged: bool,
        random: RandomSource | None,
        external: bool,
    ) -> Generator[ControlTick, Command, SimLog]:
        if not (duration > 0 and math.isfinite(duration)):
            raise ValueError(f"duration must be a positive number of seconds, got {duration}")
        sc, sched, plant = self.scenario, self.schedule, self.plant
        plant.reset(initial_state, rotor_speeds=rotor_speeds, cable_engaged=cable_engaged)
        random = RandomSource(self.seed) if random is None else random
        imu = Imu(sc.sensors.imu, random.stream("imu"), sc.sensors.noise_scale)
        mocap = Mocap(sc.sensors.mocap, random.stream("mocap"), sc.sensors.noise_scale,
                      mocap_outage(sc.faults))  # fmt: skip
        reference = self.reference
        if reference is None:
            reference = ConstantReference(p_W=plant.qpos[0:3].copy())
        estimator, controller = self.estimator, self.controller
        # told each command sent (CommandAware): e.g. tension estimation, a fault monitor
        estimator_sent = estimator.command_sent if isinstance(estimator, CommandAware) else None
        reference_sent = reference.command_sent if isinstance(reference, CommandAware) else None
        # the robot's EPM and latch commands (the magnet mechanism), passed on at every
        # control tick
        magnet = reference if plant.has_magnet and isinstance(reference, MagnetCommander) else None

        n_ctrl = sched.control_every
        n_ticks = round(duration * sched.steps_per_second) // n_ctrl * n_ctrl
        columns = BASE_COLUMNS + diagnostic_columns(self.diagnostic_keys)
        writer = LogWriter(columns, n_ticks // n_ctrl)
        dt = plant.dt
        sd = plant.sensordata
        imu_truth = sd[0:6]
        sd_rest = sd[SENSOR_SLICES["cable_force"].start : SENSOR_SLICES["lander3_touch"].stop]
        # the row of the next control tick, its fixed parts refilled in place (views of it)
        row = LogRow(columns)
        qpos, qvel = plant.qpos, plant.qvel
        self._snap = snap = row.truth_state
        # (``view[...] = values`` is numpy's cheapest copy into a view from Python)
        snap_q, snap_v, snap_p, snap_att = snap[0:7], snap[7:13], snap[0:3], snap[3:7]
        rotor_buf, contact_buf, hook_buf = row.rotor_state, row.contact_peaks, row.hook_point
        hook_point_into = plant.hook_point_into
        # last IMU sample, its true biases, last delivered mocap pose
        imu_y, bias_buf, mocap_pq = row.imu, row.imu_bias, row.mocap_pose
        imu_f, imu_w, mocap_p, mocap_q = imu_y[0:3], imu_y[3:6], mocap_pq[0:3], mocap_pq[3:7]
        mocap_t, mocap_valid = math.nan, math.nan
        queue: deque[tuple[int, MocapSample]] = deque()
        j_mocap, next_mocap = 0, 0
        imu_every, lat = sched.imu_every, sched.mocap_latency_ticks
        diag_keys = self.diagnostic_keys

        status, message, k = RunStatus.COMPLETED, "", 0
        # Bound methods and views as locals: this loop runs at the physics rate.
        step, imu_sample, predict, update = (
            plant.step,
            imu.sample,
            estimator.predict,
            estimator.update,
        )
        estimate, get_reference, control = (
            estimator.estimate,
            reference.reference,
            controller.update,
        )
        command, mocap_measure, mocap_tick = plant.command, mocap.measure, sched.mocap_tick
        write_row, rotor_state_into, bias_into, contact_peaks_into = (
            row.write,
            plant.rotor_state_into,
            imu.bias_into,
            plant.contact_peaks_into,
        )
        observers = self.observers
        for observer in observers:
            if isinstance(observer, BoundObserver):
                observer.bind(self, writer)
        hook = plant.hook
        specific_force, diag_buf = sd[0:3], row.diagnostics
        nans = [math.nan] * len(diag_keys)
        inner = self.inner_loop
        # An ImuBatchAware estimator gets the IMU samples as rows, before each motion-capture
        # update and each estimate (with the firmware's inner loop: one record per sample).
        batch = (
            estimator.predict_rows
            if inner is None and isinstance(estimator, ImuBatchAware)
            else None
        )
        n_rows = n_ctrl // imu_every + 1  # (samples between two hand-overs, at most)
        imu_rows = np.empty((n_rows, 7))
        imu_row = list(imu_rows)  # row views: [t, f_B, omega_B]
        imu_batch = [imu_rows[:j] for j in range(n_rows + 1)]
        imu_sample_into, n_imu, last_imu = imu.sample_into, 0, imu_row[0]
        wall0 = time.perf_counter()
        try:
            if inner is not None:
                inner.start()
            for k in range(n_ticks):
                control_tick = k % n_ctrl == 0
                if control_tick or k == next_mocap:
                    snap_q[...] = qpos
                    snap_v[...] = qvel
                    self._t_snap = k * dt
                    if control_tick:
                        rotor_state_into(rotor_buf)
                        hook_point_into(hook_buf)
                step()
                if k % imu_every == 0:
                    if batch is not None:
                        if n_imu == n_rows:
                            batch(imu_rows)
                            n_imu = 0
                        last_imu = imu_row[n_imu]
                        imu_sample_into(k * dt, imu_truth, last_imu)
                        n_imu += 1
                    else:
                        sample = imu_sample(k * dt, imu_truth)
                        predict(sample)
                        if inner is not None:
                            command(inner.step(sample))
                if k == next_mocap:
                    t_del = k + lat
                    queue.append((t_del, mocap_measure(k * dt, snap_p, snap_att, t_del * dt)))
                    j_mocap += 1
                    next_mocap = mocap_tick(j_mocap)
                if queue and queue[0][0] <= k:
                    if n_imu:
                        batch(imu_batch[n_imu])  # type: ignore[misc]
                        n_imu = 0
                    while queue and queue[0][0] <= k:
                        m = queue.popleft()[1]
                        update(m)
                    mocap_t, mocap_valid = m.t_measured, float(m.valid)
                    mocap_p[...] = m.p_W
                    mocap_q[...] = m.q_WB
                if not control_tick:
                    continue
                t_k = k * dt
                if n_imu:
                    batch(imu_batch[n_imu])  # type: ignore[misc]
                    n_imu = 0
                est = estimate()
                ref = get_reference(t_k, est)
                if magnet is not None:
                    plant.set_magnet(magnet.magnet_on)
                    plant.set_latch(magnet.latch_open)
                cmd = (yield ControlTick(t_k, est, ref)) if external else control(t_k, est, ref)
                if inner is None:
                    command(cmd.rotor_speeds)
                else:
                    inner.setpoint(t_k, est, ref, cmd)
                    cmd = inner.applied(cmd)
                if estimator_sent is not None:
                    estimator_sent(t_k + dt, cmd)
                if reference_sent is not None:
                    reference_sent(t_k + dt, cmd)
                if batch is None:
                    imu_f[...] = sample.specific_force_B  # the last sample (k = 0: an IMU tick)
                    imu_w[...] = sample.omega_B
                else:
                    imu_y[...] = last_imu[1:7]
                bias_into(bias_buf)
                contact_peaks_into(contact_buf)
                if diag_keys:
                    diag_buf[...] = list(map(cmd.diagnostics.get, diag_keys, nans))
                write_row(writer, specific_force, sd_rest, t_k, est, ref, cmd, hook.engaged,
                          mocap_t, mocap_valid)  # fmt: skip
                for observer in observers:
                    observer(t_k, plant)
                if ref.terminate:
                    status = RunStatus.TERMINATED
                    message = f"reference terminated at t = {t_k:.3f} s"
                    break
            if n_imu:  # the samples after the last control tick, as predict would have
                batch(imu_batch[n_imu])  # type: ignore[misc]
        except SimulationError as err:
            status, message = RunStatus.DIVERGED, str(err)
        except TetherlandError as err:
            status, message = RunStatus.FAILED, f"t = {k * dt:.4f} s: {err}"
        finally:
            if inner is not None:
                inner.stop()
        wall = time.perf_counter() - wall0
        return writer.finish(
            self._metadata(status, message, k, wall, reference, random.seed),
            p_A=self._p_A,
            R_WA=self._R_WA,
            r_att_B=self._r_att,
        )

    def _metadata(
        self,
        status: RunStatus,
        message: str,
        k: int,
        wall: float,
        reference: ReferenceSource,
        seed: int,
    ) -> dict[str, Any]:
        events = [dict(e.as_dict(), source="hook") for e in self.plant.hook.events]
        if isinstance(reference, EventSource):
            events += [e.as_dict() for e in reference.events]
        events.sort(key=lambda e: float(e["t"]))  # type: ignore[arg-type]
        sim_time = (k + 1) * self.plant.dt
        if self._provenance is None:  # git and package metadata: once per runner
            self._provenance = provenance(self.scenario, seed=self.seed)
        prov = dict(self._provenance)
        prov["created_utc"] = datetime.now(UTC).isoformat(timespec="seconds")
        prov["seed"] = seed  # of the random source the run drew from
        return {
            "provenance": prov,
            "status": status.value,
            "message": message,
            "rates": self.schedule.as_dict(),
            "events": events,
            "sim_time_s": sim_time,
            "wall_time_s": wall,
            "real_time_factor": sim_time / wall if wall > 0 else math.inf,
            "controller": type(self.controller).__name__,
            "estimator": type(self.estimator).__name__,
            "inner_loop": None if self.inner_loop is None else type(self.inner_loop).__name__,
            "reference": type(reference).__name__,
            "anchor_W": self._p_A,
            "R_WA": self._R_WA,
            "cable_attachment_B": self._r_att,
            "frame_parts": list(FRAME_PARTS),
        }


__all__ = ["BoundObserver", "ControlTick", "Observer", "Runner", "Schedule"]
