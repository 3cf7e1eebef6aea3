"""The plant's rotors for one physics step in one compiled call (docs/theory.md section 4).

Before each MuJoCo step the plant needs the thrusts the actuators apply over the step and,
with ``[aero]`` on, the surface factors and the rotor drag wrench; after it, the rotor
speeds at the end of the step. None of this depends on what MuJoCo computes in the step
(the command is held and the aero model reads the state at the start of the step), so one
kernel, :func:`rotor_step`, does it all before ``mj_step``: a single compiled call per
physics step instead of some sixty Python operations and the aero kernel's call.

The rotor state lives in one float array of :data:`ROTOR_WIDTH` entries (``R_*`` offsets):
the speeds w_i, the held commands, the thrusts out of ground effect c_f wbar_i^2 (wbar the
exact mean speed over the step), the surface factors, the constants of the lag and a flag
``spinning`` (0: the speeds equal the command, nothing to integrate until the next one).

Beside it sits its plain Python reference, :func:`rotor_step_reference` (Python floats for
the lag, :func:`~tetherland.models.aero.aero_into` for the surface model, itself checked
against its numpy reference), which a test compares bit for bit with the kernel.

For the plant with the elastic cable and the capture disk (every scenario's default),
:func:`physics_step` makes the whole physics step one compiled call: the rotors, MuJoCo's
``mj_step1``, the cable's force, ``mj_step2`` and the checks of the attachment point,
reading the plant's arrays and MuJoCo's functions through one address table
(:mod:`tetherland.sim.native`). Its plain form is the plant's Python path
(``Plant(..., compiled_step=False)``), which a test compares bit for bit with it.

numba's on-disk cache of :func:`rotor_step` and :func:`physics_step` is keyed on this file
alone: after an edit of the aero kernel (:mod:`tetherland.models.aero`) or of
:mod:`tetherland.sim.native` delete this module's cache files
(``__pycache__/step_kernel.*``), or the plant keeps the old code compiled in (the
bit-for-bit tests then fail where the change shows).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from tetherland.geometry import FloatArray
from tetherland.models.aero import aero_into, aero_work_into
from tetherland.sim.native import call_model_data, f64_at, f64_matrix_at, i32_at

R_W, R_CMD, R_BASE, R_FACTOR = 0, 4, 8, 12
"""Offsets of the speeds [rad/s], commands [rad/s], thrusts out of ground effect [N] and
surface factors [-] (4 each) in the rotor state."""
R_CF, R_MEAN, R_ALPHA, R_SETTLE, R_SPINNING, R_AERO = 16, 17, 18, 19, 20, 21
"""Offsets of c_f [N/(rad/s)^2], the mean-speed factor tau (1 - alpha) / dt [-], the lag
factor alpha = exp(-dt/tau) [-], the settling tolerance [rad/s], the spinning flag and the
aero flag (1: ``[aero]`` on) in the rotor state."""
ROTOR_WIDTH = 22
"""Floats in the rotor state."""


def rotor_state(
    c_f: float, mean_factor: float, alpha: float, settle_tol: float, aero: bool
) -> FloatArray:
    """A rotor state at rest (speeds and commands 0, factors 1, spinning) with the lag's
    constants (see the module doc and the ``R_*`` offsets)."""
    rot = np.zeros(ROTOR_WIDTH)
    rot[R_FACTOR : R_FACTOR + 4] = 1.0
    rot[R_CF], rot[R_MEAN], rot[R_ALPHA], rot[R_SETTLE] = c_f, mean_factor, alpha, settle_tol
    rot[R_SPINNING] = 1.0
    rot[R_AERO] = 1.0 if aero else 0.0
    return rot


@njit(cache=True)
def rotor_step(rot: FloatArray, qpos: FloatArray, v_W: FloatArray, centres_B: FloatArray,
               samples: FloatArray, shapes: FloatArray, params: FloatArray, work: FloatArray,
               ctrl: FloatArray, wrench: FloatArray) -> None:  # fmt: skip
    """The rotors over one physics step, before ``mj_step``.

    Parameters
    ----------
    rot : (ROTOR_WIDTH,) array, in/out
        The rotor state (module doc) at t_k; at t_{k+1} on return.
    qpos, v_W : arrays
        The vehicle's [p_W, q_WB] and velocity at t_k (the aero model's inputs) [m, -, m/s].
    centres_B, samples, shapes, params, work : arrays
        The aero model (:func:`~tetherland.models.aero.aero_work_into`; unused with the
        aero flag off).
    ctrl : (4,) array, out
        The thrusts the actuators apply over the step, c_f wbar_i^2 times the surface
        factors [N].
    wrench : (6,) array, out
        The aero wrench of the step (aero flag on; untouched otherwise) [N, N m].
    """
    c_f = rot[R_CF]
    spinning = rot[R_SPINNING] != 0.0
    if spinning:
        b = rot[R_MEAN]
        for i in range(4):
            c = rot[R_CMD + i]
            m = c + (rot[R_W + i] - c) * b  # the exact mean speed over the step
            rot[R_BASE + i] = c_f * m * m
    if rot[R_AERO] != 0.0:
        aero_work_into(qpos, v_W, rot[R_BASE : R_BASE + 4], centres_B, samples, shapes, params,
                       rot[R_FACTOR : R_FACTOR + 4], ctrl, wrench, work)  # fmt: skip
    else:
        for i in range(4):
            ctrl[i] = rot[R_BASE + i]
    if spinning:
        a = rot[R_ALPHA]
        gap = 0.0
        for i in range(4):
            c = rot[R_CMD + i]
            w = c + (rot[R_W + i] - c) * a
            rot[R_W + i] = w
            gap += abs(w - c)
        if gap < rot[R_SETTLE]:  # settled: hold exactly until the next command
            for i in range(4):
                c = rot[R_CMD + i]
                rot[R_W + i] = c
                rot[R_BASE + i] = c_f * c * c
            rot[R_SPINNING] = 0.0


def rotor_step_reference(
    rot: FloatArray,
    qpos: FloatArray,
    v_W: FloatArray,
    centres_B: FloatArray,
    samples: FloatArray,
    shapes: FloatArray,
    params: FloatArray,
    ctrl: FloatArray,
    wrench: FloatArray,
) -> None:
    """:func:`rotor_step` written plainly (Python floats; the aero model by
    :func:`~tetherland.models.aero.aero_into`), for tests."""
    c_f = float(rot[R_CF])
    w = [float(v) for v in rot[R_W : R_W + 4]]
    cmd = [float(v) for v in rot[R_CMD : R_CMD + 4]]
    base = [float(v) for v in rot[R_BASE : R_BASE + 4]]
    spinning = bool(rot[R_SPINNING])
    if spinning:
        b = float(rot[R_MEAN])
        means = [c + (wi - c) * b for wi, c in zip(w, cmd, strict=True)]
        base = [c_f * m * m for m in means]
    rot[R_BASE : R_BASE + 4] = base
    if rot[R_AERO]:
        factors = np.empty(4)
        aero_into(qpos, v_W, rot[R_BASE : R_BASE + 4].copy(), centres_B, samples, shapes,
                  params, factors, ctrl, wrench)  # fmt: skip
        rot[R_FACTOR : R_FACTOR + 4] = factors
    else:
        ctrl[:4] = base
    if spinning:
        a = float(rot[R_ALPHA])
        w = [c + (wi - c) * a for wi, c in zip(w, cmd, strict=True)]
        gap = abs(w[0] - cmd[0]) + abs(w[1] - cmd[1]) + abs(w[2] - cmd[2]) + abs(w[3] - cmd[3])
        if gap < rot[R_SETTLE]:
            w = list(cmd)
            rot[R_BASE : R_BASE + 4] = [c_f * c * c for c in cmd]
            rot[R_SPINNING] = 0.0
        rot[R_W : R_W + 4] = w


@njit(cache=True)
def rotor_row_into(rot: FloatArray, wrench: FloatArray, out: FloatArray) -> None:
    """The plant's rotor row of the log (:meth:`~tetherland.sim.plant.Plant.rotor_state_into`)
    in one compiled call: [w (4) rad/s, thrusts c_f w_i^2 k_i (4) N, surface factors k_i
    (4), aero force F_W (3) N] into ``out[:15]`` from the rotor state ``rot`` and the aero
    ``wrench`` (with the aero flag off: factors 1 and no force). Its plain form is
    :func:`rotor_row_reference` (a test compares the bits)."""
    c_f = rot[R_CF]
    aero = rot[R_AERO] != 0.0
    for i in range(4):
        w = rot[R_W + i]
        out[i] = w
        if aero:
            k = rot[R_FACTOR + i]
            out[4 + i] = c_f * w * w * k
            out[8 + i] = k
        else:
            out[4 + i] = c_f * w * w
            out[8 + i] = 1.0
    for j in range(3):
        out[12 + j] = wrench[j] if aero else 0.0


def rotor_row_reference(rot: FloatArray, wrench: FloatArray, out: FloatArray) -> None:
    """:func:`rotor_row_into` written plainly (Python floats), for tests."""
    w = rot[R_W : R_W + 4].tolist()
    c_f = float(rot[R_CF])
    if not rot[R_AERO]:
        out[:15] = [w[0], w[1], w[2], w[3], c_f * w[0] * w[0], c_f * w[1] * w[1],
                    c_f * w[2] * w[2], c_f * w[3] * w[3], 1.0, 1.0, 1.0, 1.0, 0.0, 0.0,
                    0.0]  # fmt: skip
        return
    k, F = rot[R_FACTOR : R_FACTOR + 4].tolist(), wrench
    out[:15] = [w[0], w[1], w[2], w[3], c_f * w[0] * w[0] * k[0], c_f * w[1] * w[1] * k[1],
                c_f * w[2] * w[2] * k[2], c_f * w[3] * w[3] * k[3], k[0], k[1], k[2], k[3],
                F[0], F[1], F[2]]  # fmt: skip


@njit(cache=True)
def command_rotors(rot: FloatArray, speeds: FloatArray, w_max: float) -> bool:
    """Hold new ESC speed commands ``speeds`` (4) [rad/s] in the rotor state ``rot``,
    clamped to [0, w_max] [rad/s]; a changed command sets the spinning flag. False at the
    first NaN command (the commands before it are held, the rest not; the caller
    raises). The plant's :meth:`~tetherland.sim.plant.Plant.command` in one compiled call;
    its plain form is :func:`command_rotors_reference` (a test compares the bits)."""
    changed = False
    ok = True
    for i in range(4):
        w = speeds[i]
        if w != w:
            ok = False
            break
        w = 0.0 if w < 0.0 else (w_max if w > w_max else w)
        if w != rot[R_CMD + i]:
            rot[R_CMD + i] = w
            changed = True
    if changed:
        rot[R_SPINNING] = 1.0
    return ok


def command_rotors_reference(rot: FloatArray, speeds: FloatArray, w_max: float) -> bool:
    """:func:`command_rotors` written plainly (Python floats), for tests."""
    cmd = rot[R_CMD : R_CMD + 4].tolist()
    changed = False
    ok = True
    for i, w in enumerate(np.asarray(speeds, dtype=float).tolist()):
        if w != w:
            ok = False
            break
        w = 0.0 if w < 0.0 else (w_max if w > w_max else w)
        if w != cmd[i]:
            cmd[i] = w
            changed = True
    if changed:
        rot[R_CMD : R_CMD + 4] = cmd
        rot[R_SPINNING] = 1.0
    return ok


# --------------------------------------------------------------------- the whole step
T_MODEL, T_DATA, T_STEP1, T_STEP2 = 0, 1, 2, 3
"""Address table of :func:`physics_step`: ``mjModel``, ``mjData``, ``mj_step1``, ``mj_step2``."""
T_QPOS, T_QVEL, T_CTRL, T_WRENCH = 4, 5, 6, 7
"""... the vehicle's ``qpos[0:7]``, ``qvel[0:6]``, the rotor actuators' ``ctrl[0:4]`` and
the aero wrench ``qfrc_applied[0:6]``."""
T_TENDON_LENGTH, T_TENDON_RATE, T_CABLE_CTRL, T_CABLE = 8, 9, 10, 11
"""... the cable tendon's length and rate, its actuator's ``ctrl`` and the cable's state
(:data:`C_ENGAGED` ...)."""
T_ATTACHMENT, T_BAD_QACC, T_HOOK = 12, 13, 14
"""... the attachment site's position ``site_xpos``, MuJoCo's bad-acceleration warning
count (int32) and the capture plane's state (:data:`H_NX` ...)."""
T_ROT, T_CENTRES, T_N_CENTRES, T_SAMPLES, T_N_SAMPLES = 15, 16, 17, 18, 19
T_SHAPES, T_N_SHAPES, T_SHAPE_WIDTH, T_PARAMS, T_N_PARAMS, T_WORK, T_N_WORK = (
    20, 21, 22, 23, 24, 25, 26,
)  # fmt: skip
"""... :func:`rotor_step`'s arrays (addresses and sizes)."""
TABLE_SIZE = 27
"""Entries of the address table."""

