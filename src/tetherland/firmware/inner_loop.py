"""Betaflight SITL as the vehicle's flight controller, in lockstep with the plant.

:class:`FirmwareInnerLoop` implements :class:`~tetherland.interfaces.InnerLoop`. At every
IMU sample it sends the firmware one ``fdm_packet`` (the sample as measured, noise and
biases included, in Betaflight's frames) and waits for the ``servo_packet`` of the one PID
loop that packet runs; the ESC model turns the outputs into rotor speed commands. Every
``imu_rate / radio_hz`` samples a radio frame goes first, on the same socket, so the
firmware applies it before that loop: the latest setpoint of the outer loop as body rates
(:class:`~tetherland.firmware.handover.RateHandover`), throttle
(:class:`~tetherland.firmware.motors.ThrottleMap`) and the arm switch (armed unless the
reference switches the motors off). The firmware's clock is the packets' timestamps, so
a run is a function of its inputs: the same seed gives the same flight.

Radio rate: 100 Hz by default, the frame rate of common links (CRSF at 150 Hz, ELRS and
FrSky at 50-500 Hz, SBUS 9-14 ms frames); it divides the 1 kHz IMU rate.
"""

from __future__ import annotations

import socket

import numpy as np

from tetherland import GRAVITY
from tetherland.config import Scenario
from tetherland.firmware.build import FirmwareBuild, ensure_firmware
from tetherland.firmware.configure import FirmwareConfig, configured_eeprom
from tetherland.firmware.frames import fdm_packet
from tetherland.firmware.handover import RateHandover
from tetherland.firmware.motors import Esc, ThrottleMap
from tetherland.firmware.packets import RcPacket, unpack_servo
from tetherland.firmware.process import LOOPBACK, FirmwareError, SitlProcess
from tetherland.firmware.rc import RcMap
from tetherland.geometry import FloatArray
from tetherland.interfaces import Command, ControlMode, ImuSample, Reference, StateEstimate
from tetherland.models.quadrotor import RotorLayout

BOOT_S = 2.0
"""Firmware time on the pad before the mission starts [s]."""


