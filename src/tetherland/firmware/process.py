"""One SITL process: started in its own folder, every socket on the loopback, ports read back.

The SITL writes ``eeprom.bin`` into its working directory, so each process gets a fresh
temporary folder. Ports are chosen per run by the operating system (the patched SITL
binds port 0 and prints what it got), so parallel processes never collide. The SITL
ignores SIGTERM; :meth:`SitlProcess.kill` sends SIGKILL, and a process whose parent dies
is killed by the kernel (``PR_SET_PDEATHSIG``) or exits after ``SITL_IDLE_EXIT_S``
seconds without a packet in lockstep.
"""

from __future__ import annotations

import ctypes
import os
import re
import shutil
import signal
import subprocess
import tempfile
import time
from pathlib import Path

from tetherland.errors import TetherlandError

LOOPBACK = "127.0.0.1"
_STATE_PORT = re.compile(r"\[SITL\] bound state port (\d+)")
_UART1_PORT = re.compile(r"bind port (\d+) for UART1\b")


class FirmwareError(TetherlandError):
    """The firmware process failed to start, to take its configuration, or was lost."""


def _die_with_parent() -> None:  # runs in the child before exec
    libc = ctypes.CDLL("libc.so.6", use_errno=True)
    libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG


class SitlProcess:
    """A running SITL executable.

    Parameters
    ----------
    executable : Path
        The (patched) SITL binary.
    lockstep : bool
        One PID loop per state packet on a simulated clock (``SITL_LOCKSTEP``).
    gyro_hz : int
        Virtual gyro sample rate in lockstep: the state-packet rate [Hz].
    eeprom : Path, optional
        Configuration image to start from (copied into the process's folder).
    start_timeout : float
        Seconds to wait for the ports [s].
    """

    def __init__(
        self,
        executable: Path,
        *,
        lockstep: bool,
        gyro_hz: int = 1000,
        eeprom: Path | None = None,
        start_timeout: float = 10.0,
    ) -> None:
        self.folder = Path(tempfile.mkdtemp(prefix="tetherland-sitl-"))
        if eeprom is not None:
            shutil.copyfile(eeprom, self.folder / "eeprom.bin")
        self.log_path = self.folder / "sitl.log"
        env = dict(os.environ, SITL_BIND_ADDR=LOOPBACK, SITL_STATE_PORT="0", SITL_RC_PORT="0",
                   SITL_TCP_PORT_BASE="0", SITL_LOCKSTEP="1" if lockstep else "0",
                   SITL_GYRO_HZ=str(int(gyro_hz)))  # fmt: skip
        with self.log_path.open("wb") as log:
            self.proc = subprocess.Popen(
                [str(executable)], cwd=self.folder, env=env, stdin=subprocess.DEVNULL,
                stdout=log, stderr=subprocess.STDOUT, preexec_fn=_die_with_parent,
            )  # fmt: skip
        try:
            self.state_port, self.cli_port = self._ports(start_timeout)
        except FirmwareError:
            self.kill()
            raise

    def _ports(self, timeout: float) -> tuple[int, int]:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            text = self.log_path.read_text(errors="replace")
            state, uart = _STATE_PORT.search(text), _UART1_PORT.search(text)
            if state and uart:
                return int(state.group(1)), int(uart.group(1))
            if self.proc.poll() is not None:
                raise FirmwareError(f"the SITL exited at start (code {self.proc.returncode})")
            time.sleep(0.01)
        raise FirmwareError(f"the SITL did not report its ports within {timeout:g} s")

    def alive(self) -> bool:
        return self.proc.poll() is None

    def wait(self, timeout: float) -> int:
        """Wait for the process to exit by itself; its exit code."""
        return self.proc.wait(timeout)

    def kill(self) -> None:
        """SIGKILL (the SITL ignores SIGTERM) and remove its folder."""
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(5.0)
        shutil.rmtree(self.folder, ignore_errors=True)

    def __enter__(self) -> SitlProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.kill()


__all__ = ["LOOPBACK", "FirmwareError", "SitlProcess"]
