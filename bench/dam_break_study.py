#!/usr/bin/env python3
"""The dam break's convergence study (docs/bench/fluids.md): the surge front against Martin &
Moyce (1952) at three particle spacings, and the run time per particle-step, from one command:

    python3 bench/dam_break_study.py [--kernel cubic_spline] [ACROSS ...]
                                            # default 8 12 16; needs target/release/lagra
    python3 bench/dam_break_study.py --solvers      # run time against error across solvers

Each resolution is scenes/generate.py's dam break with ACROSS particles across the column
(2·ACROSS up, 8 layers periodic in z), smoothed by the kernel (default wendland_c2), run
without its claims (the kernel's time alone).

`--solvers` runs the shipped scene, its claims checked inline, with velocity Verlet and Yoshida's
fourth order at several time steps over the same 0.48 s: the wall time, the energy balance the
checker certifies, and the front's largest departure from the finest run's (velocity Verlet at
1.25e-4 s), at Martin & Moyce's times."""

import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LAGRA = ROOT / "target" / "release" / "lagra"


def run(across, kernel):
    with tempfile.TemporaryDirectory() as d:
        scene = Path(d) / f"dam_break_{across}.lagra"
        generate = [sys.executable, ROOT / "scenes" / "generate.py", "--dam-break", str(across), scene, kernel]
        subprocess.run(generate, check=True)
        out = subprocess.run([LAGRA, "run", scene, "--json", "--quiet"], capture_output=True, text=True)
        report = json.loads(out.stdout)
    p = report["predictions"][0]
    points = [part.split(": z/a ") for part in p["detail"].split(": ", 1)[1].split(", ")]
    front = [(float(t.split()[1]), float(z.split()[0]), float(z.split("M&M ")[1].rstrip(")"))) for t, z in points]
    bodies = 2 * across * across * 8
    return bodies, report, front, p["measured"]


def fronts(report):
    p = report["predictions"][0]
    points = [part.split(": z/a ") for part in p["detail"].split(": ", 1)[1].split(", ")]
    return [float(z.split()[0]) for _, z in points]


SOLVERS = [("velocity_verlet", dt) for dt in (1.25e-4, 2.5e-4, 5e-4, 1e-3, 2e-3)] + [
    ("yoshida4", dt) for dt in (1e-3, 2e-3, 4e-3)
]


def solvers():
    shipped = (ROOT / "scenes" / "dam_break.lagra").read_text()
    rows = []
    with tempfile.TemporaryDirectory() as d:
        for integrator, dt in SOLVERS:
            scene = Path(d) / f"dam_break_{integrator}.lagra"
            scene.write_text(shipped.replace("solver { dt", f'solver {{ integrator: "{integrator}", dt'))
            steps = round(0.48 / dt)
            args = [LAGRA, "run", scene, "--json", "--quiet", "--dt", str(dt), "--steps", str(steps)]
            report = json.loads(subprocess.run(args, capture_output=True, text=True).stdout)
            energy = next(c for c in report["claims"] if c["claim"] == "energy_conservation")
            rows.append((integrator, dt, steps, report, energy))
    reference = fronts(rows[0][3])
    print("| integrator | dt s | steps | wall s | of it the checker | energy balance (tol 1e-3) | front: largest departure from the finest run |")
    print("|---|---|---|---|---|---|---|")
    for integrator, dt, steps, report, energy in rows:
        halted = report.get("halted")
        if halted:
            departure = f"halted: {halted}"
        else:
            departure = f"{max(abs(z / r - 1) for z, r in zip(fronts(report), reference)):.1e}"
        bound = energy.get("bound")
        balance = f"{energy['status']} {bound:.1e}" if bound is not None else energy["status"]
        print(f"| {integrator} | {dt:g} | {steps} | {report['wall_s']:.1f} | {report['checker_s']:.1f} | {balance} | {departure} |")


def main():
    args = sys.argv[1:]
    if args == ["--solvers"]:
        solvers()
        return
    kernel = "wendland_c2"
    if args[:1] == ["--kernel"]:
        kernel, args = args[1], args[2:]
    sizes = [int(a) for a in args] or [8, 12, 16]
    rows = [(a, *run(a, kernel)) for a in sizes]
    print(f"kernel: {kernel}")
    print()
    print("| across | particles | steps | wall s | µs per particle-step | worst z/a ratio to M&M |")
    print("|---|---|---|---|---|---|")
    for a, bodies, report, _, worst in rows:
        steps = report["steps"]
        wall = report["wall_s"]
        print(f"| {a} | {bodies} | {steps} | {wall:.1f} | {wall / steps / bodies * 1e6:.2f} | {worst:.3f} |")
    print()
    print("| T = t√(2g/a) | M&M z/a | " + " | ".join(f"{a} across" for a, *_ in rows) + " |")
    print("|---|---|" + "---|" * len(rows))
    for k, (t, _, zm) in enumerate(rows[0][3]):
        cells = " | ".join(f"{r[3][k][1]:.3f} ({100 * (r[3][k][1] / zm - 1):+.1f}%)" for r in rows)
        print(f"| {t} | {zm} | {cells} |")


if __name__ == "__main__":
    main()