class FirmwareInnerLoop:
    """The lockstep Betaflight bridge (implements InnerLoop).

    Parameters
    ----------
    truth : Scenario
        The hardware: the ESCs' full-output speed and the IMU rate.
    belief : Scenario
        What the outer loop knows: inertia and rotors (the hand-over's gain, the throttle
        map).
    config : FirmwareConfig, optional
        CLI commands (default: ``betaflight_default.txt``).
    radio_hz : float
        Radio frame rate [Hz]; must divide the IMU rate.
    timeout_s : float
        Wall time to wait for a motor packet before the firmware counts as lost [s].
    build : FirmwareBuild, optional
        The SITL executable (default: built or found by :func:`ensure_firmware`).
    """

    def __init__(
        self,
        truth: Scenario,
        belief: Scenario,
        *,
        config: FirmwareConfig | None = None,
        radio_hz: float = 100.0,
        timeout_s: float = 2.0,
        build: FirmwareBuild | None = None,
    ) -> None:
        self.config = config or FirmwareConfig.load()
        imu_hz = truth.sensors.imu.rate_hz
        every = imu_hz / radio_hz
        if radio_hz <= 0 or abs(every - round(every)) > 1e-9 or round(every) < 1:
            raise ValueError(f"radio_hz = {radio_hz:g} Hz must divide the IMU rate {imu_hz:g} Hz")
        self.imu_hz = round(imu_hz)
        self.dt = 1.0 / imu_hz
        self.radio_every = round(every)
        self.timeout_s = timeout_s
        self.esc = Esc.from_vehicle(truth.vehicle)
        self._believed_esc = Esc.from_vehicle(belief.vehicle)
        self._layout = RotorLayout.from_config(belief.vehicle)
        self._c_f = belief.vehicle.thrust_coefficient
        self.throttle_map = ThrottleMap(
            belief.vehicle.f_max,
            idle=self.config.number("motor_idle") / 1e4,
            thrust_linear=self.config.number("thrust_linear") / 100.0,
        )
        self.handover = RateHandover(belief, self.config, self.throttle_map)
        self.rc = RcMap.from_config(self.config)
        self._build = build
        self.sitl: SitlProcess | None = None
        self._sock: socket.socket | None = None
        self._reset()

    def _reset(self) -> None:
        self.k = 0  # packets sent this run
        self.channels: tuple[int, ...] = self.rc.channels(np.zeros(3), 0.0, False)
        self.estimate: StateEstimate | None = None
        self.armed = False  # the firmware's outputs say it is armed
        self.outputs = np.zeros(4)  # last servo packet [-]
        self.last_rates = np.zeros(3)  # last rate setpoint sent [rad/s]
        self.last_throttle = 0.0

    # ------------------------------------------------------------------ InnerLoop
    def start(self) -> None:
        """Boot a fresh, configured firmware in lockstep (one process per run)."""
        self.stop()
        self._reset()
        build = self._build or ensure_firmware()
        eeprom = configured_eeprom(build, self.config)
        self.sitl = SitlProcess(build.executable, lockstep=True, gyro_hz=self.imu_hz,
                                eeprom=eeprom)  # fmt: skip
        self._sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self._sock.bind((LOOPBACK, 0))
        self._sock.settimeout(self.timeout_s)
        self._addr = (LOOPBACK, self.sitl.state_port)
        self._boot()

    def _boot(self) -> None:
        """Power-on on the pad before the mission clock starts: ``BOOT_S`` of state packets
        at rest (zero rate, 1 g along z_B) with the arm switch off, so that the firmware
        can arm when the mission asks for thrust: it holds arming until its receiver has
        had frames for 0.35 s and its (virtual, always present) barometer has calibrated
        on 100 readings, 1-2 s. Sensor noise starts with the mission's samples."""
        rest = ImuSample(0.0, np.array([0.0, 0.0, GRAVITY]), np.zeros(3))
        for _ in range(round(BOOT_S * self.imu_hz)):
            self.step(rest)

    def setpoint(
        self, t: float, estimate: StateEstimate, reference: Reference, command: Command
    ) -> None:
        """The channels of the next radio frame."""
        self.estimate = estimate
        if reference.mode == ControlMode.MOTORS_OFF:
            self.channels = self.rc.channels(np.zeros(3), 0.0, False)
            return
        if not self.armed:  # arm first: sticks centred, throttle low
            self.channels = self.rc.arming()
            return
        rates = self.handover.rates(estimate, command)
        thrust = 0.0 if command.thrust is None else command.thrust
        self.last_rates, self.last_throttle = rates, self.throttle_map.throttle(thrust)
        self.channels = self.rc.channels(rates, self.last_throttle, True)

    def step(self, imu: ImuSample) -> FloatArray:
        """Send the sample (and a radio frame when due), run one PID loop, return the
        rotor speed commands [rad/s]."""
        sock = self._sock
        if sock is None or self.sitl is None:
            raise FirmwareError("the firmware is not running (start() first)")
        t = self.k * self.dt
        try:
            if self.k % self.radio_every == 0:
                sock.sendto(RcPacket(t, self.channels).pack(), self._addr)
            sock.sendto(fdm_packet(t, imu, self.estimate).pack(), self._addr)
            data = sock.recv(64)
        except (TimeoutError, OSError) as err:
            raise FirmwareError(self._lost(err)) from None
        self.k += 1
        self.outputs = unpack_servo(data)
        self.armed = bool(np.any(self.outputs > 0.0))
        return self.esc.rotor_speeds(self.outputs)

    def applied(self, command: Command) -> Command:
        """The rotors' commands from the firmware's last outputs (motor telemetry) and the
        thrust and torque they mean for the believed rotors; the outer controller's
        diagnostics kept."""
        w = self._believed_esc.rotor_speeds(self.outputs)
        wrench = self._layout.wrench(self._c_f * w * w)
        return Command(rotor_speeds=w, thrust=float(wrench[0]), torque_B=wrench[1:4],
                       diagnostics=command.diagnostics)  # fmt: skip

    def stop(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None
        if self.sitl is not None:
            self.sitl.kill()
            self.sitl = None

    # ------------------------------------------------------------------ helpers
    def _lost(self, err: Exception) -> str:
        assert self.sitl is not None
        code = self.sitl.proc.poll()
        why = f"no motor packet within {self.timeout_s:g} s" if isinstance(
            err, TimeoutError) else f"{type(err).__name__}: {err}"  # fmt: skip
        state = "process running" if code is None else f"process exited with code {code}"
        return f"firmware lost after {self.k} packets ({why}; {state})"

__all__ = ["BOOT_S", "FirmwareInnerLoop"]
