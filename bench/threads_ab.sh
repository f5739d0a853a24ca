#!/usr/bin/env bash
# Wall time of one scene on T threads for one binary or several (A/B: before and after a
# change; build each with `cargo build --release` and copy it away), in interleaved rounds so
# that the machine's drift falls on all alike. The 256,000-atom system of docs/bench is
# scenes/bench/lj_32k.lagra with `cells: [40, 40, 40]`:
#
#     sed 's/\[20, 20, 20\]/[40, 40, 40]/' scenes/bench/lj_32k.lagra > /tmp/lj_256k.lagra
#     bash bench/threads_ab.sh /tmp/lj_256k.lagra THREADS STEPS ROUNDS BINARY [BINARY...]
#
# Prints, per binary, the fastest and the mean of the rounds (`wall_s` of `lagra run --json`), and
# the median of its serial part (`serial_s`: the run's thread outside every spread pass) with
# its range and its median share of the wall.
set -euo pipefail
scene=$1 threads=$2 steps=$3 rounds=$4
shift 4
for _ in $(seq "$rounds"); do
  for b in "$@"; do
    # (a claim or prediction that fails still gives its time: exit status 1 is no error here)
    report=$("$b" run "$scene" --threads "$threads" --steps "$steps" --quiet --json || [ $? -eq 1 ])
    python3 -c "import json, sys; r = json.load(sys.stdin); print(sys.argv[1], r['wall_s'], r['serial_s'])" "$b" <<< "$report"
  done
done | python3 -c '
import collections, statistics as st, sys
runs = collections.defaultdict(list)
for line in sys.stdin:
    b, wall, serial = line.split()
    runs[b].append((float(wall), float(serial)))
for b, r in runs.items():
    walls, serials = [w for w, _ in r], [s for _, s in r]
    print(f"{b} fastest {min(walls):.3f} s, mean {st.mean(walls):.3f} s; serial {st.median(serials):.4f} s "
          f"({min(serials):.4f}-{max(serials):.4f}), {100 * st.median(s / w for w, s in r):.2f}% of the wall")
'
