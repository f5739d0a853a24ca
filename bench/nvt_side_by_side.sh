#!/usr/bin/env bash
# The thermostatted LJ liquid in Lagra and in LAMMPS, side by side: the NIST state point
# T* = 0.85, rho* = 0.86 (500 atoms, LJ truncated at 3 sigma with tail corrections, a
# Nose-Hoover chain of three, dt 0.005, 10,000 steps to equilibrate and 40,000 sampled every
# 10), each on one CPU, run one after the other. Prints <U>/N and <P> with block standard
# errors (ten blocks, as Lagra's report) beside NIST's, and the time per atom-step of the
# whole run. Needs LAMMPS (`bash ../shared/peers/lammps.sh install`, Debian `lammps`).
set -euo pipefail
cd "$(dirname "$0")/.."
work=${LAMMPS_WORK:-/tmp/lagra-lammps}
mkdir -p "$work"
command -v lmp >/dev/null || { echo "LAMMPS (lmp) is not installed: bash ../shared/peers/lammps.sh install" >&2; exit 2; }
cargo build --release -q
cp bench/nvt.lmp "$work"/
(cd "$work" && taskset -c 0 lmp -in nvt.lmp -var nsteps 40000 -log nvt.log -screen none)
taskset -c 0 target/release/lagra run scenes/validation/lj_t085_rho0860.lagra --json > "$work/nvt.json"
python3 - "$work/nvt.log" "$work/nvt.json" <<'PY'
import json, sys, statistics as st
log, lagra = sys.argv[1], json.load(open(sys.argv[2]))
rows, loops, on = [], [], False
for line in open(log):
    w = line.split()
    if w[:4] == ["Step", "Temp", "PotEng", "Press"]:
        on = True
        continue
    if line.startswith("Loop time of"):
        loops.append((float(w[3]), int(w[8]), int(w[11])))
        on = False
        continue
    if on and len(w) == 4 and w[0].isdigit():
        rows.append([float(x) for x in w[1:]])
def blocks(xs, n=10):
    size = len(xs) // n
    means = [sum(xs[i * size:(i + 1) * size]) / size for i in range(n)]
    return sum(xs) / len(xs), st.stdev(means) / n ** 0.5
u, p = blocks([r[1] for r in rows]), blocks([r[2] for r in rows])
seconds = sum(l[0] for l in loops); steps = sum(l[1] for l in loops); atoms = loops[0][2]
o = lagra["observables"]
lu, lp = o["potential_energy_per_body"], o["pressure"]
print("| engine | <U>/N | <P> | samples | ns/atom-step (whole run) |")
print("|---|---|---|---|---|")
print(f"| Lagra (NHC chain of 3) | {lu['mean']:.4f} ± {lu['stderr']:.4f} | {lp['mean']:.4f} ± {lp['stderr']:.4f} | {lu['samples']} | {lagra['ns_per_atom_step']:.0f} |")
print(f"| LAMMPS fix nvt (tchain 3) | {u[0]:.4f} ± {u[1]:.4f} | {p[0]:.4f} ± {p[1]:.4f} | {len(rows)} | {seconds / steps / atoms * 1e9:.0f} |")
print("| NIST MC NVT | -6.0305 ± 0.00023 | 1.2660 | | |")
PY
