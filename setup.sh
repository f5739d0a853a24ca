#!/usr/bin/env bash
# Installs what building Lagra needs beyond Rust itself: m4, which rug's bundled GMP build
# requires and a fresh Debian machine lacks. Safe to run again; does nothing when m4 is there.
set -eu
if ! command -v m4 >/dev/null 2>&1; then
  echo "setup: installing m4 (needed to build GMP for rug)" >&2
  sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq m4 >/dev/null
fi
# A RUSTFLAGS variable would replace .cargo/config.toml's `+fma`, which inari needs.
if [ -n "${RUSTFLAGS:-}" ]; then
  echo "setup: warning: RUSTFLAGS is set and overrides .cargo/config.toml; inari needs -C target-feature=+fma" >&2
fi