C_ENGAGED, C_STIFFNESS, C_DAMPING, C_LENGTH = 0, 1, 2, 3
"""The elastic cable's state (:class:`~tetherland.sim.cable.ElasticCable`): engaged (1/0),
k [N/m], c [N s/m], unstretched length l [m]."""
CABLE_WIDTH = 4

H_NX, H_NY, H_NZ, H_C0, H_SIDE, H_PREV, H_NOW = 0, 1, 2, 3, 4, 5, 8
"""The capture plane's state: its normal n (3) and offset c0 (the hook's side of the
plane: n.p >= c0), the side of the attachment point at the last step (1/0), the point
before the last crossing (3) and at it (3) [m]."""
HOOK_WIDTH = 11

STEP_OK, STEP_CROSSED, STEP_DIVERGED = 0, 1, 2
"""What :func:`physics_step` found: nothing, the attachment point crossed the capture
plane (``hook[H_PREV:H_PREV+3]`` -> ``hook[H_NOW:H_NOW+3]``), a non-finite state or
MuJoCo's bad-acceleration flag."""


@njit(cache=True)
def physics_step(table: np.ndarray) -> int:
    """One physics step of a plant with the elastic cable and the capture disk, compiled.

    The plain forms are :meth:`Plant.step <tetherland.sim.plant.Plant.step>`'s Python path
    with :meth:`ElasticCable.advance <tetherland.sim.cable.ElasticCable.advance>`: the rotors
    (:func:`rotor_step`), ``mj_step1``, the cable's force f_L = max(0, k x + c x') for a
    stretch x > 0 into its actuator (engaged only), ``mj_step2``, then the checks on the
    attachment point's new position (divergence, a crossing of the capture plane). A test
    compares both bit for bit.

    Parameters
    ----------
    table : (TABLE_SIZE,) int64 array
        Addresses and sizes (``T_*``, :mod:`tetherland.sim.native`).

    Returns
    -------
    int
        :data:`STEP_OK`, :data:`STEP_CROSSED` or :data:`STEP_DIVERGED`.
    """
    qpos = f64_at(table[T_QPOS], 7)
    qvel = f64_at(table[T_QVEL], 6)
    rot = f64_at(table[T_ROT], ROTOR_WIDTH)
    rotor_step(
        rot, qpos, qvel,
        f64_matrix_at(table[T_CENTRES], table[T_N_CENTRES], 3),
        f64_matrix_at(table[T_SAMPLES], table[T_N_SAMPLES], 2),
        f64_matrix_at(table[T_SHAPES], table[T_N_SHAPES], table[T_SHAPE_WIDTH]),
        f64_at(table[T_PARAMS], table[T_N_PARAMS]),
        f64_at(table[T_WORK], table[T_N_WORK]),
        f64_at(table[T_CTRL], 4),
        f64_at(table[T_WRENCH], 6),
    )  # fmt: skip
    model, data = table[T_MODEL], table[T_DATA]
    call_model_data(table[T_STEP1], model, data)  # positions, velocities, tendon at t_k
    cable = f64_at(table[T_CABLE], CABLE_WIDTH)
    if cable[C_ENGAGED] != 0.0:
        force = f64_at(table[T_CABLE_CTRL], 1)
        x = f64_at(table[T_TENDON_LENGTH], 1)[0] - cable[C_LENGTH]
        if x > 0.0:
            f = cable[C_STIFFNESS] * x + cable[C_DAMPING] * f64_at(table[T_TENDON_RATE], 1)[0]
            force[0] = f if f > 0.0 else 0.0
        else:
            force[0] = 0.0
    call_model_data(table[T_STEP2], model, data)  # actuation, constraints, integration
    p = f64_at(table[T_ATTACHMENT], 3)
    x, y, z = p[0], p[1], p[2]
    if x != x or i32_at(table[T_BAD_QACC], 1)[0] != 0:
        return STEP_DIVERGED
    hook = f64_at(table[T_HOOK], HOOK_WIDTH)
    side = 1.0 if hook[H_NX] * x + hook[H_NY] * y + hook[H_NZ] * z >= hook[H_C0] else 0.0
    if side != hook[H_SIDE]:
        hook[H_SIDE] = side
        hook[H_NOW], hook[H_NOW + 1], hook[H_NOW + 2] = x, y, z
        return STEP_CROSSED
    hook[H_PREV], hook[H_PREV + 1], hook[H_PREV + 2] = x, y, z
    return STEP_OK
