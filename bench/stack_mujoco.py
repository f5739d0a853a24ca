#!/usr/bin/env python3
"""MuJoCo's side of the 1,000-block stack (scenes/bench/stack_1000.lagra): the same blocks
(positions and turns read from the scene), mass, friction, floor, gravity and time step, run
for the scene's 4 s with MuJoCo's defaults otherwise (Newton solver, soft contacts). Prints the
time per step (the model built, the clock around mj_step alone), the fastest point of any block
at the end (|v| + |ω|·√3/2, the `resting` claim's measure), and how far any block moved sideways.

    python3 -m pip install mujoco && python3 bench/stack_mujoco.py [scene] [--dt DT]
"""

import math
import re
import sys
import time

import mujoco

scene = next((a for a in sys.argv[1:] if a.endswith(".lagra")), "scenes/bench/stack_1000.lagra")
dt = float(sys.argv[sys.argv.index("--dt") + 1]) if "--dt" in sys.argv else 0.005
duration = 4.0

blocks = re.findall(
    r"position: \[([-\d.e]+), ([-\d.e]+), ([-\d.e]+)\], orientation: \{ axis: \[0, 1, 0\], angle: ([-\d.e]+) deg \}",
    open(scene).read(),
)
bodies = "\n".join(
    f'<body pos="{x} {y} {z}" axisangle="0 1 0 {a}"><freejoint/>'
    f'<geom type="box" size="0.5 0.5 0.5" mass="1" friction="0.6 0.005 0.0001"/></body>'
    for x, y, z, a in blocks
)
xml = f"""<mujoco>
  <option timestep="{dt}" gravity="0 -9.81 0"/>
  <worldbody>
    <geom type="plane" size="0 0 1" zaxis="0 1 0" friction="0.6 0.005 0.0001"/>
    {bodies}
  </worldbody>
</mujoco>"""
model = mujoco.MjModel.from_xml_string(xml)
data = mujoco.MjData(model)
start = data.qpos.copy().reshape(-1, 7)[:, :3]
steps = round(duration / dt)
clock = time.perf_counter()
for _ in range(steps):
    mujoco.mj_step(model, data)
elapsed = time.perf_counter() - clock
qvel = data.qvel.reshape(-1, 6)
# a free joint's qvel: linear velocity (world), then angular velocity (local frame): |ω| is the same
fastest = max(math.hypot(*v[:3]) + math.hypot(*v[3:]) * math.sqrt(0.75) for v in qvel)
end = data.qpos.reshape(-1, 7)[:, :3]
shift = max(max(abs(e[0] - s[0]), abs(e[2] - s[2])) for s, e in zip(start, end))
drop = max(s[1] - e[1] for s, e in zip(start, end))
deepest = max([-data.contact[i].dist for i in range(data.ncon)], default=0.0)
print(f"mujoco {mujoco.__version__}: {len(blocks)} blocks, dt {dt}, {steps} steps")
print(f"time per step {1e3 * elapsed / steps:.2f} ms ({steps / elapsed:.0f} steps/s, one thread)")
print(f"fastest point at t = {duration}: {fastest:.2e} (the scene's resting claim: 5e-3)")
print(f"largest sideways move {shift:.2e}, largest drop {drop:.2e}, deepest contact {deepest:.2e}")
