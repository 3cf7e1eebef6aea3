#!/usr/bin/env bash
# Instructions per hot-path call (valgrind callgrind; load-independent), see hotpaths.py.
# Usage: benchmarks/bench_callgrind.sh [python] [workload...]
# Not part of `make bench`: it takes 10-20 minutes under valgrind.
set -euo pipefail
PY=${1:-.venv/bin/python}
shift || true
HERE=$(dirname "$0")
WORKLOADS=${*:-"free_flight hierarchical dfl estimator mission"}
run() {  # "<instructions> <ticks>" of one run
    valgrind --tool=callgrind --callgrind-out-file=/dev/null "$PY" "$HERE/hotpaths.py" "$1" "$2" \
        > /tmp/hotpaths.$$.out 2> /tmp/hotpaths.$$.err
    echo "$(sed -n 's/.*Collected : \([0-9]*\).*/\1/p' /tmp/hotpaths.$$.err)" \
         "$(sed -n 's/^ticks=\([0-9]*\)/\1/p' /tmp/hotpaths.$$.out)"
}
for w in $WORKLOADS; do
    if [ "$w" = mission ]; then
        read -r a ta <<< "$(run mission 4)"
        read -r b tb <<< "$(run mission 180)"  # the whole mission (it ends at about 78 s)
        echo "mission: $(( (b - a) / (tb - ta) )) instructions per control tick"
    else
        read -r a _ <<< "$(run "$w" 2000)"
        read -r b _ <<< "$(run "$w" 4000)"
        echo "$w: $(( (b - a) / 2000 )) instructions per call"
    fi
done
rm -f /tmp/hotpaths.$$.out /tmp/hotpaths.$$.err
