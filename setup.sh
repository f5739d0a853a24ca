#!/usr/bin/env bash
# Installs what building and testing Lagra needs beyond Rust itself: m4, which rug's bundled
# GMP build requires and a fresh Debian machine lacks, and z3 for the SMT proofs. Safe to run
# again; does nothing when both are there.
set -eu
# `bash setup.sh --mpi` installs only what building with `--features mpi` needs: Open MPI (its
# headers, mpicc and mpirun) and libclang, which rsmpi's bindgen reads the headers with. The
# README's two commands do not need it; CI asks for it to run tests/mpi.rs.
if [ "${1:-}" = "--mpi" ]; then
  if ! dpkg -s libopenmpi-dev openmpi-bin libclang-dev >/dev/null 2>&1; then
    echo "setup: installing Open MPI and libclang (for --features mpi)" >&2
    sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
    $sudo apt-get update -qq
    $sudo apt-get install -y -qq libopenmpi-dev openmpi-bin libclang-dev >/dev/null
  fi
  exit 0
fi
if ! command -v m4 >/dev/null 2>&1; then
  echo "setup: installing m4 (needed to build GMP for rug)" >&2
  sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq m4 >/dev/null
fi
# z3 proves the SMT models in checker/proofs (PyPI's z3-solver ships the z3 binary).
if ! command -v z3 >/dev/null 2>&1; then
  echo "setup: installing z3 (PyPI z3-solver) for the SMT proofs" >&2
  python3 -m pip install --quiet --disable-pip-version-check z3-solver >&2
  hash -r
fi
# The Python the tests drive Lagra from: the official MCP SDK (a client of `lagra mcp` no one
# here wrote), in a virtual environment of the project's own (.venv, not committed).
if [ ! -x .venv/bin/python ] || ! .venv/bin/python -c "import mcp" >/dev/null 2>&1; then
  echo "setup: preparing .venv with the MCP Python SDK (for tests/end_to_end/mcp.rs)" >&2
  python3 -m venv .venv
  .venv/bin/python -m pip install --quiet --disable-pip-version-check "mcp>=2" >&2
fi
# What the Python package's tests read with (ASE reads the trajectory formats back) and the
# example plots with; then the package itself, built from python/ (maturin, pyo3) into .venv.
# It builds in the workspace's target directory, so `cargo test` reuses what it compiled.
if ! .venv/bin/python -c "import pytest, ase, numpy, matplotlib" >/dev/null 2>&1; then
  echo "setup: installing pytest, ase, numpy and matplotlib into .venv" >&2
  .venv/bin/python -m pip install --quiet --disable-pip-version-check pytest ase numpy matplotlib >&2
fi
echo "setup: building and installing the Python package (pip install ./python) into .venv" >&2
.venv/bin/python -m pip install --quiet --disable-pip-version-check ./python >&2
# Chromium, headless, loads the viewer's pages in tests/end_to_end/view.rs.
if ! command -v chromium >/dev/null 2>&1; then
  echo "setup: installing chromium (headless, for the viewer's tests)" >&2
  sudo=""; [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq chromium >/dev/null
fi
# A RUSTFLAGS variable would replace .cargo/config.toml's `+fma`, which inari needs.
if [ -n "${RUSTFLAGS:-}" ]; then
  echo "setup: warning: RUSTFLAGS is set and overrides .cargo/config.toml; inari needs -C target-feature=+fma" >&2
fi
