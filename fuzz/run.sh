#!/usr/bin/env bash
# Fuzzes what reads input (coverage-guided, libFuzzer through cargo-fuzz) for a bounded time:
#   bash fuzz/run.sh readers [SECONDS]   certificates and state files, seeded from seeds/
#   bash fuzz/run.sh scenes [SECONDS]    the scene reader and compiler, from the shipped scenes
#                                        and the corpus checked in (corpus/scenes)
# (SECONDS defaults to 60). Builds on stable Rust without a sanitizer: the checker forbids unsafe
# code, so the fuzzer hunts panics, hangs and runaway allocations (-timeout, -rss_limit_mb), not
# memory bugs. Both targets build together, once. A crash leaves its input in artifacts/TARGET/
# and exits non-zero. A scenes run adds what it finds to corpus/scenes; minimise it (`cargo fuzz
# cmin scenes corpus/scenes`) before checking it in.
set -euo pipefail
cd "$(dirname "$0")"
target=${1:?usage: bash fuzz/run.sh readers|scenes [SECONDS]}
secs=${2:-60}
command -v cargo-fuzz >/dev/null 2>&1 || cargo install --locked cargo-fuzz
# cargo-fuzz sets RUSTFLAGS itself; inari needs +fma on top of them.
export RUSTFLAGS="-C target-feature=+fma"
cargo fuzz build --sanitizer none -O
run() { cargo fuzz run --sanitizer none -O "$target" "$@" -- -max_total_time="$secs" -print_final_stats=1 "${extra[@]}"; }
case "$target" in
  readers)
    mkdir -p corpus/readers
    cp seeds/* corpus/readers/
    extra=()
    run corpus/readers ;;
  scenes)
    # new inputs go to the first folder (checked in); the shipped scenes are read as seeds. The
    # fuzzer runs in 3 GiB of address space, which the compiler weighs a lattice against (so that
    # a scene of millions of bodies is refused as it would be on a small machine, not allocated).
    mkdir -p corpus/scenes
    ulimit -v 3145728
    extra=(-timeout=10 -rss_limit_mb=2048 -max_len=4096)
    run corpus/scenes ../scenes ../scenes/bench ../scenes/validation ;;
  *) echo "fuzz/run.sh: no target '$target' (readers, scenes)" >&2; exit 2 ;;
esac
