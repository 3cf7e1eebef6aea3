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
        self.last_tension: TensionEstimate | None = None
        """Raw and filtered tension and the taut rule, as of the last estimate."""

    # ------------------------------------------------------------------ Estimator protocol
    def predict(self, imu: ImuSample) -> None:
        """Buffer one IMU sample; it is integrated before the next estimate or update."""
        if imu.t <= self.ukf.t:
            return  # a sample at the estimate's own time spans no interval
        if self._n == _BUFFER:
            self._flush()
        row = self._buf[self._n]
        row[0] = imu.t
        row[1:4] = imu.specific_force_B
        row[4:7] = imu.omega_B
        self._n += 1
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
        t = ukf.t
        out = np.empty(kernels.WIDTH)  # fresh: the record's arrays are views into it
        thrust = self._thrust_at(t)
        if self.ground_effect is not None:
            c_f = self.motors.c_f
            w0, w1, w2, w3 = self.motors.speeds
            thrust = self.ground_effect.total_thrust_of(
                ukf.x_view, [c_f * (w0 * w0), c_f * (w1 * w1), c_f * (w2 * w2), c_f * (w3 * w3)]
            )
        kernels.estimate_into(ukf.x_view, ukf.imu_view, thrust, self.mass, self._geo, out)
        phi, delta, phi_dot, delta_dot = out[kernels.LINK].tolist()
        # tension: thrust (motor lag) and the specific force projected on the link
        tension = self.tension.filter(t, float(out[kernels.TENSION]))
        self.last_tension = tension
        self._cached = StateEstimate(
            t=t,
            body=RigidBodyState(out[0:3], out[3:6], out[6:10], out[10:13]),
            gyro_bias_B=out[kernels.GYRO_BIAS],
            accel_bias_B=out[kernels.ACCEL_BIAS],
            covariance=ukf.covariance,
            link=LinkState(phi, delta, phi_dot, delta_dot),
            tension=tension.filtered,
            external_force_B=out[kernels.EXTERNAL],
        )
        return self._cached

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
