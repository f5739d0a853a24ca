#!/usr/bin/env bash
# Peak resident memory of a run against its length (issue 40's goal: a run's memory does not
# grow with the number of steps). Runs SCENE for each step count given, with the claims checked
# as the scene says and, with --certificate, the certificate written (its marks go to disk as
# they are made); prints steps, peak RSS (GNU time's %M), wall time and the certificate's size.
#
#     bash bench/memory.sh BINARY SCENE [--certificate] STEPS [STEPS...]
#
# Exit status 1 of a run (a prediction that disagrees) is no error here.
set -euo pipefail
bin=$1 scene=$2
shift 2
cert=()
if [ "${1:-}" = "--certificate" ]; then
  cert=(--certificate "$(mktemp -d)/run.cert")
  shift
fi
printf '%12s %12s %10s %14s\n' steps peak_rss_kb wall_s certificate_b
for n in "$@"; do
  out=$( { /usr/bin/time -f '%M %e' "$bin" run "$scene" --steps "$n" --quiet "${cert[@]}" > /dev/null || true; } 2>&1 | tail -n 1)
  size=$([ ${#cert[@]} -gt 0 ] && stat -c %s "${cert[1]}" || echo -)
  printf '%12s %12s %10s %14s\n' "$n" ${out} "$size"
done
