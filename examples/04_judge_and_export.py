"""Run the contact-free baseline, save the run, judge it again from its files, export MCAP."""

import sys
from pathlib import Path

from tetherland.config import load_scenario
from tetherland.runs import jsonable_summary, rejudge, run_mission, save_run

out = Path(sys.argv[1] if len(sys.argv) > 1 else "out/examples/perch20")
out.mkdir(parents=True, exist_ok=True)
scenario = load_scenario("slope50", ["surface.slope_deg=20"])
result = run_mission(scenario, method="free-flight", seed=0)  # any registered method
files = save_run(result, out)  # log.npz, run.json, summary.json, the plan as CSV
again = rejudge(out)  # the one judge, from log.npz and run.json alone
print(result.method, again.outcome.value, again.reason)
assert jsonable_summary(again) == jsonable_summary(result.verdict)

try:
    from tetherland.viz import load_run
    from tetherland.viz.mcap import write_mcap
except ImportError as err:  # the 'viz' extra is not installed
    print(err)
else:
    print("MCAP:", write_mcap(load_run(out), out / "run.mcap").path)
