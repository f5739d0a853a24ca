#!/usr/bin/env bash
# What a run costs outside its own loop: the set-up before step 0 (compile, lattice, model
# checks, graph, first memory) and the exit after the last, as the process's wall time less
# the run's `wall_s`, one step on one thread (on `THREADS` threads where that is set: a large
# lattice is laid out on the run's threads). Give one binary, or several (A/B: before and after
# a change), interleaved round by round so the machine's drift falls on all alike:
#
#     sed 's/\[20, 20, 20\]/[40, 40, 40]/' scenes/bench/lj_32k.lagra > /tmp/lj_256k.lagra
#     THREADS=2 bash bench/setup_cost.sh /tmp/lj_256k.lagra ROUNDS BINARY [BINARY...]
#
# Prints each binary's times in seconds, sorted, and their median.
set -euo pipefail
scene=$1 rounds=$2
shift 2
report=$(mktemp)
trap 'rm -f "$report"' EXIT
for _ in $(seq "$rounds"); do
  for b in "$@"; do
    start=$(date +%s%N)
    "$b" run "$scene" --threads "${THREADS:-1}" --steps 1 --quiet --json > "$report" || [ $? -eq 1 ]
    end=$(date +%s%N)
    python3 -c "import json, sys; print(sys.argv[1], ($end - $start) / 1e9 - json.load(open(sys.argv[2]))['wall_s'])" "$b" "$report"
  done
done | python3 -c '
import collections, statistics, sys
times = collections.defaultdict(list)
for line in sys.stdin:
    b, t = line.split()
    times[b].append(float(t))
for b, t in times.items():
    print(b, " ".join(f"{x:.4f}" for x in sorted(t)), f"median {statistics.median(t):.4f} s")
'
