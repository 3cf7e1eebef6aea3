"""The run log's row under construction: one buffer, the runner's parts as views of it.

At each control tick the runner writes one row of the :class:`~tetherland.sim.log.SimLog`
schema (:data:`~tetherland.sim.log.BASE_COLUMNS` then the diagnostics). Most of a row
is refilled in place by the parts that produce it (the plant's rotor state and contact
peaks, the truth snapshot, the last IMU sample and mocap pose): each gets a view of the
one row buffer, :class:`LogRow`, so that nothing has to be gathered from separate
buffers. What is new at each tick (the scalars, the sensor readings of the plant, the
estimate, reference and command) is written by :meth:`LogRow.write`, which then appends
the whole buffer to the :class:`~tetherland.sim.log.LogWriter` with one copy.
"""

from __future__ import annotations

import math

import numpy as np

from tetherland.geometry import FloatArray
from tetherland.interfaces import Command, Reference, StateEstimate
from tetherland.sim.log import BASE_COLUMNS, Column, LogWriter, row_width
from tetherland.sim.plant import CONTACT_PEAK_WIDTH, ROTOR_STATE_WIDTH

_NAN3 = np.full(3, np.nan)
_NAN3.setflags(write=False)
_NAN4 = np.full(4, np.nan)
_NAN4.setflags(write=False)


def _span(first: str, last: str, width: int) -> slice:
    """Columns ``first`` to ``last`` (inclusive) of the base schema, which must be
    ``width`` wide: the row parts below rely on these groups being adjacent."""
    names = [c.name for c in BASE_COLUMNS]
    i, j = names.index(first), names.index(last)
    start = row_width(BASE_COLUMNS[:i])
    stop = row_width(BASE_COLUMNS[: j + 1])
    if stop - start != width:
        raise AssertionError(f"log columns {first}..{last} are {stop - start} wide, not {width}")
    return slice(start, stop)


SCALARS = _span("t", "cmd_thrust", 9)
"""t, phase, mode, hook, mocap_t, mocap_valid, est_tension, ref_yaw, cmd_thrust."""
TRUTH_STATE = _span("p_W", "omega_B", 13)
"""The true state [p_W, q_WB, v_W, omega_B]: MuJoCo's qpos then qvel of the vehicle."""
SPECIFIC_FORCE = _span("specific_force_B", "specific_force_B", 3)
SENSORS = _span("tension", "lander_forces", 6)
"""The plant's sensors after the IMU's: cable force, cable length, lander touch (4)."""
ROTOR_STATE = _span("rotor_speeds", "drag_force_W", ROTOR_STATE_WIDTH)
""":meth:`Plant.rotor_state_into`: speeds, thrusts, surface factors, aero force."""
CONTACT_PEAKS = _span("lander_surface_forces", "penetration", CONTACT_PEAK_WIDTH)
""":meth:`Plant.contact_peaks_into`."""
HOOK_POINT = _span("hook_p_W", "hook_p_W", 3)
IMU = _span("imu_specific_force_B", "imu_omega_B", 6)
IMU_BIAS = _span("imu_bias", "imu_bias", 6)
MOCAP_POSE = _span("mocap_p_W", "mocap_q_WB", 7)
DECISIONS = _span("est_p_W", "cmd_torque_B", 37)
"""What the robot believed, wanted and commanded: the estimate, reference and command."""


class LogRow:
    """The row of the next control tick, its parts as named views of one buffer.

    Parameters
    ----------
    columns : tuple of Column
        The run's schema: :data:`~tetherland.sim.log.BASE_COLUMNS`, then the diagnostics
        (one column each).

    Attributes
    ----------
    values : (width,) array
        The whole row, NaN until written.
    truth_state, rotor_state, contact_peaks, hook_point, imu, imu_bias, mocap_pose : arrays
        Views of ``values`` that their producers refill in place (see the module doc and
        the slices of this module for what each holds).
    diagnostics : (n_diagnostics,) array
        The ``diag.<key>`` columns.
    """

    def __init__(self, columns: tuple[Column, ...]) -> None:
        base = len(BASE_COLUMNS)
        if columns[:base] != BASE_COLUMNS:
            raise ValueError("a log row's columns start with the base columns")
        self.values = values = np.full(row_width(columns), np.nan)
        self.truth_state = values[TRUTH_STATE]
        self.rotor_state = values[ROTOR_STATE]
        self.contact_peaks = values[CONTACT_PEAKS]
        self.hook_point = values[HOOK_POINT]
        self.imu = values[IMU]
        self.imu_bias = values[IMU_BIAS]
        self.mocap_pose = values[MOCAP_POSE]
        self.diagnostics = values[row_width(BASE_COLUMNS) :]
        self._scalars = values[SCALARS]
        self._specific_force = values[SPECIFIC_FORCE]
        self._sensors = values[SENSORS]
        self._decisions = values[DECISIONS]

    def write(
        self,
        writer: LogWriter,
        specific_force_B: FloatArray,
        sensors: FloatArray,
        t: float,
        estimate: StateEstimate,
        reference: Reference,
        command: Command,
        engaged: bool,
        mocap_t: float,
        mocap_valid: float,
    ) -> None:
        """Fill in what is new at control tick ``t`` and append the row to ``writer``.

        Parameters
        ----------
        writer : LogWriter
            The run's log.
        specific_force_B : (3,) array
            True specific force (the plant's accelerometer sensor) [m/s^2].
        sensors : (6,) array
            The plant's cable force [N], cable length [m] and lander touch forces [N].
        t : float
            Time of the control tick [s].
        estimate, reference, command
            What the estimator, the reference source and the controller gave at ``t``.
        engaged : bool
            The cable is hooked (plant truth).
        mocap_t, mocap_valid : float
            Measurement time [s] and validity (1 or 0) of the last delivered mocap sample
            (NaN before any).
        """
        self._scalars[...] = (
            t,
            reference.phase,
            reference.mode,
            engaged,
            mocap_t,
            mocap_valid,
            math.nan if estimate.tension is None else estimate.tension,
            reference.yaw,
            math.nan if command.thrust is None else command.thrust,
        )
        self._specific_force[...] = specific_force_B
        self._sensors[...] = sensors
        b, link, p_W, output = estimate.body, estimate.link, reference.p_W, reference.output
        np.concatenate(
            (
                b.p_W,
                b.v_W,
                b.q_WB,
                b.omega_B,
                _NAN3 if estimate.accel_bias_B is None else estimate.accel_bias_B,
                _NAN3 if estimate.gyro_bias_B is None else estimate.gyro_bias_B,
                _NAN4 if link is None else (link.phi, link.delta, link.phi_dot, link.delta_dot),
                _NAN3 if p_W is None else p_W[0],
                _NAN4 if output is None else output[0],
                command.rotor_speeds,
                _NAN3 if command.torque_B is None else command.torque_B,
            ),
            out=self._decisions,
        )
        writer.write(self.values)


__all__ = ["LogRow"]
