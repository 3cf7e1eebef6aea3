"""The estimator used in the loop: UKF + link state + cable tension (docs/theory.md section 8).

Implements :class:`tetherland.interfaces.Estimator` and ``CommandAware``. IMU samples are
buffered by :meth:`UkfEstimator.predict` and integrated together (every sample, one
unscented transform, one compiled call: :meth:`Ukf.predict_rows`) when an estimate or a
motion-capture update needs them, i.e. at the control rate. The cable tension is
estimated from the rotors' actual thrust (commanded speeds through the motor lag) and the
bias-corrected specific force, projected on the estimated link direction; the link state
and the tension of an estimate come from one compiled call as well
(:func:`tetherland.estimation.kernels.estimate_into`). With an elastic cable the link
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
from tetherland.estimation.kernels import estimate_into as _estimate_into
from tetherland.estimation.tension import (
    CableEstimate,
    MotorLagThrust,
    TensionEstimate,
    TensionEstimator,
    elastic_tension,
    tension_filter_time_constant,
)
from tetherland.estimation.ukf import NavState, Ukf, UkfNoise, initial_covariance
from tetherland.geometry import LandingGeometry
from tetherland.interfaces import Command, ImuSample, MocapSample, StateEstimate
from tetherland.rotations import quat_to_rotmat
from tetherland.state import LinkState, RigidBodyState

_BUFFER = 16
_P_W, _V_W, _Q_WB, _OMEGA_B = kernels.P_W, kernels.V_W, kernels.Q_WB, kernels.OMEGA_B
_ACCEL_BIAS, _GYRO_BIAS, _EXTERNAL = kernels.ACCEL_BIAS, kernels.GYRO_BIAS, kernels.EXTERNAL
_LINK_TO_TENSION = slice(kernels.LINK.start, kernels.TENSION + 1)
"""The link state (4), d_B (3) and the raw tension of ``estimate_into``'s output."""
assert kernels.LINK.stop == kernels.D_B.start and kernels.D_B.stop == kernels.TENSION
"""IMU samples buffered at most between two integrations."""


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
        self._geo = kernels.pack_geometry(self._r_att, geo.p_A, geo.R_WA)
        self._length, self._stiffness = scenario.tether.length, scenario.tether.stiffness
        if tension_time_constant is None:
            tension_time_constant = tension_filter_time_constant(self._stiffness, v.mass)
        self.tension = TensionEstimator(
            v.mass,
            scenario.mission.stretch.tension_threshold,
            scenario.mission.stretch.tension_dwell,
            tension_time_constant,
        )
        w0 = np.zeros(4) if rotor_speeds0 is None else np.asarray(rotor_speeds0, dtype=float)
        self.motors = MotorLagThrust(v.thrust_coefficient, v.motor_time_constant, w0)
        self.ground_effect = (
            BelievedGroundEffect(scenario) if scenario.estimator.ground_effect_belief else None
        )
        """The believed ground effect on the predicted thrust (None: not modelled)."""
        self._motor_t = t0
        self._w_cmd = [float(w) for w in w0]
        self._buf = np.empty((_BUFFER, 7))  # rows [t, f_B (3), omega_B (3)]
        self._n = 0
        self.dropouts = 0
        """Invalid (dropped) motion-capture samples received."""
        self.last_nis = math.nan
        """Normalised innovation squared of the last fused pose (chi-square, 6 dof)."""
        self._cached: StateEstimate | None = None
        # load the compiled outputs now (numba's cache, once per process)
        kernels.estimate_into(
            self.ukf.x_view, self.ukf.imu_view, 0.0, self.mass, self._geo, np.empty(kernels.WIDTH)
        )
        self._last_raw: float | None = None  # raw tension of the last estimate [N]
        # the UKF's live state and IMU record (updated in place, never replaced)
        self._x_view, self._imu_view = self.ukf.x_view, self.ukf.imu_view

    # ------------------------------------------------------------------ Estimator protocol
    def predict(self, imu: ImuSample) -> None:
        """Buffer one IMU sample; it is integrated before the next estimate or update."""
        t = imu.t
        if t <= self._imu_view[0]:  # ukf.t
            return  # a sample at the estimate's own time spans no interval
        n = self._n
        if n == _BUFFER:
            self._flush()
            n = 0
        buf = self._buf  # (indexed in place: no row view per sample)
        buf[n, 0] = t
        buf[n, 1:4] = imu.specific_force_B
        buf[n, 4:7] = imu.omega_B
        self._n = n + 1
        self._cached = None

    def update(self, mocap: MocapSample) -> None:
        """Fuse a (delayed) motion-capture pose; dropouts are counted and skipped."""
        if not mocap.valid:
            self.dropouts += 1
            return
        self._flush()
        self.last_nis = self.ukf.update_pose(mocap.t_measured, mocap.p_W, mocap.q_WB)
        self._cached = None

    def estimate(self) -> StateEstimate:
        """Current estimate, with link state (w.r.t. the believed anchor) and tension."""
        cached = self._cached
        if cached is not None:
            return cached
        if self._n:  # _flush
            self.ukf.predict_rows(self._buf, self._n)
            self._n = 0
        x, imu = self._x_view, self._imu_view
        t = float(imu[0])  # ukf.t
        out = np.empty(kernels.WIDTH)  # fresh: the record's arrays are views into it
        thrust = self._thrust_at(t)
        ge = self.ground_effect
        if ge is not None:
            motors = self.motors
            c_f = motors.c_f
            w0, w1, w2, w3 = motors.speeds
            thrust = ge.total_thrust_of(
                x, [c_f * (w0 * w0), c_f * (w1 * w1), c_f * (w2 * w2), c_f * (w3 * w3)]
            )
        _estimate_into(x, imu, thrust, self.mass, self._geo, out)
        # link (4) and the raw tension: the tension low-passed, the taut rule applied
        phi, delta, phi_dot, delta_dot, _, _, _, raw = out[_LINK_TO_TENSION].tolist()
        tension = self.tension
        filtered = tension.filter_value(t, raw)
        self._last_raw = raw
        self._cached = cached = StateEstimate(
            t,
            RigidBodyState(out[_P_W], out[_V_W], out[_Q_WB], out[_OMEGA_B]),
            out[_GYRO_BIAS],
            out[_ACCEL_BIAS],
            self.ukf.covariance,
            LinkState(phi, delta, phi_dot, delta_dot),
            filtered,
            out[_EXTERNAL],
        )
        return cached

    @property
    def last_tension(self) -> TensionEstimate | None:
        """Raw and filtered tension and the taut rule, as of the last estimate (None
        before the first)."""
        if self._last_raw is None:
            return None
        return TensionEstimate(self._last_raw, self.tension.value, self.tension.taut)

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
        self._thrust_at(t)
        self._w_cmd = np.asarray(command.rotor_speeds, dtype=float).tolist()

    # ------------------------------------------------------------------ helpers
    def _thrust_at(self, t: float) -> float:
        """Total actual thrust at ``t`` (the motor lag advanced to ``t``) [N]."""
        dt = t - self._motor_t
        if dt > 0.0:
            self._motor_t = t
            return self.motors.advance(self._w_cmd, dt)
        return self.motors.total_thrust

    def _flush(self) -> None:
        n = self._n
        if n == 0:
            return
        self.ukf.predict_rows(self._buf, n)
        self._n = 0
