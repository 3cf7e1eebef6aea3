"""tetherland's frames to Betaflight SITL's, written once.

tetherland: world F_W with z up, taken here as north-west-up (x_W north, y_W west); body
F_B forward-left-up (FLU); quaternions (w, x, y, z) of R_WB. Betaflight's own gyro and
accelerometer axes are FLU as well (its mixer rolls right for +x, pitches nose down for +y,
yaws counter-clockwise seen from above for +z); the SITL fills them from the packet as
(``sitl.c``, ``updateState``)::

    gyro  = (+p[0], -p[1], -p[2])    p = imu_angular_velocity_rpy  (so p is F_B in FRD)
    acc   = -a                       a = imu_linear_acceleration_xyz (all three negated)

and takes ``imu_orientation_quat`` as the attitude of a forward-right-down body in a
north-east-down earth frame (its Euler angles then come out as Betaflight's: roll right
wing down, pitch nose down, yaw clockwise, all positive). Hence, with the flip
F = diag(1, -1, -1) between FLU/FRD and NWU/NED::

    p = F omega_B          a = -f_B           q_NED,FRD = (w, x, -y, -z) of q_WB
    velocity (ENU, the struct's virtual-GPS convention) = (-v_y, v_x, v_z)
    position (NED) = F p_W      pressure: ISA at the altitude z_W

so that the firmware's gyro reads omega_B and its accelerometer the specific force f_B.
"""

from __future__ import annotations

import numpy as np

from tetherland.firmware.packets import FdmPacket
from tetherland.geometry import FloatArray
from tetherland.interfaces import ImuSample, StateEstimate

FLIP = np.array([1.0, -1.0, -1.0])
"""diag(1, -1, -1): FLU <-> FRD and NWU <-> NED."""
P0 = 101325.0
"""Sea-level standard pressure [Pa]."""


def pressure_at(z: float) -> float:
    """International Standard Atmosphere pressure at altitude ``z`` [m] above sea level [Pa]."""
    return P0 * (1.0 - 2.25577e-5 * z) ** 5.25588


def quat_ned_frd(q_WB: FloatArray) -> FloatArray:
    """q of R_NED,FRD = F R_WB F from q_WB (w, x, y, z): (w, x, -y, -z)."""
    q = np.asarray(q_WB, dtype=float)
    return np.array([q[0], q[1], -q[2], -q[3]])


def fdm_packet(t: float, imu: ImuSample, estimate: StateEstimate | None) -> FdmPacket:
    """The state packet of one IMU sample.

    Parameters
    ----------
    t : float
        Firmware time of the sample [s].
    imu : ImuSample
        What the vehicle's IMU measured (noise and biases included), F_B.
    estimate : StateEstimate or None
        The robot's latest estimate, for the attitude, velocity and position fields (the
        SITL uses the attitude in place of its own attitude filter); None before the
        first: level at the origin.
    """
    if estimate is None:
        q, v, p = np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3), np.zeros(3)
    else:
        b = estimate.body
        q, v, p = b.q_WB, b.v_W, b.p_W
    return FdmPacket(
        timestamp=t,
        omega_rpy=FLIP * imu.omega_B,
        accel_xyz=-np.asarray(imu.specific_force_B, dtype=float),
        quat_wxyz=quat_ned_frd(q),
        velocity_xyz=np.array([-v[1], v[0], v[2]]),
        position_xyz=FLIP * p,
        pressure=pressure_at(float(p[2])),
    )


def firmware_gyro(packet: FdmPacket) -> FloatArray:
    """What the SITL writes into its gyro (its ``updateState``), rad/s in its own axes."""
    return np.array([1.0, -1.0, -1.0]) * packet.omega_rpy


def firmware_accelerometer(packet: FdmPacket) -> FloatArray:
    """What the SITL writes into its accelerometer, m/s^2 in its own axes."""
    return -packet.accel_xyz


def firmware_euler(packet: FdmPacket) -> FloatArray:
    """Betaflight's (roll, pitch, yaw) of the packet's quaternion in the SITL build [rad]:
    its rotation matrix with entries (1,0) and (2,0) negated (``imuComputeRotationMatrix``
    under SIMULATOR_BUILD), then ``imuUpdateEulerAngles``."""
    w, x, y, z = packet.quat_wxyz
    r10 = -2.0 * (x * y + w * z)
    r20 = -2.0 * (x * z - w * y)
    r00 = 1.0 - 2.0 * (y * y + z * z)
    r21 = 2.0 * (y * z + w * x)
    r22 = 1.0 - 2.0 * (x * x + y * y)
    roll = np.arctan2(r21, r22)
    pitch = 0.5 * np.pi - np.arccos(np.clip(-r20, -1.0, 1.0))
    yaw = -np.arctan2(r10, r00)
    return np.array([roll, pitch, yaw])


__all__ = [
    "FLIP",
    "fdm_packet",
    "firmware_accelerometer",
    "firmware_euler",
    "firmware_gyro",
    "pressure_at",
    "quat_ned_frd",
]
