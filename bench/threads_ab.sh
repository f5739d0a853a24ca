#!/usr/bin/env bash
# Wall time of one scene on T threads for one binary or several (A/B: before and after a
# change; build each with `cargo build --release` and copy it away), in interleaved rounds so
# that the machine's drift falls on all alike. The 256,000-atom system of docs/bench is
# scenes/bench/lj_32k.lagra with `cells: [40, 40, 40]`:
#
#     sed 's/\[20, 20, 20\]/[40, 40, 40]/' scenes/bench/lj_32k.lagra > /tmp/lj_256k.lagra
#     bash bench/threads_ab.sh /tmp/lj_256k.lagra THREADS STEPS ROUNDS BINARY [BINARY...]
#
# Prints, per binary, the fastest and the mean of the rounds (`wall_s` of `lagra run --json`).
set -euo pipefail
scene=$1 threads=$2 steps=$3 rounds=$4
shift 4
for _ in $(seq "$rounds"); do
  for b in "$@"; do
    # (a claim or prediction that fails still gives its time: exit status 1 is no error here)
    report=$("$b" run "$scene" --threads "$threads" --steps "$steps" --quiet --json || [ $? -eq 1 ])
    w=$(python3 -c "import json, sys; print(json.load(sys.stdin)['wall_s'])" <<< "$report")
    echo "$b $w"
  done
done | awk '{ if (!($1 in m) || $2 < m[$1]) m[$1] = $2; s[$1] += $2; n[$1]++ }
  END { for (b in m) printf "%s fastest %.3f s, mean %.3f s\n", b, m[b], s[b] / n[b] }'
