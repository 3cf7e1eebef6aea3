"""Body rates, throttle and arming as RC channels (AETR, ARM on AUX1), and back.

Actual rates with centre sensitivity equal to the maximum rate and no expo make Betaflight's
rate setpoint linear in the stick: rate = max_rate (pwm - 1500)/500. Betaflight's setpoint
axes are its gyro's, FLU (:mod:`tetherland.firmware.frames`): roll and pitch sticks map to
+omega_x and +omega_y, and the yaw stick is inverted by the firmware (stick right turns
clockwise seen from above, -omega_z). Throttle: pwm = 1000 + 1000 t (``min_check`` 1000).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tetherland.firmware.configure import FirmwareConfig
from tetherland.firmware.packets import RC_CHANNELS
from tetherland.geometry import FloatArray

ARM_HIGH, ARM_LOW = 1800, 1000
"""AUX1 values for armed and disarmed (the ``aux`` range is 1700-2100 us)."""
THROTTLE_ARMING = 990
"""Throttle channel while arming: below ``min_check`` [us]."""


@dataclass(frozen=True)
class RcMap:
    """Stick scaling of the configuration's rates.

    Attributes
    ----------
    max_rate : (3,) array
        Full-stick rate of roll, pitch, yaw [rad/s].
    """

    max_rate: FloatArray

    @classmethod
    def from_config(cls, config: FirmwareConfig) -> RcMap:
        rates = []
        for axis in ("roll", "pitch", "yaw"):
            centre = config.number(f"{axis}_rc_rate")
            if config.number(f"{axis}_srate") != centre or config.number(f"{axis}_expo") != 0:
                raise ValueError(f"{config.source}: {axis} rates must be linear "
                                 "(rc_rate = srate, expo 0)")  # fmt: skip
            rates.append(math.radians(10.0 * centre))
        if config.settings.get("rates_type") != "ACTUAL":
            raise ValueError(f"{config.source}: needs 'set rates_type = ACTUAL'")
        return cls(np.array(rates))

    def channels(self, omega_B: FloatArray, throttle: float, armed: bool) -> tuple[int, ...]:
        """16 channels [us] for body rates omega_B [rad/s] (clipped to the full-stick rate),
        throttle in [0, 1] and the arm switch."""
        x = np.clip(np.asarray(omega_B, dtype=float) / self.max_rate, -1.0, 1.0)
        roll, pitch, yaw = (1500 + np.rint(500.0 * x * np.array([1.0, 1.0, -1.0]))).astype(int)
        thr = 1000 + round(1000.0 * min(max(throttle, 0.0), 1.0))
        out = [1500] * RC_CHANNELS
        out[0:5] = [int(roll), int(pitch), thr, int(yaw), ARM_HIGH if armed else ARM_LOW]
        return tuple(out)

    def arming(self) -> tuple[int, ...]:
        """Centred sticks, throttle low, AUX1 high: what arming needs."""
        out = [1500] * RC_CHANNELS
        out[2], out[4] = THROTTLE_ARMING, ARM_HIGH
        return tuple(out)

    def rates(self, channels: tuple[int, ...]) -> FloatArray:
        """The rate setpoint the firmware derives from ``channels`` [rad/s] (inverse)."""
        x = (np.array(channels[0:4:1])[[0, 1, 3]] - 1500) / 500.0 * np.array([1.0, 1.0, -1.0])
        return x * self.max_rate


__all__ = ["ARM_HIGH", "ARM_LOW", "THROTTLE_ARMING", "RcMap"]
