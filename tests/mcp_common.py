"""What the MCP SDK scripts (tests/mcp_client.py, tests/mcp_confined.py) share."""
import os
import sys


def check(cond, what):
    """Ends the script with the reason, named after it, when `cond` fails."""
    if not cond:
        name = os.path.splitext(os.path.basename(sys.argv[0]))[0]
        raise SystemExit(f"{name}: FAILED: {what}")


def text_of(result):
    """The text parts of a tool's result."""
    return "".join(c.text for c in result.content if getattr(c, "type", "") == "text")
