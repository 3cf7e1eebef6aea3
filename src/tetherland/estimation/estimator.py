"""The estimator used in the loop: UKF + link state + cable tension (DESIGN.md section 8).

Implements :class:`tetherland.interfaces.Estimator` and ``CommandAware``. IMU samples are
buffered by :meth:`UkfEstimator.predict` and integrated together (every sample, one
unscented transform, :meth:`Ukf.predict_many`) when an estimate or a motion-capture
update needs them, i.e. at the control rate. The cable tension is estimated from the
rotors' actual thrust (commanded speeds through the motor lag) and the bias-corrected
specific force, projected on the estimated link direction.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from tetherland.config import Scenario
from tetherland.estimation.tension import MotorLagThrust, TensionEstimate, TensionEstimator
from tetherland.estimation.ukf import NavState, Ukf, UkfNoise, initial_covariance
from tetherland.geometry import FloatArray, LandingGeometry
from tetherland.interfaces import Command, ImuSample, MocapSample, StateEstimate
from tetherland.rotations import quat_to_rotmat
from tetherland.state import RigidBodyState, link_state_of


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
    tension_time_constant : float
        Low-pass time constant of the tension estimate [s].
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
        tension_time_constant: float = 0.05,
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
        self._p_A, self._R_WA = geo.p_A, geo.R_WA
        self._r_att = np.asarray(v.cable_attachment, dtype=float)
        self.tension = TensionEstimator(
            v.mass,
            scenario.mission.tension_threshold,
            scenario.mission.tension_dwell,
            tension_time_constant,
        )
        w0 = np.zeros(4) if rotor_speeds0 is None else np.asarray(rotor_speeds0, dtype=float)
        self.motors = MotorLagThrust(v.thrust_coefficient, v.motor_time_constant, w0)
        self._motor_t = t0
        self._w_cmd = w0.copy()
        self._buf_t: list[float] = []
        self._buf_f: list[FloatArray] = []
        self._buf_w: list[FloatArray] = []
        self._f_mean = np.array([0.0, 0.0, 9.81])
        self.dropouts = 0
        """Invalid (dropped) motion-capture samples received."""
        self.last_nis = math.nan
        """Normalised innovation squared of the last fused pose (chi-square, 6 dof)."""
        self._cached: StateEstimate | None = None
        self.last_tension: TensionEstimate | None = None
        """Raw and filtered tension and the taut rule, as of the last estimate."""

    # ------------------------------------------------------------------ Estimator protocol
    def predict(self, imu: ImuSample) -> None:
        """Buffer one IMU sample; it is integrated before the next estimate or update."""
        self._buf_t.append(imu.t)
        self._buf_f.append(imu.specific_force_B)
        self._buf_w.append(imu.omega_B)
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
        if self._cached is not None:
            return self._cached
        self._flush()
        ukf = self.ukf
        x = ukf.state
        t = ukf.t
        omega = ukf.omega_B
        body = RigidBodyState(x.p_W, x.v_W, x.q_WB, omega)
        link = link_state_of(
            np.concatenate((x.p_W, x.q_WB, x.v_W, omega)), self._r_att, self._p_A, self._R_WA
        )
        # tension: thrust (motor lag) and the specific force projected on the link
        thrust = float(np.sum(self._thrust_at(t)))
        R_WB = quat_to_rotmat(x.q_WB)
        p_att = x.p_W + R_WB @ self._r_att
        r = p_att - self._p_A
        dist = float(np.linalg.norm(r))
        d_B = R_WB.T @ (r / dist) if dist > 1e-9 else None
        tension = self.tension.update(t, thrust, self._f_mean - x.b_a, d_B)
        self.last_tension = tension
        self._cached = StateEstimate(
            t=t,
            body=body,
            gyro_bias_B=x.b_g,
            accel_bias_B=x.b_a,
            covariance=ukf.covariance,
            link=link,
            tension=tension.filtered,
        )
        return self._cached

    # ------------------------------------------------------------------ CommandAware
    def command_sent(self, t: float, command: Command) -> None:
        """The rotors are commanded ``command.rotor_speeds`` from time ``t`` on."""
        self._thrust_at(t)
        self._w_cmd = np.asarray(command.rotor_speeds, dtype=float).copy()

    # ------------------------------------------------------------------ helpers
    def _thrust_at(self, t: float) -> FloatArray:
        dt = t - self._motor_t
        if dt > 0.0:
            f = self.motors.step(self._w_cmd, dt)
            self._motor_t = t
            return f
        return self.motors.c_f * self.motors.w * self.motors.w

    def _flush(self) -> None:
        if not self._buf_t:
            return
        ts = np.asarray(self._buf_t)
        fs = np.asarray(self._buf_f)
        ws = np.asarray(self._buf_w)
        newer = ts > self.ukf.t  # a sample at the estimate's own time spans no interval
        if not newer.all():
            ts, fs, ws = ts[newer], fs[newer], ws[newer]
        if ts.size:
            self.ukf.predict_many(ts, fs, ws)
            self._f_mean = fs.mean(axis=0)
        self._buf_t.clear()
        self._buf_f.clear()
        self._buf_w.clear()
