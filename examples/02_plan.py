"""Plan the tethered landing (OCP (6.21)) and look at the rotor thrusts it needs."""

import sys
from pathlib import Path

from tetherland.config import load_scenario
from tetherland.planning import Maneuver, Planner

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/examples")
planner = Planner()  # keeps compiled solvers: later plans are fast
result = planner.plan(load_scenario("slope50"), Maneuver.LANDING)
print(result.status.name, result.message or "")
trajectory = result.require()  # raises with the reason when there is no verified plan
samples = trajectory.sample([0.0, trajectory.duration])
f_L = samples.tension
print(f"{trajectory.duration:.2f} s, tension {f_L[0]:.2f} -> {f_L[1]:.2f} N")
path = trajectory.save_csv(out / "landing_trajectory.csv")
print("written", path)
assert result.success and min(f_L) > 0
