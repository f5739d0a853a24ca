"""Lagra from Python: compile a scene, run it, read the certified verdicts and the frames.

    import lagra
    s = lagra.Scene.from_file("scenes/kepler.lagra")
    r = s.run()
    r.verdicts            # each claim: PASS / FAIL / UNDECIDED, its certified bound
    r.positions           # NumPy array (frames, bodies, 3)
    r.write("orbit.xyz")  # extended XYZ for ASE and OVITO (.lammpstrj, .jsonl too)

The engine is the same code as the `lagra` command: a run's `report` is the document
`lagra run --json` prints. A run releases the GIL, and Ctrl-C stops it cleanly.
"""

from __future__ import annotations

import json
import sys
import time
from dataclasses import dataclass
from typing import Callable, Optional, Sequence

from . import _lagra
from ._lagra import SceneError

__all__ = ["Scene", "Result", "Verdict", "Checked", "SceneError", "check"]


@dataclass(frozen=True)
class Verdict:
    """One claim's verdict: `status` is "PASS", "FAIL" or "UNDECIDED"; `bound` the certified
    bound on its measure (for a FAIL, the lower end of the breach); `step` where it failed."""

    claim: str
    status: str
    bound: Optional[float]
    step: Optional[int]
    line: str


class Result:
    """A finished run: the report, the verdicts and the frames (every `frame_every` steps).

    What a run keeps in memory is bounded however long it is: the frames to 1 GiB (past it
    every 2nd, 4th, ... frame and the last; `steps` says which) and each claim's bounds to
    20,000 checkpoints the same way. Ask `lagra run --trace FILE --certificate FILE` for all."""

    def __init__(self, run: "_lagra.Run"):
        self._run = run
        self.report: dict = json.loads(run.report)

    @property
    def positions(self):
        """NumPy array (frames, bodies, 3), the frames' own storage (no copy)."""
        return self._run.positions

    @property
    def velocities(self):
        return self._run.velocities

    @property
    def orientations(self):
        """NumPy array (frames, bodies, 4): each body's orientation, a unit quaternion (w, x, y,
        z) from its body frame to the world (the identity for a point mass); None where the
        scene has no rigid body."""
        return self._run.orientations

    @property
    def steps(self):
        """The step of each frame."""
        return self._run.frame_steps

    @property
    def times(self):
        return self._run.times

    @property
    def energies(self):
        """The energy witness of each frame (H, or H′ with a Nosé–Hoover chain)."""
        return self._run.energies

    @property
    def verdicts(self) -> list:
        out = []
        for c in self.report["claims"]:
            status = c["status"]
            bound = c.get("bound", c.get("lower"))
            out.append(Verdict(c["claim"], status, bound, c.get("step"), c["line"]))
        return out

    @property
    def bounds(self) -> dict:
        """Each certified claim's enclosure per checkpoint: {claim: (steps, lo, hi, tol)} as
        NumPy arrays (what `lagra view` plots; a certificate's trails). A claim declared again
        (a second `distance`) is `distance#1`."""
        import numpy as np

        out = {}
        for trail in json.loads(self._run.trails):
            marks = np.array([m[:4] for m in trail["marks"]], dtype=np.float64).reshape(-1, 4)
            name, n = trail["claim"], 1
            while name in out:
                name, n = f"{trail['claim']}#{n}", n + 1
            out[name] = (marks[:, 0].astype(np.uint64), marks[:, 1], marks[:, 2], marks[:, 3])
        return out

    @property
    def passed(self) -> bool:
        """Every claim PASSed, every prediction agreed, and the run did not halt."""
        return bool(self.report["passed"])

    @property
    def observables(self) -> Optional[dict]:
        return self.report.get("observables")

    def write(self, path) -> None:
        """Writes the frames: `.xyz` (extended XYZ), `.lammpstrj` (LAMMPS dump) or `.jsonl`."""
        self._run.write(str(path))

    def __repr__(self) -> str:
        shown = ", ".join(f"{v.claim} {v.status}" for v in self.verdicts) or "no claims"
        return f"<lagra.Result {self.report['scene']}: {self.report['steps']} steps, {shown}>"


class _Bar:
    """A progress bar on stderr: tqdm's if it is installed, else a line rewritten in place."""

    def __init__(self, total: int):
        try:
            from tqdm import tqdm

            self._tqdm = tqdm(total=total, unit="step", file=sys.stderr)
        except ImportError:
            self._tqdm = None
        self.total, self.done, self.start, self.drawn = total, 0, time.monotonic(), 0.0

    def __call__(self, step: int) -> None:
        # the engine may report every step: redraw five times a second at most
        now = time.monotonic()
        if now - self.drawn < 0.2 and step < self.total:
            return
        self.drawn = now
        if self._tqdm is not None:
            self._tqdm.update(step - self.done)
        else:
            elapsed = time.monotonic() - self.start
            rate = step / elapsed if elapsed > 0 else 0.0
            left = (self.total - step) / rate if rate > 0 else float("nan")
            width = 30
            filled = int(width * step / max(self.total, 1))
            sys.stderr.write(f"\r[{'#' * filled}{'.' * (width - filled)}] {step}/{self.total} steps, {rate:.0f} steps/s, {left:.0f} s left")
            sys.stderr.flush()
        self.done = step

    def close(self) -> None:
        if self._tqdm is not None:
            self._tqdm.close()
        else:
            sys.stderr.write("\n")


