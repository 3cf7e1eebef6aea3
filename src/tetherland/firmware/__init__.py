"""Real flight firmware in the loop: Betaflight 4.6 SITL as the vehicle's rate controller.

tetherland's supervisor, estimator and controllers become the outer loop; their desired
attitude and thrust reach the firmware as body-rate and throttle sticks over a simulated
radio link, and the firmware's motor outputs drive the plant's rotors, in lockstep
(docs/firmware.md). Needs the optional extra ``tetherland[firmware]`` and a C compiler.

Roles: :mod:`~tetherland.firmware.build` (the patched SITL in the cache),
:mod:`~tetherland.firmware.process` (one SITL process), :mod:`~tetherland.firmware.configure`
(the CLI configuration), :mod:`~tetherland.firmware.packets` (the UDP packets),
:mod:`~tetherland.firmware.frames` (frame conventions), :mod:`~tetherland.firmware.motors`
(ESC, throttle path, motor order), :mod:`~tetherland.firmware.rc` (sticks),
:mod:`~tetherland.firmware.handover` (what the outer loop sends, the rate loop's gain),
:mod:`~tetherland.firmware.inner_loop` (the lockstep bridge),
:mod:`~tetherland.firmware.step_response` (rate steps on the plant, either inner loop).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from tetherland.config import Scenario
from tetherland.firmware.build import (
    FIRMWARE_VERSION,
    PACKAGE,
    PACKAGE_VERSION,
    FirmwareBuild,
    FirmwareUnavailable,
    build_key,
    ensure_firmware,
)
from tetherland.firmware.configure import FirmwareConfig
from tetherland.firmware.handover import RateHandover, RateLoopGain
from tetherland.firmware.inner_loop import FirmwareInnerLoop
from tetherland.firmware.process import FirmwareError

FIRMWARES = ("betaflight",)
"""Names accepted by ``--firmware``."""


@dataclass(frozen=True)
class BetaflightSitl:
    """Factory of :class:`FirmwareInnerLoop` for :func:`tetherland.runs.run_mission`.

    Attributes
    ----------
    radio_hz : float
        Radio frame rate [Hz].
    timeout_s : float
        Wall time without a motor packet before the firmware counts as lost [s].
    """

    radio_hz: float = 100.0
    timeout_s: float = 2.0

    def __call__(self, truth: Scenario, belief: Scenario) -> FirmwareInnerLoop:
        return FirmwareInnerLoop(truth, belief, radio_hz=self.radio_hz, timeout_s=self.timeout_s)

    def describe(self) -> dict[str, Any]:
        """Firmware, its source package, the patch and configuration hashes, the radio rate."""
        return {"firmware": "betaflight", "firmware_version": FIRMWARE_VERSION,
                "package": f"{PACKAGE}=={PACKAGE_VERSION}", "patch_key": build_key(),
                "config_key": FirmwareConfig.load().key(), "radio_hz": self.radio_hz}  # fmt: skip


__all__ = [
    "FIRMWARES",
    "BetaflightSitl",
    "FirmwareBuild",
    "FirmwareConfig",
    "FirmwareError",
    "FirmwareInnerLoop",
    "FirmwareUnavailable",
    "RateHandover",
    "RateLoopGain",
    "ensure_firmware",
]
