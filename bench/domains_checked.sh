#!/usr/bin/env bash
# What certifying energy and momentum costs a run in domains: lj_32k_checked (shifted LJ, energy
# and momentum every EVERY steps) at CELLS³ × 4 atoms, 100 steps on `mpirun -np 2` (a thread a
# rank), against the same scene without claims, interleaved rounds, the fastest of each kept.
# Needs a lagra built with --features mpi (after `bash setup.sh --mpi`).
#
#     bash bench/domains_checked.sh CELLS EVERY ROUNDS   # 20 20 3: 32,000 atoms; 40 20 3: 256,000
#
# Prints seconds (rank 0's `wall_s`), the checker's share over the unchecked run, and how the
# checkpoints were judged (`--explain`: from the ranks' parts, or refused).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cells=$1 every=$2 rounds=$3
lagra=$root/target/release/lagra
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
sed -e "s/cells: \[20, 20, 20\]/cells: [$cells, $cells, $cells]/" -e "s/every: 100/every: $every/g" \
  "$root/scenes/bench/lj_32k_checked.lagra" > "$work/checked.lagra"
sed '/@expect/d' "$work/checked.lagra" > "$work/unchecked.lagra"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
for _ in $(seq "$rounds"); do
  for s in unchecked checked; do
    mpirun -np 2 --bind-to core "$lagra" run "$work/$s.lagra" --threads 1 --quiet --json --explain |
      python3 -c "
import json, sys
r = json.load(sys.stdin)
assert r['passed'], 'a claim did not pass'
print('$s', r['wall_s'], (r.get('checker_parts') or '-').replace(' ', '_'))"
  done
done | awk '{ if (!($1 in m) || $2 < m[$1]) { m[$1] = $2; p[$1] = $3 } }
  END { printf "unchecked %.3f s\nchecked   %.3f s (the checker +%.1f%%)\n%s\n", m["unchecked"], m["checked"],
        100 * (m["checked"] / m["unchecked"] - 1), p["checked"] }' | tr '_' ' '