class Scene:
    """A compiled scene. `Scene.from_file(path)` or `Scene.from_str(text)`; a scene with errors
    raises `SceneError` (a `ValueError`) whose message carries file:line:col."""

    def __init__(self, inner: "_lagra.Scene"):
        self._s = inner

    @classmethod
    def from_file(cls, path) -> "Scene":
        return cls(_lagra.Scene.from_file(str(path)))

    @classmethod
    def from_str(cls, text: str, path: str = "<string>") -> "Scene":
        return cls(_lagra.Scene.from_str(text, path))

    name = property(lambda self: self._s.name)
    description = property(lambda self: self._s.description)
    dt = property(lambda self: self._s.dt)
    steps = property(lambda self: self._s.steps, doc="The scene's own run length.")
    terms = property(lambda self: self._s.terms, doc="Each term: kind, keyword, sites, params.")
    bodies = property(lambda self: self._s.bodies, doc="Each body's mass and charge.")
    warnings = property(lambda self: self._s.warnings)

    @property
    def positions(self):
        """The initial positions, (bodies, 3); assign an array of that shape to change them."""
        return self._s.positions

    @positions.setter
    def positions(self, a) -> None:
        self._s.positions = _float_rows(a, "positions")

    @property
    def velocities(self):
        return self._s.velocities

    @velocities.setter
    def velocities(self, a) -> None:
        self._s.velocities = _float_rows(a, "velocities")

    def set(self, name: str, value: float) -> "Scene":
        """Sets a parameter by `lagra grad`'s spellings (`trap.k`, `body[0].mass`, ...)."""
        self._s.set(name, float(value))
        return self

    def run(
        self,
        steps: Optional[int] = None,
        dt: Optional[float] = None,
        threads: Optional[int] = None,
        frame_every: Optional[int] = None,
        progress: bool = False,
        callback: Optional[Callable[[int, dict], None]] = None,
        every: Optional[int] = None,
        restart: Optional[str] = None,
        resume: Optional[str] = None,
        until: Optional[int] = None,
    ) -> Result:
        """Runs the scene (its own length and time step unless given). `progress=True` shows a
        bar on stderr; `callback(step, state)` is called every `every` steps (default: every
        frame) with the state's time, positions and velocities. The GIL is released while it
        runs; Ctrl-C raises KeyboardInterrupt after stopping the run cleanly.

        `restart="r.bin"` writes a restart file where the run ends or stops (Ctrl-C, `until`);
        `resume="r.bin"` continues the run it holds, to the same bits as if it had never
        stopped (`lagra run --restart/--resume/--until`). The frames are then the segment's."""
        bar = _Bar(steps if steps is not None else self.steps) if progress else None
        try:
            run = self._s._run(steps, dt, threads, frame_every, bar, callback, every, restart, resume, until)
        finally:
            if bar is not None:
                bar.close()
        return Result(run)

    def gradient(self, objective: str, wrt: Sequence[str], threads: int = 1) -> dict:
        """The exact gradient of `objective` (`energy@end`, `x[1]@end`, ...) with respect to each
        of `wrt`, by reverse mode: {"value": ..., "gradient": {name: value}, ...}."""
        if isinstance(wrt, str):
            wrt = [wrt]
        return json.loads(self._s._gradient(objective, list(wrt), threads))

    def __repr__(self) -> str:
        return repr(self._s)


def _float_rows(a, name: str):
    import numpy as np

    arr = np.ascontiguousarray(a, dtype=np.float64)
    if arr.ndim != 2:
        raise ValueError(f"{name} must be a 2-D array of shape (bodies, 3); got {arr.ndim} dimension(s)")
    return arr


@dataclass(frozen=True)
class Checked:
    """A re-check's outcome: `agrees` (the re-derivation matches and every claim PASSed) and
    what `lagra-check` printed."""

    agrees: bool
    text: str


def check(certificate, states=None) -> Checked:
    """Re-checks a certificate without the kernel (`lagra-check`); a missing or malformed file
    raises ValueError with the reason."""
    code, out, err = _lagra.check(str(certificate), None if states is None else str(states))
    if code == 2:
        raise ValueError(err.strip())
    return Checked(code == 0, out)
