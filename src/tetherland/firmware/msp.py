"""A minimal MSP v1 client over the SITL's TCP port (read-only queries).

Frame: ``$M<`` size command payload checksum, the checksum the XOR of size, command and
payload; the answer comes as ``$M>`` in the same form (``$M!`` for an unknown command).
Used to read back what the firmware sees (raw IMU, attitude, arming flags) in tests and
diagnostics; the flight itself never talks MSP.
"""

from __future__ import annotations

import socket
import struct
import time

from tetherland.firmware.process import LOOPBACK, FirmwareError

MSP_STATUS_EX = 150
MSP_RAW_IMU = 102
MSP_ATTITUDE = 108
MSP_MOTOR = 104
MSP_DEBUG = 254


def _frame(command: int, payload: bytes = b"") -> bytes:
    checksum = len(payload) ^ command
    for b in payload:
        checksum ^= b
    return b"$M<" + bytes([len(payload), command]) + payload + bytes([checksum])


class MspClient:
    """Connects to the SITL's UART1 port; :meth:`request` sends one query."""

    def __init__(self, port: int, timeout: float = 2.0):
        self.sock = socket.create_connection((LOOPBACK, port), timeout=timeout)
        self.timeout = timeout
        self._buf = b""

    def send(self, command: int) -> None:
        """Queue a query (the firmware answers when its serial task runs)."""
        self.sock.sendall(_frame(command))

    def receive(self, command: int) -> bytes:
        """The payload of the next answer to ``command``."""
        deadline = time.monotonic() + self.timeout
        while True:
            start = self._buf.find(b"$M")
            if start >= 0 and len(self._buf) >= start + 5:
                size, cmd = self._buf[start + 3], self._buf[start + 4]
                end = start + 5 + size + 1
                if len(self._buf) >= end:
                    kind, payload = self._buf[start + 2 : start + 3], self._buf[start + 5 : end - 1]
                    self._buf = self._buf[end:]
                    if cmd == command:
                        if kind != b">":
                            raise FirmwareError(f"MSP command {command} was refused")
                        return payload
                    continue
            if time.monotonic() > deadline:
                raise FirmwareError(f"no MSP answer to command {command}")
            self._buf += self.sock.recv(4096)

    def request(self, command: int) -> bytes:
        self.send(command)
        return self.receive(command)

    def close(self) -> None:
        self.sock.close()


def arming_disable_flags(payload: bytes) -> int:
    """The arming-disable bit field of an MSP_STATUS_EX answer."""
    n_modes = payload[15]
    offset = 16 + n_modes
    return struct.unpack_from("<I", payload, offset + 1)[0]


def raw_imu(payload: bytes) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """(acc, gyro) of an MSP_RAW_IMU answer, both in the sensors' raw units: acc in
    1/``acc_1G`` g (256 per g for the virtual accelerometer), gyro in LSB of the gyro
    driver's scale (16.384 per deg/s for the virtual gyro: ``gyroRateDps`` divides the
    filtered rate by the driver's scale, despite its name)."""
    v = struct.unpack_from("<9h", payload)
    return v[0:3], v[3:6]


def debug_values(payload: bytes) -> tuple[int, ...]:
    """The ``debug[]`` array of an MSP_DEBUG answer (what ``debug_mode`` selects)."""
    return struct.unpack_from(f"<{len(payload) // 2}h", payload)


def attitude(payload: bytes) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of an MSP_ATTITUDE answer [deg] (roll and pitch in 0.1 deg)."""
    r, p, y = struct.unpack_from("<3h", payload)
    return r / 10.0, p / 10.0, float(y)


__all__ = ["MspClient", "arming_disable_flags", "attitude", "debug_values", "raw_imu"]
