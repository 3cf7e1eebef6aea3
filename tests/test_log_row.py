"""LogRow: every part of a row lands in its named log column."""

from __future__ import annotations

import numpy as np

from tetherland.interfaces import Command, ControlMode, Reference, StateEstimate
from tetherland.sim.log import BASE_COLUMNS, LogWriter, diagnostic_columns
from tetherland.sim.log_row import LogRow
from tetherland.state import LinkState, RigidBodyState


def _row(n: int, width: int, start: float) -> np.ndarray:
    return start + np.arange(width) + 100.0 * n


def test_each_part_lands_in_its_columns() -> None:
    columns = BASE_COLUMNS + diagnostic_columns(("e_x", "ff_tension"))
    row = LogRow(columns)
    writer = LogWriter(columns, 1)  # grows to the second row
    for n in range(2):
        body = RigidBodyState(_row(n, 3, 1), _row(n, 3, 4), _row(n, 4, 7), _row(n, 3, 11))
        est = StateEstimate(0.1 * n, body, gyro_bias_B=_row(n, 3, 14), accel_bias_B=_row(n, 3, 17),
                            link=LinkState(0.1, 0.2, 0.3, 0.4 + n), tension=2.5 + n)  # fmt: skip
        ref = Reference(0.1 * n, mode=ControlMode.TETHERED, phase=7, yaw=0.25,
                        output=np.vstack([_row(n, 4, 20), np.zeros(4)]))  # fmt: skip
        cmd = Command(_row(n, 4, 30), thrust=None, torque_B=_row(n, 3, 34))
        row.truth_state[...] = _row(n, 13, 40)
        row.rotor_state[...] = _row(n, 15, 60)
        row.contact_peaks[...] = _row(n, 11, 80)
        row.hook_point[...] = _row(n, 3, 95)
        row.imu[...] = _row(n, 6, 200)
        row.imu_bias[...] = _row(n, 6, 210)
        row.mocap_pose[...] = _row(n, 7, 220)
        row.diagnostics[...] = (5.0 + n, 6.0)
        row.write(writer, _row(n, 3, 300), _row(n, 6, 310), 0.1 * n, est, ref, cmd, True,
                  0.05, 1.0)  # fmt: skip
    log = writer.finish({}, derived=False)
    assert len(log) == 2
    for n in range(2):
        expected = {
            "t": 0.1 * n, "phase": 7, "mode": 1, "hook": 1, "mocap_t": 0.05, "mocap_valid": 1,
            "est_tension": 2.5 + n, "ref_yaw": 0.25, "cmd_thrust": np.nan,
            "p_W": _row(n, 3, 40), "q_WB": _row(n, 4, 43), "v_W": _row(n, 3, 47),
            "omega_B": _row(n, 3, 50), "specific_force_B": _row(n, 3, 300),
            "tension": 310 + 100 * n, "cable_length": 311 + 100 * n,
            "lander_forces": _row(n, 4, 312), "rotor_speeds": _row(n, 4, 60),
            "rotor_thrusts": _row(n, 4, 64), "ground_effect": _row(n, 4, 68),
            "drag_force_W": _row(n, 3, 72), "lander_surface_forces": _row(n, 4, 80),
            "lander_ground_forces": _row(n, 4, 84), "frame_force": 88 + 100 * n,
            "frame_part": 89 + 100 * n, "penetration": 90 + 100 * n,
            "hook_p_W": _row(n, 3, 95), "imu_specific_force_B": _row(n, 3, 200),
            "imu_omega_B": _row(n, 3, 203), "imu_bias": _row(n, 6, 210),
            "mocap_p_W": _row(n, 3, 220), "mocap_q_WB": _row(n, 4, 223),
            "est_p_W": _row(n, 3, 1), "est_v_W": _row(n, 3, 4), "est_q_WB": _row(n, 4, 7),
            "est_omega_B": _row(n, 3, 11), "est_accel_bias_B": _row(n, 3, 17),
            "est_gyro_bias_B": _row(n, 3, 14), "est_link": [0.1, 0.2, 0.3, 0.4 + n],
            "ref_p_W": np.full(3, np.nan), "ref_output": _row(n, 4, 20),
            "cmd_rotor_speeds": _row(n, 4, 30), "cmd_torque_B": _row(n, 3, 34),
            "diag.e_x": 5.0 + n, "diag.ff_tension": 6.0,
        }  # fmt: skip
        assert set(expected) == set(log.names)
        for name, value in expected.items():
            np.testing.assert_array_equal(log[name][n], value, err_msg=name)


def test_the_finished_log_holds_the_written_rows_and_later_writes_do_not_touch_them() -> None:
    """``finish`` hands out the rows it wrote without a copy, the derived link angles
    beside them: rows written after it (the buffer growing into a new one on the way)
    leave that log as it was, and a second ``finish`` holds every row."""
    from tetherland.sim.log import DERIVED, link_angles_from_log

    columns = BASE_COLUMNS
    width = sum(c.width for c in columns)
    writer = LogWriter(columns, 3)
    rows = [np.linspace(0.0, 1.0, width) + 0.1 * n for n in range(5)]
    rows[0][3:10] = rows[1][3:10] = (0.3, -0.2, 1.1, 0.9, 0.1, 0.2, 0.3)  # p_W, q_WB
    geometry = {"p_A": np.array([0.5, 0.0, 1.0]), "R_WA": np.eye(3),
                "r_att_B": np.array([0.0, 0.0, -0.03])}  # fmt: skip
    for row in rows[:2]:
        writer.write(row)
    first = writer.finish({}, **geometry)
    assert first.columns == columns + DERIVED
    want = first.matrix.copy()
    np.testing.assert_array_equal(want[:, :width], np.vstack(rows[:2]))
    base = type(first)(columns, np.vstack(rows[:2]), {})
    phi, delta = link_angles_from_log(base, **geometry)
    np.testing.assert_array_equal(want[:, width], phi)
    np.testing.assert_array_equal(want[:, width + 1], delta)
    for row in rows[2:]:  # the fourth row grows the buffer
        writer.write(row)
    np.testing.assert_array_equal(first.matrix, want)
    second = writer.finish({}, **geometry)
    np.testing.assert_array_equal(second.matrix[:, :width], np.vstack(rows))
    np.testing.assert_array_equal(second.matrix[:2], want)
    np.testing.assert_array_equal(writer.last_row, rows[-1])
