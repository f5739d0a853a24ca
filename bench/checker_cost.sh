#!/usr/bin/env bash
# The checker's cost in a run: lj_32k with energy and momentum certified every 100 steps
# (lj_32k_checked) against the same run without claims (lj_32k_shifted), on one CPU and on two,
# interleaved so that the machine's drift falls on both alike. Give one binary, or two (A/B:
# before and after a change; build each with `cargo build --release` and copy it away).
#
#     bash bench/checker_cost.sh ROUNDS STEPS BINARY [BINARY...]
#
# Prints each wall time, then per binary and CPU count the overhead, fastest against fastest,
# median against median, and paired (each checked run against the run without claims just
# before it, the median of those ratios: the least moved by the machine's drift), and as each
# checked run measures it itself (`checker_s`: the
# checker's CPU time judging, its cost on one CPU; `checker_wait_s`: the kernel's time waiting
# for it, its cost on two), the median share of the rest of the run.
set -euo pipefail
rounds=${1:-5}; steps=${2:-100}; shift 2
out=$(mktemp)
for cpus in 0 0,1; do
  for _ in $(seq "$rounds"); do
    for bin in "$@"; do
      for s in shifted checked; do
        t=$(taskset -c $cpus "$bin" run scenes/bench/lj_32k_$s.lagra --steps "$steps" --threads 1 --json |
          python3 -c "import json,sys; r=json.load(sys.stdin); print(r['wall_s'], r.get('checker_s', 0), r.get('checker_wait_s', 0))")
        echo "$cpus $bin $s $t" | tee -a "$out"
      done
    done
  done
done
python3 - "$out" <<'PY'
import collections, statistics, sys
d = collections.defaultdict(list)
inside = collections.defaultdict(list)
paired = collections.defaultdict(list)
for line in open(sys.argv[1]):
    cpus, b, s, t, judging, waiting = line.split()
    d[(cpus, b, s)].append(float(t))
    if s == "checked":
        paired[(cpus, b)].append(float(t) / d[(cpus, b, "shifted")][-1] - 1)
    if s == "checked":
        # within the run: on one CPU the checker's CPU time judging, on two the kernel's wait,
        # against the rest of the run
        cost = float(judging) if cpus == "0" else float(waiting)
        inside[(cpus, b)].append(100 * cost / (float(t) - cost))
for (cpus, b) in sorted({(c, b) for c, b, _ in d}):
    c, u = d[(cpus, b, "checked")], d[(cpus, b, "shifted")]
    print(f"{b} on CPUs {cpus}: overhead {100 * (min(c) / min(u) - 1):.1f}% fastest/fastest, "
          f"{100 * (statistics.median(c) / statistics.median(u) - 1):.1f}% median/median, "
          f"{100 * statistics.median(paired[(cpus, b)]):.1f}% paired median "
          f"(without claims {min(u):.3f} s, with {min(c):.3f} s); within the run "
          f"{'judging' if cpus == '0' else 'waiting'} {statistics.median(inside[(cpus, b)]):.1f}% median")
PY
rm -f "$out"
