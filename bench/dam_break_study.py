#!/usr/bin/env python3
"""The dam break's convergence study (docs/bench/fluids.md): the surge front against Martin &
Moyce (1952) at three particle spacings, and the run time per particle-step, from one command:

    python3 bench/dam_break_study.py [--kernel cubic_spline] [ACROSS ...]
                                            # default 8 12 16; needs target/release/lagra

Each resolution is scenes/generate.py's dam break with ACROSS particles across the column
(2·ACROSS up, 8 layers periodic in z), smoothed by the kernel (default wendland_c2), run
without its claims (the kernel's time alone)."""

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


def main():
    args = sys.argv[1:]
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
