"""The compiled per-tick kernels of the mission glue give their plain forms' bits (issue 25).

Each kernel compiled for the control loop (rotation matrix of a quaternion, the
free-flight path's rows) is compared with the plain
Python form beside it with exact equality: the default missions' logs must not change by
a bit. Inputs the kernels do not take (lists, other dtypes, read-only arrays) must fall
back to the plain forms, with the same result. The vectorised attitude angles of the MCAP
export and the figures likewise give the per-attitude bits.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from rounding import assert_same
from tetherland.geometry import theta_A_from_z_B, theta_A_from_z_B_many
from tetherland.mission.paths import Path, ZVShaper, path_rows, path_rows_reference
from tetherland.planning.spline import smoothstep9_scalar
from tetherland.report.figures import robot_angles
from tetherland.rotations import (
    _quat_to_rotmat_into,
    quat_to_rotmat,
    quat_to_rotmat_reference,
    quat_to_rotmat_stack,
)


def _unit_quats(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    return q / np.linalg.norm(q, axis=1)[:, None]


def test_compiled_rotation_matrix_has_the_reference_bits():
    """Unit quaternions, near-identity ones and unnormalised ones: the same bits; the
    kernel itself is what runs for a float64 vector (a view into a state vector too)."""
    rng = np.random.default_rng(25)
    quats = np.concatenate((
        _unit_quats(rng, 20000),
        np.array([1.0, 0.0, 0.0, 0.0]) + 1e-9 * rng.normal(size=(2000, 4)),
        rng.normal(size=(2000, 4)) * 3.0,
    ))  # fmt: skip
    for q in quats:
        expected = quat_to_rotmat_reference(q)
        R = np.full((3, 3), np.nan)
        _quat_to_rotmat_into(q, R)
        assert np.array_equal(R, expected)
        assert np.array_equal(quat_to_rotmat(q), expected)
    state = np.concatenate((rng.normal(size=3), quats[0], rng.normal(size=6)))
    assert np.array_equal(quat_to_rotmat(state[3:7]), quat_to_rotmat_reference(quats[0]))
    strided = np.zeros(8)
    strided[::2] = quats[1]
    assert np.array_equal(quat_to_rotmat(strided[::2]), quat_to_rotmat_reference(quats[1]))


def _robot_angles_per_attitude(q_WB, R_WA, phi, delta):
    """robot_angles as it was written, one attitude at a time (the reference)."""
    n = len(q_WB)
    roll, theta, psi = np.empty(n), np.empty(n), np.empty(n)
    for i in range(n):
        R_AB = R_WA.T @ quat_to_rotmat(q_WB[i])
        z = R_AB[:, 2]
        th_e = math.atan2(z[0], z[2])
        roll[i] = math.atan2(-z[1], math.hypot(z[0], z[2]))
        c_t, s_t, c_r, s_r = math.cos(th_e), math.sin(th_e), math.cos(roll[i]), math.sin(roll[i])
        M = np.array([[c_t, s_t * s_r, s_t * c_r], [0.0, c_r, -s_r], [-s_t, c_t * s_r, c_t * c_r]])
        Rz = M.T @ R_AB
        psi[i] = math.atan2(Rz[1, 0], Rz[0, 0])
        try:
            theta[i] = theta_A_from_z_B(z, phi[i], delta[i])
        except ArithmeticError:
            theta[i] = math.nan
    return roll, theta, psi


def test_vectorised_attitude_angles_have_the_per_attitude_bits():
    """The stacked rotation matrices, theta_A and robot_angles (the MCAP export's and the
    figures' angles) over many attitudes: exactly the per-attitude values, NaN where the
    thrust axis is perpendicular to the link plane."""
    rng = np.random.default_rng(26)
    q = np.concatenate((_unit_quats(rng, 3000),
                        np.array([1.0, 0.0, 0.0, 0.0]) + 1e-9 * rng.normal(size=(300, 4))))
    R = quat_to_rotmat_stack(q)
    assert all(np.array_equal(R[i], quat_to_rotmat_reference(q[i])) for i in range(len(q)))
    phi, delta = rng.uniform(-1.5, 1.5, len(q)), rng.uniform(-0.6, 0.6, len(q))
    z = R[:, :, 2].copy()
    y_L = np.column_stack((np.cos(phi) * np.sin(delta), np.cos(delta), np.sin(phi) * np.sin(delta)))
    z[:5] = y_L[:5]  # along y_L: no tilt defined
    expected = []
    for z_i, p, d in zip(z, phi, delta, strict=True):
        try:
            expected.append(theta_A_from_z_B(z_i, p, d))
        except ArithmeticError:
            expected.append(math.nan)
    theta = theta_A_from_z_B_many(z, phi, delta)
    # (where numpy's BLAS sums its dot products in another order, tests/rounding.py: to
    # the rounding of the 3-term products and the angle's arctangent, radians of order 1)
    assert_same(theta, expected, ulps=8, equal_nan=True)
    assert np.isnan(theta[:5]).all()
    R_WA = quat_to_rotmat_reference(_unit_quats(rng, 1)[0])
    got = robot_angles(q, R_WA, phi, delta)
    for a, b in zip(got, _robot_angles_per_attitude(q, R_WA, phi, delta), strict=True):
        assert_same(a, b, ulps=8, equal_nan=True)
    assert [len(a) for a in robot_angles(q[:0], R_WA, phi[:0], delta[:0])] == [0, 0, 0]


def test_rotation_matrix_takes_what_the_kernel_does_not():
    """Lists, integers, float32 and read-only arrays go through the plain form (float64
    arithmetic on the float64 values); a vector of the wrong length is refused."""
    q = _unit_quats(np.random.default_rng(3), 1)[0]
    frozen = q.copy()
    frozen.setflags(write=False)
    expected = quat_to_rotmat_reference(q)
    assert np.array_equal(quat_to_rotmat(frozen), expected)
    assert np.array_equal(quat_to_rotmat(q.tolist()), expected)
    assert np.array_equal(quat_to_rotmat(np.array([1, 0, 0, 0])), np.eye(3))
    q32 = q.astype(np.float32)
    assert np.array_equal(quat_to_rotmat(q32), quat_to_rotmat_reference(q32.astype(float)))
    with pytest.raises(ValueError):
        quat_to_rotmat(np.zeros(3))


def test_compiled_path_rows_have_the_reference_bits():
    """Free-flight rows (p, v, a) compiled and in Python floats, plain and shaped moves,
    before, inside and after the move."""
    rng = np.random.default_rng(11)
    none = np.empty(0)
    for k in range(20000):
        t0, T = rng.uniform(0.0, 60.0), rng.uniform(0.3, 8.0)
        t = t0 + rng.uniform(-0.2, 1.4) * T
        p0, delta = rng.normal(size=3) * 3.0, rng.normal(size=3)
        if k % 2:
            times, amplitudes = np.array([0.0, rng.uniform(0.1, 1.0)]), np.array([0.5, 0.5])
        else:
            times = amplitudes = none
        expected = path_rows_reference(t, t0, T, times, amplitudes, p0, delta)
        assert np.array_equal(path_rows(t, t0, T, times, amplitudes, p0, delta), expected)


def test_shaped_path_rows_are_the_convolved_smoothstep():
    """A shaped path's rows are the smoothstep convolved with the shaper's two impulses
    (numpy form), and a shaped move still ends at rest at its end point."""
    rng = np.random.default_rng(5)
    shaper = ZVShaper(0.8)
    start, end = rng.normal(size=3), rng.normal(size=3) * 2.0
    path = Path(0.5, start, speed=1.0, accel=1.0, shaper=shaper).to(end)
    seg = path.segments[0]
    T, delta = seg.base, seg.p1 - seg.p0
    inside = 0
    for t in np.linspace(seg.t0, seg.t_end - 1e-9, 500):
        s = np.zeros(3)
        for ti, ai in zip(shaper.times, shaper.amplitudes, strict=True):
            s += ai * np.array(smoothstep9_scalar((float(t) - seg.t0 - ti) / T, 2))
        expected = np.array([seg.p0 + s[0] * delta, (s[1] / T) * delta, (s[2] / T**2) * delta])
        np.testing.assert_allclose(path.sample(float(t)), expected, rtol=0, atol=1e-12)
        inside += 1
    assert inside == 500
    np.testing.assert_array_equal(path.sample(seg.t_end + 1.0), [end, np.zeros(3), np.zeros(3)])


def test_kept_path_end_time_is_the_last_segments():
    """Path.t_end, kept as segments are added and delayed, is the last segment's end
    exactly (the start time before any)."""
    rng = np.random.default_rng(13)
    path = Path(1.25, rng.normal(size=3), speed=1.0, accel=1.0)
    assert path.t_end == 1.25
    for k in range(30):
        if k % 3 == 2:
            path.delay(float(rng.uniform(0.0, 0.01)))
        else:
            path.to(rng.normal(size=3), pause=float(rng.choice([0.0, 0.3])))
        assert path.t_end == path.segments[-1].t0 + path.segments[-1].duration
    empty = Path(2.0, np.zeros(3), speed=1.0, accel=1.0)
    empty.delay(0.5)
    assert empty.t_end == empty.t0 == 2.5


def test_compiled_kernels_refuse_wrong_shapes():
    """A wrong length is an error, not a read or write past an array's end."""
    none = np.empty(0)
    with pytest.raises(ValueError):
        path_rows(0.5, 0.0, 1.0, none, none, np.zeros(2), np.ones(3))
    with pytest.raises(ValueError):
        path_rows(0.5, 0.0, 1.0, np.zeros(2), np.ones(1), np.zeros(3), np.ones(3))
