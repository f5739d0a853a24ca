#!/usr/bin/env bash
# The 10,000-block stack (issue 42): a thousand ten-block towers under AVBD, generated into a
# temporary folder (1.5 MB of scene, not kept in the repository) and run to its end with its
# `resting` and `no_penetration` claims. Prints the run's report.
#
#   bash bench/stack_10000.sh [THREADS]      (default 1; the release build must exist)
set -euo pipefail
cd "$(dirname "$0")/.."
threads="${1:-1}"
dir="$(mktemp -d)"
trap 'rm -rf "$dir"' EXIT
python3 scenes/generate.py --stack-10000 "$dir/stack_10000.lagra"
./target/release/lagra run "$dir/stack_10000.lagra" --quiet --threads "$threads"
