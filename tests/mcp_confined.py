"""`lagra mcp` kept in its room, driven by the official MCP Python SDK (PyPI `mcp`).

Run by tests/end_to_end/mcp.rs: python tests/mcp_confined.py PATH/TO/lagra WORKDIR
WORKDIR is an empty folder the test owns. The server is started there with `--root root` (and
its scenes inside it); the test then asks it, through every tool that takes a path, for what
lies outside — `../`, an absolute path, a symlink inside the root pointing out — and for what
is no regular file or too large — /dev/zero, a FIFO, a directory, a sparse gigabyte, an inline
scene of 17 MiB — and requires a clear error each time, nothing of the outside file echoed, and
the server still answering afterwards. Exits non-zero, with the reason, on any mismatch.
"""
import asyncio
import os
import sys
import time

from mcp import StdioServerParameters
from mcp.client.client import Client
from mcp_common import check, text_of


SECRET = "lagra-secret-line: this must never reach the client"
SCENE = """scene s {
  entity { position: [0, 0, 0], mass: 1 }
  entity { position: [1, 0, 0], mass: 1 }
  bond harmonic [0, 1] { k: 2.0, r0: 1.0 }
  solver { dt: 0.01, steps: 10 }
}
"""


async def main(binary, work):
    root = os.path.join(work, "root")
    os.makedirs(os.path.join(root, "scenes"))
    with open(os.path.join(root, "scenes", "s.lagra"), "w") as f:
        f.write(SCENE)
    outside = os.path.join(work, "outside.lagra")
    with open(outside, "w") as f:
        f.write(SECRET + "\n")
    os.symlink(outside, os.path.join(root, "link.lagra"))
    os.symlink(outside, os.path.join(root, "scenes", "leak.lagra"))
    os.mkfifo(os.path.join(root, "fifo.lagra"))
    with open(os.path.join(root, "big.lagra"), "wb") as f:
        f.truncate(1 << 30)  # sparse: a gigabyte that takes no disk
    os.mkdir(os.path.join(root, "dir.lagra"))

    server = StdioServerParameters(command=binary, args=["mcp", "--root", "root", "--scenes", "root/scenes"], cwd=work)
    async with Client(server) as client:
        async def refused(tool, args, why):
            started = time.monotonic()
            r = await client.call_tool(tool, args)
            text = text_of(r)
            check(r.is_error, f"{tool} {args} was not refused: {text[:200]}")
            check(why in text, f"{tool} {args}: expected `{why}` in the error, got: {text[:300]}")
            check("lagra-secret-line" not in text and "root:x:0" not in text, f"{tool} {args} echoed a file: {text[:300]}")
            check(time.monotonic() - started < 10, f"{tool} {args} took {time.monotonic() - started:.1f} s to refuse")

        for path in ["outside.lagra", "../outside.lagra", "root/../outside.lagra", outside, "/etc/passwd",
                     "root/link.lagra", "/no/such/file.lagra"]:
            for tool in ["check_scene", "run_scene", "noether"]:
                await refused(tool, {"path": path}, "outside the server's roots")
            await refused("gradient", {"path": path, "objective": "energy@end", "wrt": "harmonic.k"}, "outside the server's roots")
            await refused("recheck_certificate", {"certificate": path}, "outside the server's roots")
        await refused("recheck_certificate", {"certificate": "/etc/shadow", "states": "/etc/passwd"}, "outside the server's roots")
        await refused("gradient", {"path": "root/scenes/s.lagra", "objective": "mse:" + outside, "wrt": "harmonic.k"},
                      "outside the server's roots")
        await refused("read_scene", {"name": "leak"}, "outside the server's roots")

        await refused("run_scene", {"path": "/dev/zero"}, "outside the server's roots")
        await refused("run_scene", {"path": "root/fifo.lagra"}, "a FIFO, not a regular file")
        await refused("check_scene", {"path": "root/dir.lagra"}, "a directory, not a regular file")
        await refused("run_scene", {"path": "root/big.lagra"}, "over the limit of 16.0 MiB")
        await refused("recheck_certificate", {"certificate": "root/fifo.lagra"}, "a FIFO, not a regular file")
        await refused("check_scene", {"scene": "x" * (17 << 20)}, "over the limit of 16.0 MiB")
        await refused("run_scene", {"scene": SCENE, "set": {f"body[0].mass{i}": 1.0 for i in range(2000)}}, "`set` names")

        # and the server still answers, inside its room as before
        ok = await client.call_tool("check_scene", {"path": "root/scenes/s.lagra"})
        check(not ok.is_error and "s compiles" in text_of(ok), f"a scene inside the root: {text_of(ok)}")
        listed = await client.call_tool("list_scenes", {})
        check(not listed.is_error and "lagra-secret-line" not in text_of(listed), f"list_scenes: {text_of(listed)[:300]}")
        ran = await client.call_tool("run_scene", {"scene": SCENE})
        check(not ran.is_error, f"an inline scene: {text_of(ran)[:300]}")
    print("mcp_confined: ok (every path outside the root, every irregular or oversize input refused; the server answered after)")


asyncio.run(main(sys.argv[1], sys.argv[2]))
