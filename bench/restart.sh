#!/usr/bin/env bash
# What restart files cost (issue 40): a run of STEPS steps of SCENE plain, with a restart file
# written every EVERY steps (--restart-every), and resumed from the one written at STEPS for
# another STEPS steps against a fresh run of 2·STEPS; whole-process wall times (GNU time), each
# the least of REPEATS runs, and the restart file's size. The resumed run must end where the
# unbroken one ends, to the bit: the script compares their restart files and fails if not.
#
#     bash bench/restart.sh BINARY SCENE STEPS EVERY [REPEATS]
set -euo pipefail
bin=$1 scene=$2 steps=$3 every=$4 repeats=${5:-3}
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
least() { # the least wall time of $repeats runs of "$@"
  local best=
  for _ in $(seq "$repeats"); do
    t=$( { /usr/bin/time -f '%e' "$@" --quiet > /dev/null || true; } 2>&1 | tail -n 1)
    best=$(python3 -c "print(min(x for x in [$t, ${best:-$t}]))")
  done
  echo "$best"
}
plain=$(least "$bin" run "$scene" --steps "$steps")
every_run=$(least "$bin" run "$scene" --steps "$steps" --restart "$dir/r" --restart-every "$every")
size=$(stat -c %s "$dir/r")
twice=$((2 * steps))
"$bin" run "$scene" --steps "$twice" --until "$steps" --restart "$dir/half" --quiet > /dev/null || true
whole=$(least "$bin" run "$scene" --steps "$twice" --restart "$dir/whole")
resumed=$(least "$bin" run "$scene" --steps "$twice" --resume "$dir/half" --restart "$dir/end")
cmp -s "$dir/whole" "$dir/end" || { echo "the resumed run did not end where the unbroken one did" >&2; exit 1; }
writes=$((steps / every))
echo "scene $scene, $steps steps; a restart every $every steps ($writes written), $size bytes each"
echo "plain run                 ${plain} s"
echo "with --restart-every      ${every_run} s  ($(python3 -c "print(f'{($every_run - $plain) / $writes * 1e3:.1f}')") ms a restart)"
echo "2·$steps steps unbroken   ${whole} s"
echo "$steps resumed from $steps  ${resumed} s  (the same last state, to the bit)"
