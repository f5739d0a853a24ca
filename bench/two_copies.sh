#!/usr/bin/env bash
# What two threads can reach on this machine, beside what they do reach. Each round runs one
# scene three ways: one thread alone; two one-thread copies at once (independent work, no
# sharing: the most two CPUs give this job here, short of 2× where the vCPUs share a core, its
# caches or its clock); and two threads. A virtual machine's neighbours move all three, so the
# ways are interleaved within each round and the medians compared:
#
#     bash bench/two_copies.sh scenes/bench/stack_1000.lagra 200 8 target/release/lagra
#
# Prints each round, then the medians, two threads against one, and two copies against one
# (the ceiling: 2 × alone / each copy).
set -euo pipefail
scene=$1 steps=$2 rounds=$3 bin=$4
wall() {
  local report
  # (a claim that fails or is left undecided still gives its time: exit status 1 is no error)
  report=$("$bin" run "$scene" --threads "$1" --steps "$steps" --quiet --json) || [ $? -eq 1 ] || {
    echo "two_copies.sh: $bin run $scene failed" >&2
    return 2
  }
  python3 -c "import json, sys; print(json.load(sys.stdin)['wall_s'])" <<< "$report"
}
copy=$(mktemp)
trap 'rm -f "$copy"' EXIT
rows=""
for _ in $(seq "$rounds"); do
  alone=$(wall 1)
  wall 1 > "$copy" &
  other=$!
  mine=$(wall 1)
  wait "$other"
  two=$(wall 2)
  rows+="alone $alone copies $mine $(cat "$copy") two $two"$'\n'
done
python3 -c '
import statistics as st, sys
rows = [l.split() for l in sys.stdin if l.strip()]
for r in rows:
    print(" ".join(r))
alone = st.median(float(r[1]) for r in rows)
copy = st.median((float(r[3]) + float(r[4])) / 2 for r in rows)
two = st.median(float(r[6]) for r in rows)
print(f"medians: alone {alone:.3f} s, each of two copies {copy:.3f} s, two threads {two:.3f} s")
print(f"two threads against one {alone / two:.2f}x; two copies against one (the ceiling) {2 * alone / copy:.2f}x")
' <<< "$rows"
