#!/usr/bin/env bash
# Instructions per hot-path call (valgrind callgrind; load-independent), see hotpaths.py.
# Usage: benchmarks/bench_callgrind.sh [python] [workload...]
# Not part of `make bench`: it takes several minutes under valgrind.
set -euo pipefail
PY=${1:-.venv/bin/python}
shift || true
HERE=$(dirname "$0")

WORKLOADS=${*:-"free_flight hierarchical dfl estimator aero believed compensation stack stack_layered plant bar_free bar_seated mission"}
tmp=$(mktemp -d)
for w in $WORKLOADS; do
    if [ "$w" = mission ]; then n=1; else n=2000; fi
    valgrind --tool=callgrind --toggle-collect=math_fsum --callgrind-out-file=/dev/null \
        "$PY" "$HERE/hotpaths.py" "$w" "$n" > "$tmp/out" 2> "$tmp/err"
    total=$(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' "$tmp/err")
    ticks=$(sed -n 's/^ticks=\([0-9]*\)/\1/p' "$tmp/out")
    if [ "$w" = mission ]; then
        echo "mission (runner loop): $(( total / ticks )) instructions per control tick"
    else
        echo "$w: $(( total / n )) instructions per call"
    fi
done
rm -rf "$tmp"
