#!/usr/bin/env bash
# Instructions per hot-path call (valgrind callgrind; load-independent), see hotpaths.py.
# Usage: benchmarks/bench_callgrind.sh [python] [workload...]
# Not part of `make bench` (it takes minutes under valgrind).
set -euo pipefail
PY=${1:-.venv/bin/python}
shift || true
HERE=$(dirname "$0")
WORKLOADS=${*:-"free_flight hierarchical dfl estimator mission"}
count() {  # instructions of one run
    valgrind --tool=callgrind --callgrind-out-file=/dev/null "$PY" "$HERE/hotpaths.py" "$1" "$2" \
        2>&1 | sed -n 's/.*Collected : \([0-9]*\).*/\1/p'
}
for w in $WORKLOADS; do
    if [ "$w" = mission ]; then n1=4; n2=8; unit="simulated s"; else n1=2000; n2=4000; unit=call; fi
    a=$(count "$w" "$n1")
    b=$(count "$w" "$n2")
    echo "$w: $(( (b - a) / (n2 - n1) )) instructions per $unit"
done
