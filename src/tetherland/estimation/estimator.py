"""The estimator used in the loop: UKF + link state + cable tension (docs/theory.md section 8).

Implements :class:`tetherland.interfaces.Estimator`, ``ImuBatchAware`` and ``CommandAware``.
IMU samples are buffered by :meth:`UkfEstimator.predict` (or, several at once,
:meth:`~UkfEstimator.predict_rows`) and integrated together (every sample, one unscented
transform) when an estimate or a motion-capture update needs them, i.e. at the control
rate. The cable tension is estimated from the rotors' actual thrust (commanded
speeds through the motor lag, the believed ground effect) and the bias-corrected specific
force, projected on the estimated link direction. Each step is one compiled call on the
estimator's mutable state (the filter's workspace and the estimator's own array, see
:mod:`tetherland.estimation.kernels`): :func:`~tetherland.estimation.kernels.push_imu`,
:func:`~tetherland.estimation.kernels.estimate_tick` (the integration, the thrust, the
link state and the filtered tension of an estimate),
:func:`~tetherland.estimation.kernels.fuse_pose` and
:func:`~tetherland.estimation.kernels.command_into`; the plain pieces they compile
(:class:`~tetherland.estimation.tension.MotorLagThrust`,
:class:`~tetherland.estimation.tension.TensionEstimator`,
:meth:`~tetherland.estimation.ukf.Ukf.predict_rows`, ...) give the same bits (a test runs
both side by side). With an elastic cable the link
state is that of the stretched cable (direction and rates from the actual distance, not
l) and :meth:`UkfEstimator.cable` reports the estimated stretch.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from tetherland.config import Scenario
from tetherland.estimation import kernels
from tetherland.estimation.ground_effect import BelievedGroundEffect
from tetherland.estimation.kernels import command_into as _command_into
from tetherland.estimation.kernels import estimate_tick as _estimate_tick
from tetherland.estimation.kernels import fuse_pose as _fuse_pose
from tetherland.estimation.kernels import push_imu as _push_imu
from tetherland.estimation.kernels import push_imu_rows as _push_imu_rows
from tetherland.estimation.tension import (
    F_T,
    F_TAUT,
    F_TIME_CONSTANT,
    F_VALUE,
    CableEstimate,
    TensionEstimate,
    TensionEstimator,
    elastic_tension,
    pack_motor_lag,
    pack_tension_filter,
    tension_filter_time_constant,
)
from tetherland.estimation.ukf import NavState, Ukf, UkfNoise, initial_covariance
from tetherland.estimation.ukf_kernels import REJECTED
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.interfaces import Command, ImuSample, MocapSample, StateEstimate
from tetherland.rotations import quat_to_rotmat
from tetherland.state import LinkState, RigidBodyState

_P_W, _V_W, _Q_WB, _OMEGA_B = kernels.P_W, kernels.V_W, kernels.Q_WB, kernels.OMEGA_B
_ACCEL_BIAS, _GYRO_BIAS, _EXTERNAL = kernels.ACCEL_BIAS, kernels.GYRO_BIAS, kernels.EXTERNAL


class UkfEstimator:
    """UKF estimator with link state and tension, for the runner and the mission.

    Parameters
    ----------
    scenario : Scenario
        The *believed* scenario (mass, rotor model, anchor, sensor noise).
    initial : RigidBodyState
        Initial estimate (e.g. the start pad pose).
    t0 : float
        Time of ``initial`` [s].
    rotor_speeds0 : (4,) array, optional
        Rotor speeds at ``t0`` for the motor-lag model [rad/s] (default: stopped).
    P0 : (15, 15) array, optional
        Initial error covariance (default: 1 cm, 5 cm/s, 2 deg, small biases).
    noise_inflation : float
        Process/measurement noise multiplier (>= 1 makes the filter more robust to
        unmodelled effects) [-].
    tension_time_constant : float, optional
        Low-pass time constant of the tension estimate (default: from the believed
        cable's stiffness, :func:`~tetherland.estimation.tension.tension_filter_time_constant`) [s].
    """

    def __init__(
        self,
        scenario: Scenario,
        initial: RigidBodyState,
        t0: float = 0.0,
        *,
        rotor_speeds0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
        noise_inflation: float = 1.0,
        tension_time_constant: float | None = None,
    ) -> None:
        v = scenario.vehicle
        self.mass = v.mass
        self.ukf = Ukf(
            UkfNoise.from_config(scenario.sensors, inflation=noise_inflation),
            NavState(initial.p_W, initial.v_W, initial.q_WB, np.zeros(3), np.zeros(3)),
            initial_covariance() if P0 is None else P0,
            t0,
            imu_rate_hz=scenario.sensors.imu.rate_hz,
        )
        geo = LandingGeometry.from_scenario(scenario)
        self._p_A, self._r_att = geo.p_A, np.asarray(v.cable_attachment, dtype=float)
        self._length, self._stiffness = scenario.tether.length, scenario.tether.stiffness
        if tension_time_constant is None:
            tension_time_constant = tension_filter_time_constant(self._stiffness, v.mass)
        stretch = scenario.mission.stretch
        TensionEstimator(v.mass, stretch.tension_threshold, stretch.tension_dwell,
                         tension_time_constant)  # (validates the arguments)  # fmt: skip
        w0 = np.zeros(4) if rotor_speeds0 is None else np.asarray(rotor_speeds0, dtype=float)
        self.ground_effect = (
            BelievedGroundEffect(scenario) if scenario.estimator.ground_effect_belief else None
        )
        """The believed ground effect on the predicted thrust (None: not modelled)."""
        # the mutable state of every step in two arrays, the filter's and this one
        # (kernels.E_*: buffered IMU samples, motor lag, tension filter, the belief)
        self._ws = self.ukf.workspace
        self._e = kernels.pack_estimator(
            self._r_att, geo.p_A, geo.R_WA, v.mass, t0,
            pack_motor_lag(v.thrust_coefficient, v.motor_time_constant, w0),
            pack_tension_filter(stretch.tension_threshold, stretch.tension_dwell,
                                tension_time_constant),
            None if self.ground_effect is None else self.ground_effect.packed,
        )  # fmt: skip
        self.dropouts = 0
        """Invalid (dropped) motion-capture samples received."""
        self.last_nis = math.nan
        """Normalised innovation squared of the last fused pose (chi-square, 6 dof)."""
        self._cached: StateEstimate | None = None
        self._P = self.ukf.covariance_view
        self._load_kernels()

    def _load_kernels(self) -> None:
        """Load the compiled steps now (numba's cache, once per process) rather than inside
        the first control ticks: calls on scratch copies."""
        ws, e = self._ws.copy(), self._e.copy()
        t = float(ws[kernels.WS_CLOCK0]) + 1e-3
        f_B, omega_B = np.array([0.0, 0.0, 9.81]), np.zeros(3)
        kernels.push_imu(ws, e, t, f_B, omega_B)
        kernels.push_imu_rows(ws, e, np.array([[t + 1e-3, *f_B, *omega_B]]))
        kernels.estimate_tick(ws, e, np.empty(kernels.WIDTH))
        held = np.zeros(4)
        kernels.command_into(e, t, held)
        held.setflags(write=False)  # (some controllers hand out read-only speeds)
        kernels.command_into(e, t, held)
        x = ws[kernels.WS_X0 : kernels.WS_X1]
        kernels.fuse_pose(ws, e, t, x[0:3].copy(), x[6:10].copy())

    # ------------------------------------------------------------------ Estimator protocol
    def predict(self, imu: ImuSample) -> None:
        """Buffer one IMU sample; it is integrated before the next estimate or update."""
        if _push_imu(self._ws, self._e, imu.t, imu.specific_force_B, imu.omega_B):
            self._cached = None

    def predict_rows(self, rows: FloatArray) -> None:
        """Buffer the IMU samples [t, f_B (3), omega_B (3)] of the rows of ``rows`` (n, 7),
        in order: the same as :meth:`predict` of each (``ImuBatchAware``, one compiled
        call)."""
        if _push_imu_rows(self._ws, self._e, rows):
            self._cached = None

    def update(self, mocap: MocapSample) -> None:
        """Fuse a (delayed) motion-capture pose; dropouts are counted and skipped."""
        if not mocap.valid:
            self.dropouts += 1
            return
        nis = _fuse_pose(
            self._ws, self._e, float(mocap.t_measured),
            np.ascontiguousarray(mocap.p_W, dtype=float),
            np.ascontiguousarray(mocap.q_WB, dtype=float),
        )  # fmt: skip
        if nis == REJECTED:
            self.ukf.rejected_late += 1
            nis = math.nan
        self.last_nis = nis
        self._cached = None

    def estimate(self) -> StateEstimate:
        """Current estimate, with link state (w.r.t. the believed anchor) and tension."""
        cached = self._cached
        if cached is not None:
            return cached
        out = np.empty(kernels.WIDTH)  # fresh: the record's arrays are views into it
        t, filtered, phi, delta, phi_dot, delta_dot = _estimate_tick(self._ws, self._e, out)
        self._cached = cached = StateEstimate(
            t,
            RigidBodyState(out[_P_W], out[_V_W], out[_Q_WB], out[_OMEGA_B]),
            out[_GYRO_BIAS],
            out[_ACCEL_BIAS],
            self._P.copy(),
            LinkState(phi, delta, phi_dot, delta_dot),
            filtered,
            out[_EXTERNAL],
        )
        return cached

    @property
    def tension_time_constant(self) -> float:
        """Time constant of the tension estimate's low-pass [s] (chosen from the believed
        cable's axial mode, :func:`~tetherland.estimation.tension.tension_filter_time_constant`,
        unless given)."""
        return float(self._e[kernels.E_FILTER][F_TIME_CONSTANT])

    @property
    def last_tension(self) -> TensionEstimate | None:
        """Raw and filtered tension and the taut rule, as of the last estimate (None
        before the first)."""
        e = self._e
        f = e[kernels.E_FILTER]
        if math.isnan(f[F_T]):  # (the filter's time: set by the first estimate)
            return None
        return TensionEstimate(float(e[kernels.E_RAW]), float(f[F_VALUE]), bool(f[F_TAUT]))

    def cable(self) -> CableEstimate:
        """The cable seen from the current estimate: distance, stretch and, for an elastic
        cable, the tension k max(D - l, 0) the stretch implies (docs/tether.md)."""
        body = self.estimate().body
        p_att = body.p_W + quat_to_rotmat(body.q_WB) @ self._r_att
        D = float(np.linalg.norm(p_att - self._p_A))
        k = self._stiffness
        f = None if k is None else elastic_tension(D, self._length, k)
        return CableEstimate(D, D - self._length, f)

    # ------------------------------------------------------------------ CommandAware
    def command_sent(self, t: float, command: Command) -> None:
        """The rotors are commanded ``command.rotor_speeds`` from time ``t`` on."""
        w = command.rotor_speeds
        if type(w) is not np.ndarray or w.dtype != np.float64 or w.shape != (4,):
            w = np.ascontiguousarray(w, dtype=float).reshape(4)
        _command_into(self._e, t, w)
