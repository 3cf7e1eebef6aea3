"""Betaflight SITL's UDP packets, byte for byte (``target/SITL/target.h`` of Betaflight 4.6).

- ``fdm_packet`` (simulator -> firmware, 144 bytes, little-endian doubles): timestamp [s],
  imu_angular_velocity_rpy [rad/s], imu_linear_acceleration_xyz [m/s^2],
  imu_orientation_quat (w, x, y, z), velocity_xyz [m/s], position_xyz [m], pressure [Pa].
  The frames of each field are :mod:`tetherland.firmware.frames`' business.
- ``rc_packet`` (simulator -> firmware, 40 bytes): timestamp [s], 16 channels [us PWM,
  uint16].
- ``servo_packet`` (firmware -> simulator, 16 bytes): 4 motor outputs (float32), normalised
  to [0, 1], in the SITL's own slot order (:mod:`tetherland.firmware.motors`).
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

import numpy as np

from tetherland.geometry import FloatArray

RC_CHANNELS = 16
"""SIMULATOR_MAX_RC_CHANNELS."""

FDM = struct.Struct("<d3d3d4d3d3dd")
RC = struct.Struct(f"<d{RC_CHANNELS}H")
SERVO = struct.Struct("<4f")


@dataclass(frozen=True, slots=True)
class FdmPacket:
    """One flight-dynamics state for the firmware (already in the firmware's frames).

    Attributes
    ----------
    timestamp : float
        Simulated time [s].
    omega_rpy : (3,) array
        Angular velocity, body axes forward-right-down [rad/s].
    accel_xyz : (3,) array
        Field the firmware negates into its accelerometer [m/s^2].
    quat_wxyz : (4,) array
        Attitude quaternion (w, x, y, z) [-].
    velocity_xyz : (3,) array
        Velocity [m/s].
    position_xyz : (3,) array
        Position [m].
    pressure : float
        Static pressure [Pa].
    """

    timestamp: float
    omega_rpy: FloatArray
    accel_xyz: FloatArray
    quat_wxyz: FloatArray
    velocity_xyz: FloatArray
    position_xyz: FloatArray
    pressure: float

    def pack(self) -> bytes:
        return FDM.pack(self.timestamp, *self.omega_rpy, *self.accel_xyz, *self.quat_wxyz,
                        *self.velocity_xyz, *self.position_xyz, self.pressure)  # fmt: skip

    @classmethod
    def unpack(cls, data: bytes) -> FdmPacket:
        v = np.array(FDM.unpack(data))
        return cls(float(v[0]), v[1:4], v[4:7], v[7:11], v[11:14], v[14:17], float(v[17]))


@dataclass(frozen=True, slots=True)
class RcPacket:
    """One radio frame.

    Attributes
    ----------
    timestamp : float
        Simulated time the frame is sent [s].
    channels : tuple of int
        16 channel values [us], 1000 to 2000 in use.
    """

    timestamp: float
    channels: tuple[int, ...]

    def __post_init__(self) -> None:
        if len(self.channels) != RC_CHANNELS or not all(0 <= c < 65536 for c in self.channels):
            raise ValueError(f"an RC packet has {RC_CHANNELS} channels in 0..65535 us")

    def pack(self) -> bytes:
        return RC.pack(self.timestamp, *self.channels)

    @classmethod
    def unpack(cls, data: bytes) -> RcPacket:
        v = RC.unpack(data)
        return cls(v[0], tuple(v[1:]))


def unpack_servo(data: bytes) -> FloatArray:
    """The 4 normalised motor outputs of a ``servo_packet`` (SITL slot order) [-]."""
    if len(data) != SERVO.size:
        raise ValueError(f"a servo packet has {SERVO.size} bytes, got {len(data)}")
    return np.array(SERVO.unpack(data))


__all__ = ["FDM", "RC", "RC_CHANNELS", "SERVO", "FdmPacket", "RcPacket", "unpack_servo"]
