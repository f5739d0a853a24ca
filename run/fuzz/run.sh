#!/usr/bin/env bash
# Fuzzes the scene reader and compiler (coverage-guided, libFuzzer through cargo-fuzz) for a
# bounded time: bash run/fuzz/run.sh [SECONDS] (default 60). Starts from the shipped scenes and
# the corpus checked in here (corpus/: inputs a campaign found that reach new code), and
# builds on stable Rust without a sanitizer (the fuzzer hunts panics, hangs and runaway
# allocations: -rss_limit_mb, -timeout). A crash leaves its input in run/fuzz/artifacts/ and
# exits non-zero. A run adds what it finds to corpus/; minimise it (`cargo fuzz cmin scenes
# corpus`) before checking it in.
set -euo pipefail
cd "$(dirname "$0")"
secs=${1:-60}
command -v cargo-fuzz >/dev/null 2>&1 || cargo install --locked cargo-fuzz
# new inputs go to the first folder (corpus/, checked in); the shipped scenes are read as seeds
mkdir -p corpus
# cargo-fuzz sets RUSTFLAGS itself; inari needs +fma on top of them. The build runs unbounded;
# the fuzzer in 3 GiB of address space, which the compiler weighs a lattice against (so that a
# scene of millions of bodies is refused as it would be on a small machine, not allocated).
RUSTFLAGS="-C target-feature=+fma" cargo fuzz build --sanitizer none -O scenes
ulimit -v 3145728
RUSTFLAGS="-C target-feature=+fma" cargo fuzz run --sanitizer none -O scenes corpus ../../scenes \
  ../../scenes/bench ../../scenes/validation -- \
  -max_total_time="$secs" -timeout=10 -rss_limit_mb=2048 -max_len=4096 -print_final_stats=1
