"""`lagra mcp` driven by the official MCP Python SDK (PyPI `mcp`), a client no one here wrote.

Run by tests/end_to_end/mcp.rs with the binary's path: python tests/mcp_client.py PATH/TO/lagra
It connects as the SDK connects by default (probing the 2026-07-28 `server/discover`, falling
back to the initialize handshake), lists the tools and the scene resources, runs the oscillator,
runs it again with its spring constant changed and checks the predicted period moved as
T ∝ 1/√k, submits a broken scene and reads the error with its line:col, and cancels nothing
it does not mean to. Exits non-zero, with the reason, on any mismatch.
"""
import asyncio
import json
import math
import sys

from mcp import StdioServerParameters
from mcp.client.client import Client
from mcp_common import check, text_of


def period(report):
    for p in report["predictions"]:
        if p["name"] == "oscillator_period":
            return p["predicted"], p["measured"], p["agrees"]
    raise SystemExit("mcp_client: FAILED: no oscillator_period prediction in the report")


async def main(binary):
    server = StdioServerParameters(command=binary, args=["mcp", "--scenes", "scenes"])
    async with Client(server) as client:
        tools = {t.name for t in (await client.list_tools()).tools}
        want = {"list_scenes", "read_scene", "terms", "check_scene", "run_scene", "noether", "recheck_certificate", "gradient"}
        check(want <= tools, f"tools {sorted(tools)} lack {sorted(want - tools)}")

        resources = [str(r.uri) for r in (await client.list_resources()).resources]
        check("lagra://scenes/oscillator.lagra" in resources, f"resources {resources}")
        osc = (await client.read_resource("lagra://scenes/oscillator.lagra")).contents[0].text
        check("bond harmonic [0, 1] { k: 2.0" in osc, "the oscillator resource is the scene")

        progress = []

        async def on_progress(done, total, message):
            progress.append((done, total))

        base = await client.call_tool("run_scene", {"scene": osc}, progress_callback=on_progress)
        check(not base.is_error, f"run_scene failed: {text_of(base)}")
        report = json.loads(text_of(base))
        check(report["passed"], f"the oscillator did not pass: {report['claims']}")
        t2, measured, agrees = period(report)
        check(agrees and abs(measured - t2) / t2 < 1e-4, f"period {measured} vs {t2}")

        stiffer = await client.call_tool("run_scene", {"scene": osc, "set": {"harmonic.k": 8.0}, "dt": 0.001, "steps": 6000})
        check(not stiffer.is_error, f"run_scene with set failed: {text_of(stiffer)}")
        t4, measured4, _ = period(json.loads(text_of(stiffer)))
        # the damped period 2π/√(k/μ − (γ/2μ)²): four times k is about half the period
        check(0.45 < t4 / t2 < 0.55, f"k ×4 moved the period from {t2} to {t4}")
        check(abs(measured4 - t4) / t4 < 1e-3, f"the stiffer oscillator measured {measured4} against {t4}")

        broken = osc.replace("mass: 1.0 }", "mass: 1.0 kg }", 1)
        bad = await client.call_tool("check_scene", {"scene": broken})
        check(bad.is_error, "a scene with a unit in reduced units checked clean")
        check("scene.lagra:" in text_of(bad) and "^" in text_of(bad), f"no located error: {text_of(bad)}")
        badrun = await client.call_tool("run_scene", {"scene": "scene s { entity { mass: 1 } solver { dt: 0.1 } }"})
        check(badrun.is_error and "needs a position" in text_of(badrun), f"broken run: {text_of(badrun)}")

        grad = await client.call_tool("gradient", {"path": "scenes/kepler.lagra", "objective": "energy@end", "wrt": "gravity.G", "steps": 500})
        check(not grad.is_error, f"gradient failed: {text_of(grad)}")
        g = json.loads(text_of(grad))["gradient"]["gravity.G"]
        check(math.isfinite(g) and g < 0, f"dH/dG = {g}")

        try:
            await client.call_tool("no_such_tool", {})
            check(False, "an unknown tool was accepted")
        except Exception as e:  # the SDK raises the protocol error
            check("unknown tool" in str(e), f"unknown tool error: {e}")
    print(f"mcp_client: ok ({len(tools)} tools, {len(resources)} scenes, period {t2:.6f} -> {t4:.6f}, {len(progress)} progress notes)")


asyncio.run(main(sys.argv[1]))
