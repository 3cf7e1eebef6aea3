"""Load a built-in scenario, override it, and ask whether tethered landing works there."""

import math

from tetherland.analysis import analyze
from tetherland.config import load_scenario, with_overrides

scenario = load_scenario("slope50", ["tether.length=1.2"])  # built-in name or a TOML path
steeper = with_overrides(scenario, ["surface.slope_deg=75"])  # a validated copy
for sc in (scenario, steeper):
    a = analyze(sc)
    limit = math.degrees(a.tethered.max_slope_rad)
    print(f"{sc.surface.slope_deg:.0f} deg: tethered feasible={a.tethered.feasible}, "
          f"contact-free feasible={a.free_flight.feasible}, tethered limit {limit:.1f} deg")
    if not a.tethered.feasible:
        print("  binding:", a.tethered.binding.value)
assert analyze(scenario).tethered.feasible and not analyze(steeper).tethered.feasible
