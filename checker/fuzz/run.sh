#!/usr/bin/env bash
# Fuzzes the certificate and state-file readers (coverage-guided, libFuzzer through cargo-fuzz)
# for a bounded time: bash checker/fuzz/run.sh [SECONDS] (default 60). Builds on stable Rust
# (no sanitizer: the checker forbids unsafe code, so the fuzzer hunts panics, not memory bugs).
# A crash leaves its input in checker/fuzz/artifacts/ and exits non-zero.
set -euo pipefail
cd "$(dirname "$0")"
secs=${1:-60}
command -v cargo-fuzz >/dev/null 2>&1 || cargo install --locked cargo-fuzz
mkdir -p corpus/readers
cp seeds/* corpus/readers/
# cargo-fuzz sets RUSTFLAGS itself; inari needs +fma on top of them.
RUSTFLAGS="-C target-feature=+fma" cargo fuzz run --sanitizer none -O readers corpus/readers -- \
  -max_total_time="$secs" -print_final_stats=1
