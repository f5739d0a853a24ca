#!/usr/bin/env bash
# A soak run: one long run of SCENE for STEPS with its certificate written, its resident memory
# (VmRSS) sampled every SECONDS while it runs. Prints the samples' count, the first, the
# smallest, the largest and the last, then the run's last lines; not run in CI.
#
#     bash bench/soak.sh BINARY SCENE STEPS [SECONDS]
set -euo pipefail
bin=$1 scene=$2 steps=$3 every=${4:-1}
dir=$(mktemp -d)
"$bin" run "$scene" --steps "$steps" --quiet --certificate "$dir/run.cert" > "$dir/report.txt" &
pid=$!
samples=()
while kill -0 "$pid" 2> /dev/null; do
  rss=$(awk '/^VmRSS/ { print $2 }' "/proc/$pid/status" 2> /dev/null || true)
  [ -n "$rss" ] && samples+=("$rss")
  sleep "$every"
done
wait "$pid" || true
printf '%s\n' "${samples[@]}" | awk -v steps="$steps" '
  NR == 1 { first = $1; lo = $1; hi = $1 }
  { if ($1 < lo) lo = $1; if ($1 > hi) hi = $1; last = $1 }
  END { printf "%s steps: %d samples of VmRSS (KiB): first %d, min %d, max %d, last %d\n", steps, NR, first, lo, hi, last }'
echo "certificate: $(stat -c %s "$dir/run.cert") bytes"
tail -n 3 "$dir/report.txt"
rm -rf "$dir"
