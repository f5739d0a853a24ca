"""Run Kepler's two-body orbit from Python, and plot the orbit and the energy bound the checker
certified at every checkpoint. Saves examples/kepler_orbit.png (or the path given).

    .venv/bin/python examples/kepler_orbit.py [OUT.png]
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

import lagra

here = Path(__file__).resolve().parent
r = lagra.Scene.from_file(here.parent / "scenes" / "kepler.lagra").run()
print("\n".join(v.line for v in r.verdicts))

orbit = r.positions[:, 1] - r.positions[:, 0]  # the relative position, frame by frame
steps, lo, hi, tol = r.bounds["energy_conservation"]

fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4.5))
a.plot(orbit[:, 0], orbit[:, 1], lw=1)
a.set_aspect("equal")
a.set_title("the orbit (body 1 about body 0)")
b.semilogy(steps, hi, lw=1, label="certified upper bound of |ΔH|/|H₀|")
b.axhline(tol[0], color="red", ls="--", label="tolerance")
b.set_xlabel("step")
b.set_title(f"energy_conservation: {r.verdicts[0].status}")
b.legend()
fig.tight_layout()
out = Path(sys.argv[1]) if len(sys.argv) > 1 else here / "kepler_orbit.png"
fig.savefig(out, dpi=110)
print(f"wrote {out}")
