#!/usr/bin/env python3
"""Warns when pip's build of the Python package would compile the engine a second time.

maturin builds python/ alone, so cargo gives its dependencies the features that package asks
for; `cargo test --workspace` gives them those of the whole workspace (symbolica's, the
dev-dependencies'). Where the two differ, a crate and everything above it (GMP, the engine) is
compiled twice: about 10 minutes of CI. python/Cargo.toml therefore asks for the workspace's
features; this compares the two with `cargo tree` (no build) and names what drifted."""

import subprocess
import sys

# used by the Python package alone (or, for syn, by a test's parser and by the proc macros, whose
# features python/Cargo.toml's build-dependency matches): a difference there costs nothing
ALONE = ("pyo3", "pyo3-ffi", "pyo3-build-config", "pyo3-macros", "pyo3-macros-backend", "numpy", "ndarray", "syn")


def features(args):
    out = subprocess.run(
        ["cargo", "tree", "-q", "--prefix", "none", "-f", "{p}|{f}", "-e", "normal,build"] + args,
        capture_output=True, text=True, check=True,
    ).stdout
    found = {}
    for line in out.splitlines():
        if "|" not in line:
            continue
        package, feats = line.replace(" (*)", "").split("|", 1)
        found.setdefault(" ".join(package.split()[:2]), set()).update(f for f in feats.split(",") if f)
    return found


def main():
    workspace = features(["--workspace", "-e", "dev"])
    python = features(["-p", "lagra-python", "--features", "pyo3/extension-module"])
    drift = [
        (p, sorted(workspace[p] - python[p]), sorted(python[p] - workspace[p]))
        for p in sorted(python)
        if p in workspace and p.split()[0] not in ALONE and workspace[p] != python[p]
    ]
    for p, more, fewer in drift:
        alone = f" (python/ alone: {fewer})" if fewer else ""
        print(f"ci: warning: {p}: the workspace's test build gives it {more}{alone}; ask for them in "
              "python/Cargo.toml, or pip's build compiles it, and all above it, a second time", file=sys.stderr)
    if not drift:
        print(f"ci: python/'s build and the workspace's share their {len(python)} dependencies' features")


if __name__ == "__main__":
    main()
