"""Roll-rate step responses of tetherland's own inner loop against Betaflight's (docs/firmware.md).

Run: .venv/bin/python docs/scripts/firmware_step_response.py [--png docs/firmware_step_response.png]

A 1 rad/s roll-rate step from hover on the default vehicle (slope50's), held 0.3 s
(:mod:`tetherland.firmware.step_response`), flown at five start times 2 ms apart: a radio
frame leaves every 10 ms, so the five starts cover every phase of the setpoint against the
frame. Cases: tetherland's own inner loop; Betaflight with the repository's configuration;
the same with the RC smoothing filter on (Betaflight's default); without the gyro low-pass;
with a 500 Hz radio link. Prints a Markdown table (times in ms, mean and range over the
phases) and draws the responses.
"""

from __future__ import annotations

import argparse
import statistics
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from tetherland.config import load_scenario
from tetherland.firmware.configure import FirmwareConfig
from tetherland.firmware.inner_loop import FirmwareInnerLoop
from tetherland.firmware.step_response import RateStep, StepResponse, rate_step_response

STARTS = (1.000, 1.002, 1.004, 1.006, 1.008)
"""Step times [s]: every phase of a 500 Hz setpoint against a 100 Hz radio frame."""


def cases() -> dict[str, tuple[dict, float] | None]:
    """Name -> (configuration changes, radio rate [Hz]), None for tetherland's own loop."""
    return {
        "tetherland": None,
        "Betaflight": ({}, 100.0),
        "Betaflight, RC smoothing on": ({"rc_smoothing": "ON"}, 100.0),
        "Betaflight, no gyro low-pass": ({"gyro_lpf1_static_hz": 0}, 100.0),
        "Betaflight, 500 Hz radio": ({}, 500.0),
    }


def fly(name: str, case: tuple[dict, float] | None) -> list[StepResponse]:
    scenario = load_scenario("slope50")
    out = []
    for start in STARTS:
        inner = None
        if case is not None:
            changes, radio = case
            config = FirmwareConfig.load().with_settings(**changes)
            inner = FirmwareInnerLoop(scenario, scenario, config=config, radio_hz=radio)
        out.append(rate_step_response(scenario, RateStep(start=start), inner_loop=inner))
        print(f"  {name}: step at {start:.3f} s", flush=True)
    return out


def row(name: str, responses: list[StepResponse], reference: float | None) -> str:
    def stat(values: list[float], scale: float = 1e3) -> str:
        v = [scale * x for x in values]
        return f"{statistics.mean(v):.1f} ({min(v):.0f}-{max(v):.0f})"

    t10 = [r.time_to(0.1) for r in responses]
    t50 = [r.time_to(0.5) for r in responses]
    t90 = [r.time_to(0.9) for r in responses]
    over = [r.overshoot for r in responses]
    lag = "" if reference is None else f"{1e3 * (statistics.mean(t50) - reference):+.1f}"
    return (f"| {name} | {stat(t10)} | {stat(t50)} | {stat(t90)} | "
            f"{100 * statistics.mean(over):.1f} | {lag} |")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--png", type=Path, default=Path("docs/firmware_step_response.png"))
    args = parser.parse_args()
    results = {name: fly(name, case) for name, case in cases().items()}
    own = statistics.mean(r.time_to(0.5) for r in results["tetherland"])
    print("| inner loop | 10 % [ms] | 50 % [ms] | 90 % [ms] | overshoot [%] | "
          "later than tetherland at 50 % [ms] |")
    print("|---|---|---|---|---|---|")
    for name, responses in results.items():
        print(row(name, responses, None if name == "tetherland" else own))

    fig, ax = plt.subplots(figsize=(7.0, 4.0))
    styles = dict(zip(results, ("k-", "C0-", "C1--", "C2:", "C3-."), strict=True))
    for name, responses in results.items():
        t = 1e3 * responses[0].t
        y = np.array([r.y for r in responses])
        ax.plot(t, y.mean(axis=0), styles[name], lw=1.4, label=name)
        if name == "Betaflight":
            ax.fill_between(t, y.min(axis=0), y.max(axis=0), color="C0", alpha=0.2, lw=0,
                            label="Betaflight, range over radio phase")  # fmt: skip
    ax.axhline(1.0, color="0.6", lw=0.8)
    ax.set_xlim(0, 200)
    ax.set_xlabel("time since the step [ms]")
    ax.set_ylabel("roll rate / step [-]")
    ax.set_title("1 rad/s roll-rate step from hover, default vehicle (mean of 5 radio phases)")
    ax.legend(fontsize=8, loc="lower right")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(args.png, dpi=130)
    print(f"figure: {args.png}")


if __name__ == "__main__":
    main()
