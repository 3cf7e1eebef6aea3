"""What the outer loop hands to the firmware's rate loop: body rates and thrust.

tetherland's controllers end in a torque command, an angular acceleration
alpha = J^-1 (tau - w x J w) of the attitude law (Lee et al. 2010)

    alpha = -k_R e_R - k_w (w - w_d) + alpha_ff        (alpha_ff: feed-forward, cable torque)

and their own inner loop is that torque on the rotors. The firmware instead runs a rate
loop on its gyro; configured as a proportional loop (``betaflight_default.txt``: no I, D
or feed-forward terms) it commands alpha = K (w_cmd - w_gyro) for a gain K per axis that
follows from the configuration and the vehicle (:class:`RateLoopGain`). Sending

    w_cmd = w + b_g + alpha / K          (w the estimated rate, b_g the estimated gyro bias)

makes the firmware command exactly the outer controller's alpha at the radio frame: the
measured rate cancels, and between frames the firmware adds K (w(t_k) - w(t)), the same
rate damping tetherland's own inner loop would apply at K = k_w. The default P gains put
K at k_w (25.2 rad/s) on roll and pitch at hover.

An integrating rate loop would not fit: the rate error w_cmd - w is the commanded
angular acceleration, so an I term would integrate every standing torque the outer
controller asks for (the cable's offset torque, held by feed-forward) and cancel it, and
the attitude would settle off by alpha_ff / k_R (10 deg for 0.5 N m). The outer
controllers' own integrators (position, link angles) remove model errors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tetherland.config import Scenario, VehicleConfig
from tetherland.firmware.configure import FirmwareConfig
from tetherland.firmware.motors import ThrottleMap
from tetherland.geometry import FloatArray
from tetherland.interfaces import Command, StateEstimate
from tetherland.models.quadrotor import RotorLayout
from tetherland.rotations import cross3

PTERM_SCALE = 0.032029
"""Betaflight's P term per deg/s of rate error and unit of P gain (``pid.h``) [-]."""
PID_MIXER_SCALING = 1000.0
"""PID sum per unit of motor mix (``pid.h``) [-]."""
AXES = ("roll", "pitch", "yaw")
PROPORTIONAL_ONLY = tuple(f"{term}_{axis}" for term in ("i", "d", "d_max", "f") for axis in AXES
                          if not (term == "d_max" and axis == "yaw"))  # fmt: skip
"""Settings the hand-over needs at 0: a proportional rate loop (no d_max on yaw)."""


@dataclass(frozen=True)
class RateLoopGain:
    """The firmware's proportional rate loop as an angular-acceleration gain (believed).

    A rate error e [rad/s] gives a PID sum s P (180/pi) e (s = ``PTERM_SCALE``), a motor
    mix m = sum/1000 with QUADX's +-1 coefficients, and a body torque
    m (df/dm) sum_i |Gamma_ai| (the allocation row of axis a: arm offsets for roll and
    pitch, drag coefficients for yaw), so

        K_a = s P_a (180/pi) / 1000 * (df/dm) sum_i |Gamma_ai| / J_a     [1/s]

    with df/dm the thrust slope of the throttle path at the collective thrust
    (:meth:`ThrottleMap.mix_slope`).

    Attributes
    ----------
    per_slope : (3,) array
        K / (df/dm) for roll, pitch, yaw [1/(s N)].
    throttle_map : ThrottleMap
    """

    per_slope: FloatArray
    throttle_map: ThrottleMap

    @classmethod
    def from_config(
        cls, config: FirmwareConfig, vehicle: VehicleConfig, throttle_map: ThrottleMap
    ) -> RateLoopGain:
        p = np.array([config.number(f"p_{axis}") for axis in AXES])
        lever = np.abs(RotorLayout.from_config(vehicle).allocation[1:4]).sum(axis=1)
        J = np.asarray(vehicle.inertia, dtype=float)
        mix_per_rate = PTERM_SCALE * p * math.degrees(1.0) / PID_MIXER_SCALING
        return cls(mix_per_rate * lever / J, throttle_map)

    def at(self, thrust: float) -> FloatArray:
        """K of roll, pitch, yaw at a collective thrust [N] [1/s]."""
        return self.per_slope * self.throttle_map.mix_slope(thrust)


class RateHandover:
    """Body-rate setpoints from a controller's command (see the module docstring).

    Parameters
    ----------
    belief : Scenario
        Believed vehicle (inertia, rotors).
    config : FirmwareConfig
        The firmware's configuration: P gains; I, D and feed-forward must be 0.
    throttle_map : ThrottleMap
        The believed throttle path of that configuration.

    Raises
    ------
    ValueError
        A term of :data:`PROPORTIONAL_ONLY` is not 0 (naming it).
    """

    def __init__(self, belief: Scenario, config: FirmwareConfig, throttle_map: ThrottleMap):
        for name in PROPORTIONAL_ONLY:
            value = config.number(name)
            if value != 0.0:
                raise ValueError(f"{config.source}: the rate hand-over needs a proportional rate "
                                 f"loop: set {name} = 0 (is {value:g})")  # fmt: skip
        self.J = np.asarray(belief.vehicle.inertia, dtype=float)
        self.gain = RateLoopGain.from_config(config, belief.vehicle, throttle_map)

    def rates(self, estimate: StateEstimate, command: Command) -> FloatArray:
        """w_cmd in F_B [rad/s]; zero when the command carries no torque (motors off)."""
        tau = command.torque_B
        if tau is None or command.thrust is None:
            return np.zeros(3)
        w = np.asarray(estimate.body.omega_B, dtype=float)
        alpha = (np.asarray(tau, dtype=float) - cross3(w, self.J * w)) / self.J
        gyro = w if estimate.gyro_bias_B is None else w + estimate.gyro_bias_B
        return gyro + alpha / self.gain.at(command.thrust)


__all__ = ["PROPORTIONAL_ONLY", "PTERM_SCALE", "RateHandover", "RateLoopGain"]
