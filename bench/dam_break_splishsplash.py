#!/usr/bin/env python3
"""The dam break beside a peer: SPlisHSPlasH (PyPI `pysplishsplash`) on Martin & Moyce's column,
2-D, 12 particles across and 24 up as Lagra's shipped scene, with its own boundary (volume
maps, Bender et al. 2019) and two of its pressure solvers: WCSPH with Lagra's Tait constants and
time step, and DFSPH (its default, adaptive time step). One thread (OMP_NUM_THREADS=1).

    python3 -m venv /tmp/sphv && /tmp/sphv/bin/pip install pysplishsplash
    LD_PRELOAD=/lib/x86_64-linux-gnu/libGLdispatch.so.0 /tmp/sphv/bin/python bench/dam_break_splishsplash.py [ACROSS ...]

(ACROSS: particles across the column, default 12; with several, a line each per solver at each
resolution instead of the fronts' table)
(the wheel bundles a libGLdispatch that crashes against a system libGLX: preloading the
system's avoids it). The front is measured as Lagra's `dam_break_front` does: the farthest
particle plus half a spacing, from the column's back face, over the column's width a, at the
times T = t√(2g/a) of Martin & Moyce's Table 2. `SimulatorBase.run()` ends the process at its
stop time, so each solver runs in a child process that records from the step callback."""

import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

A, G = 0.5, 9.81
# Martin & Moyce (1952), Table 2, n² = 2: T and z/a (as docs/bench/fluids.md and lang/src/prediction.rs)
MM = [(0.41, 1.11), (0.84, 1.22), (1.19, 1.44), (1.43, 1.67), (1.63, 1.89), (1.83, 2.11), (1.98, 2.33),
      (2.2, 2.56), (2.32, 2.78), (2.51, 3.0), (2.65, 3.22), (2.83, 3.44), (2.98, 3.67)]


class Column:
    """`across` particles across, twice as many up, spacing DX = 2r. The first particle stands
    3r from the tank's back wall and floor (at 2r the peer's boundary throws the column up: its
    own examples start 3r off), so the column's back face is 2r inside the wall."""

    def __init__(self, across):
        self.across = across
        self.dx = A / across
        self.r = self.dx / 2
        self.first = 3 * self.r
        self.back = self.first - self.r

    def z(self, front):
        """The front as Lagra's `dam_break_front` measures it: the farthest particle plus half a
        spacing, from the column's back face, over a."""
        return (front + self.r - self.back) / A


