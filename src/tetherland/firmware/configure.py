"""The firmware's configuration: a file of CLI commands, applied through Betaflight's CLI.

:class:`FirmwareConfig` reads the file (``betaflight_default.txt`` beside this module: one
command a line, ``#`` starts the reason). :func:`configured_eeprom` starts the SITL once,
types every command into its CLI over the TCP port of UART1, ends with ``save`` (the SITL
writes ``eeprom.bin`` and exits) and keeps the image in the firmware cache, named by the
hash of the executable and the commands; each flight starts from a copy.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import socket
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from tetherland.firmware.build import FirmwareBuild, cache_dir
from tetherland.firmware.process import LOOPBACK, FirmwareError, SitlProcess

DEFAULT_CONFIG = Path(__file__).with_name("betaflight_default.txt")
_SET = re.compile(r"^set\s+(\w+)\s*=\s*(\S+)$")
_PROMPT = b"\r\n# "


@dataclass(frozen=True)
class FirmwareConfig:
    """CLI commands and the ``set`` values among them.

    Attributes
    ----------
    commands : tuple of str
        The commands in order, reasons stripped.
    settings : dict
        ``name -> value`` of every ``set`` command (text, as typed).
    source : str
        Where the commands come from.
    """

    commands: tuple[str, ...]
    settings: dict[str, str]
    source: str

    @classmethod
    def load(cls, path: Path = DEFAULT_CONFIG) -> FirmwareConfig:
        commands, settings = [], {}
        for line in Path(path).read_text().splitlines():
            command = line.split("#", 1)[0].strip()
            if not command:
                continue
            commands.append(command)
            m = _SET.match(command)
            if m:
                settings[m.group(1)] = m.group(2)
        return cls(tuple(commands), settings, str(path))

    def number(self, name: str) -> float:
        """A numeric ``set`` value; FirmwareError naming the setting when absent."""
        try:
            return float(self.settings[name])
        except (KeyError, ValueError):
            raise FirmwareError(f"{self.source}: needs a numeric 'set {name} = ...'") from None

    def with_settings(self, **values: str | float) -> FirmwareConfig:
        """This configuration with the ``set`` values of ``values`` replaced (appended when
        absent); the source names the change."""
        commands, pending = [], {k: str(v) for k, v in values.items()}
        for command in self.commands:
            m = _SET.match(command)
            if m and m.group(1) in pending:
                command = f"set {m.group(1)} = {pending.pop(m.group(1))}"
            commands.append(command)
        commands += [f"set {k} = {v}" for k, v in pending.items()]
        settings = {**self.settings, **{k: str(v) for k, v in values.items()}}
        changes = ", ".join(f"{k} = {v}" for k, v in values.items())
        return FirmwareConfig(tuple(commands), settings, f"{self.source} ({changes})")

    def key(self) -> str:
        return hashlib.sha256("\n".join(self.commands).encode()).hexdigest()[:16]


def _read_until(sock: socket.socket, done: Callable[[bytes], bool], timeout: float) -> bytes:
    """Receive until ``done(data)``, the peer closes or ``timeout`` seconds pass [s]."""
    data, deadline = b"", time.monotonic() + timeout
    while not done(data) and time.monotonic() < deadline:
        try:
            chunk = sock.recv(4096)
        except TimeoutError:
            continue
        if not chunk:
            break
        data += chunk
    return data


def _read_until_prompt(sock: socket.socket, timeout: float) -> bytes:
    data = _read_until(sock, lambda d: d.endswith(_PROMPT), timeout)
    if not data.endswith(_PROMPT):
        raise FirmwareError(f"no CLI prompt within {timeout:g} s (got {data[-80:]!r})")
    return data


def apply_cli(port: int, commands: tuple[str, ...], timeout: float = 5.0) -> list[str]:
    """Type ``commands`` into the CLI on ``127.0.0.1:port``, then ``save``.

    Returns the firmware's answer to each command; raises FirmwareError naming the first
    command it rejects.
    """
    answers = []
    with socket.create_connection((LOOPBACK, port), timeout=timeout) as sock:
        sock.settimeout(0.2)
        deadline = time.monotonic() + timeout
        banner = b""
        while _PROMPT not in banner:  # '#' enters the CLI (retried until it answers)
            if time.monotonic() > deadline:
                raise FirmwareError("the firmware's CLI did not answer")
            sock.sendall(b"#")
            try:
                banner += sock.recv(4096)
            except TimeoutError:
                pass
        for command in commands:
            sock.sendall(command.encode() + b"\n")
            answer = _read_until_prompt(sock, timeout).decode(errors="replace")
            if "ERROR" in answer or "Invalid" in answer:
                line = " ".join(answer.split())
                raise FirmwareError(f"the firmware rejected {command!r}: {line[:160]}")
            answers.append(answer)
        sock.sendall(b"save\n")  # writes eeprom.bin, answers 'Rebooting' and exits
        _read_until(sock, lambda d: b"Rebooting" in d, timeout)
    return answers


def configured_eeprom(build: FirmwareBuild, config: FirmwareConfig) -> Path:
    """The configuration image for ``config`` on ``build`` (made once, then cached)."""
    target = cache_dir() / f"eeprom-{build.key}-{config.key()}.bin"
    if target.is_file():
        return target
    with SitlProcess(build.executable, lockstep=False) as sitl:
        apply_cli(sitl.cli_port, config.commands)
        try:
            sitl.wait(10.0)  # 'save' writes eeprom.bin and exits
        except Exception as err:
            raise FirmwareError("the SITL did not exit after 'save'") from err
        image = sitl.folder / "eeprom.bin"
        tmp = target.with_suffix(f".{os.getpid()}.{id(sitl)}.tmp")  # parallel workers
        shutil.copyfile(image, tmp)
        tmp.replace(target)
    return target


__all__ = ["DEFAULT_CONFIG", "FirmwareConfig", "apply_cli", "configured_eeprom"]
