"""Sensor settings: IMU and motion capture (docs/theory.md sections 8, 9 and 12)."""

from __future__ import annotations

from pydantic import Field

from tetherland.config.base import Section


class ImuConfig(Section):
    """Strapdown IMU: specific force and angular rate in F_B, white noise and bias walks."""

    rate_hz: float = Field(1000.0, gt=0, le=10000)
    """Sample rate of the IMU [Hz]."""
    gyro_noise: float = Field(0.005, ge=0, le=10)
    """Standard deviation of the gyro white noise per sample [rad/s]."""
    accel_noise: float = Field(0.05, ge=0, le=100)
    """Standard deviation of the accelerometer white noise per sample [m/s^2]."""
    gyro_bias_walk: float = Field(1.0e-4, ge=0, le=1)
    """Gyro bias random-walk intensity [rad/s per sqrt(s)]."""
    accel_bias_walk: float = Field(1.0e-3, ge=0, le=10)
    """Accelerometer bias random-walk intensity [m/s^2 per sqrt(s)]."""
    gyro_bias_initial: float = Field(0.0, ge=0, le=1)
    """Standard deviation of the initial gyro bias [rad/s]."""
    accel_bias_initial: float = Field(0.0, ge=0, le=10)
    """Standard deviation of the initial accelerometer bias [m/s^2]."""


class MocapConfig(Section):
    """Motion capture: position and attitude of the body, with noise, latency and dropouts."""

    rate_hz: float = Field(120.0, gt=0, le=2000)
    """Sample rate of the motion-capture poses [Hz]."""
    position_noise: float = Field(0.001, ge=0, le=1)
    """Standard deviation of the position noise per axis [m]."""
    attitude_noise_deg: float = Field(0.3, ge=0, le=45)
    """Standard deviation of the attitude noise per axis (rotation vector) [deg]."""
    latency: float = Field(0.005, ge=0, le=1)
    """Delay between the measured instant and its delivery [s]."""
    dropout_rate: float = Field(0.0, ge=0, le=100)
    """Mean number of dropouts per second (Poisson) [1/s]."""
    dropout_duration: float = Field(0.0, ge=0, le=10)
    """Length of each dropout [s]."""


class SensorsConfig(Section):
    """All sensors of the vehicle."""

    imu: ImuConfig = ImuConfig()
    """Inertial measurement unit."""
    mocap: MocapConfig = MocapConfig()
    """Motion-capture system."""
    noise_scale: float = Field(1.0, ge=0, le=100)
    """Multiplier applied to every noise and bias intensity (0 gives perfect sensors) [-]."""