def scene(method, col):
    R, DX, FIRST, BACK, ACROSS = col.r, col.dx, col.first, col.back, col.across
    last = FIRST + (ACROSS - 1) * DX
    top = FIRST + (2 * ACROSS - 1) * DX
    length = BACK + 5 * A + 2 * R
    config = {
        "sim2D": True, "particleRadius": R, "numberOfStepsPerRenderUpdate": 1, "gravitation": [0, -G, 0],
        "boundaryHandlingMethod": 2, "enableVTKExport": False, "enablePartioExport": False,
    }
    material = {"id": "Fluid", "density0": 1000}
    if method == "wcsph":
        # Lagra's constants: B = ρ₀c₀²/γ, c₀ = 10√(2ga), γ = 7, dt 2.5e-4 fixed at 12 across
        # (in proportion to the spacing at others); no viscosity
        c0 = 10 * math.sqrt(2 * G * A)
        config |= {"simulationMethod": 0, "timeStepSize": 2.5e-4 * 12 / ACROSS, "cflMethod": 0,
                   "WCSPH": {"stiffness": 1000 * c0 * c0 / 7, "exponent": 7}}
        material |= {"viscosityMethod": 0}
    else:
        # its dam-break examples' settings: DFSPH, CFL step up to 1 ms, XSPH viscosity 0.01
        config |= {"simulationMethod": 4, "cflMethod": 1, "cflFactor": 1, "cflMaxTimeStepSize": 0.001 * 12 / ACROSS,
                   "DFSPH": {"minIterations": 2, "maxIterations": 100, "maxError": 0.01,
                             "maxIterationsV": 100, "maxErrorV": 0.1, "enableDivergenceSolver": True}}
        material |= {"viscosityMethod": 1, "Standard viscosity": {"viscosity": 0.01}}
    return {
        "Configuration": config,
        "Materials": [material],
        "RigidBodies": [{
            "geometryFile": "UnitBox.obj", "translation": [length / 2, 0.75, 0], "rotationAxis": [1, 0, 0],
            "rotationAngle": 0, "scale": [length, 1.5, 1], "isDynamic": False, "isWall": True,
            "mapInvert": True, "mapThickness": 0.0, "mapResolution": [5 * ACROSS, 10 * ACROSS // 3, 20]}],
        # the sampler fills [start + 2r, end − 2r] with spacing 2r
        "FluidBlocks": [{"denseMode": 0, "start": [FIRST - DX, FIRST - DX, -1],
                         "end": [last + DX + 1e-9, top + DX + 1e-9, 1], "translation": [0, 0, 0], "scale": [1, 1, 1]}],
    }


def child(scene_file, out_file):
    import pysplishsplash as sph

    times = [t / math.sqrt(2 * G / A) for t, _ in MM]
    out = open(out_file, "w")
    state = {"next": 0, "steps": 0, "start": None}

    def xs():
        fluid = sph.Simulation.getCurrent().getFluidModel(0)
        return [float(fluid.getPosition(i)[0]) for i in range(fluid.numActiveParticles())]

    def step():
        t = float(sph.TimeManager.getCurrent().getTime())
        state["steps"] += 1
        if state["start"] is None:
            x = xs()
            out.write(json.dumps({"particles": len(x), "first": min(x), "last": max(x)}) + "\n")
            state["start"] = time.perf_counter()
        while state["next"] < len(times) and t >= times[state["next"]]:
            wall = time.perf_counter() - state["start"]
            out.write(json.dumps({"t": t, "front": max(xs()), "steps": state["steps"], "wall": wall}) + "\n")
            out.flush()
            state["next"] += 1

    base = sph.Exec.SimulatorBase()
    base.init(useGui=False, sceneFile=scene_file, outputDir=str(Path(out_file).parent / "out"))
    base.setValueFloat(base.STOP_AT, times[-1] + 0.002)
    base.setTimeStepCB(step)
    base.run()


def run(method, col, workdir):
    import pysplishsplash

    box = Path(pysplishsplash.__file__).resolve().parent.parent.parent.parent / "bin" / "data" / "models" / "UnitBox.obj"
    (workdir / "UnitBox.obj").write_bytes(box.read_bytes())
    scene_file, out_file = workdir / f"{method}_{col.across}.json", workdir / f"{method}_{col.across}.jsonl"
    scene_file.write_text(json.dumps(scene(method, col), indent=1))
    env = dict(os.environ, OMP_NUM_THREADS="1")
    subprocess.run([sys.executable, __file__, "--child", scene_file, out_file], env=env, check=True,
                   stdout=subprocess.DEVNULL)
    lines = [json.loads(l) for l in out_file.read_text().splitlines()]
    return lines[0], lines[1:]


def main():
    if sys.argv[1:2] == ["--child"]:
        child(sys.argv[2], sys.argv[3])
        return
    sizes = [int(a) for a in sys.argv[1:]] or [12]
    with tempfile.TemporaryDirectory() as d:
        results = {(m, n): run(m, Column(n), Path(d)) for n in sizes for m in ["wcsph", "dfsph"]}
    print("| SPlisHSPlasH | across | particles | steps to T = 2.98 | wall s | µs per particle-step | worst z/a ratio to M&M | at T = 1.19 | at T = 2.98 |")
    print("|---|---|---|---|---|---|---|---|---|")
    for (m, n), (start, points) in results.items():
        col, count, last = Column(n), start["particles"], points[-1]
        ratios = [col.z(p["front"]) / z for p, (_, z) in zip(points, MM)]
        worst = max(ratios, key=lambda r: abs(r - 1))
        per = last["wall"] / last["steps"] / count * 1e6
        print(f"| {m} | {n} | {count} | {last['steps']} | {last['wall']:.2f} | {per:.2f} | {worst:.3f} | {ratios[2]:.3f} | {ratios[-1]:.3f} |")
    if len(sizes) > 1:
        return
    print()
    print("| T = t√(2g/a) | M&M z/a | " + " | ".join(m for m, _ in results) + " |")
    print("|---|---|" + "---|" * len(results))
    col = Column(sizes[0])
    for k, (t, z) in enumerate(MM):
        cells = []
        for start, points in results.values():
            front = col.z(points[k]["front"])
            cells.append(f"{front:.3f} ({100 * (front / z - 1):+.1f}%)")
        print(f"| {t} | {z} | " + " | ".join(cells) + " |")
    for (m, _), (start, _) in results.items():
        print(f"\n{m}: {start['particles']} particles, the first at x = {start['first']:.4f}, the last at {start['last']:.4f}")


if __name__ == "__main__":
    main()
