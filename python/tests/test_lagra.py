"""The Python package against the `lagra` command: the same reports, the same frames, and every
kind of bad input. Run from the repository root after the README's test command has built the
binary (`cargo test --workspace --profile release-tests`), or with LAGRA_BIN naming one."""

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

import lagra

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"
# the command-line binary of the README's test build (`cargo test --profile release-tests`), or
# the one LAGRA_BIN names
LAGRA = Path(os.environ.get("LAGRA_BIN", ROOT / "target" / "release-tests" / "lagra"))


def cli(*args):
    return subprocess.run([str(LAGRA), *map(str, args)], cwd=ROOT, capture_output=True, text=True)


def test_a_scene_reads_from_a_file_and_from_text():
    s = lagra.Scene.from_file(SCENES / "kepler.lagra")
    assert s.name == "kepler"
    assert [t["keyword"] for t in s.terms] == ["gravity"]
    assert s.terms[0]["params"] == {"G": 1.0}
    assert [b["mass"] for b in s.bodies] == [0.9, 0.1]
    again = lagra.Scene.from_str((SCENES / "kepler.lagra").read_text())
    assert again.name == s.name and np.array_equal(again.positions, s.positions)
    assert s.positions.shape == (2, 3) and s.velocities.shape == (2, 3)


def test_a_run_reports_what_the_command_reports():
    r = lagra.Scene.from_file(SCENES / "kepler.lagra").run()
    out = cli("run", SCENES / "kepler.lagra", "--json")
    theirs = json.loads(out.stdout)
    assert [c["line"] for c in r.report["claims"]] == [c["line"] for c in theirs["claims"]]
    assert r.report["predictions"] == theirs["predictions"]
    assert r.passed and theirs["passed"]
    assert [v.status for v in r.verdicts] == ["PASS"] * len(theirs["claims"])
    energy = r.verdicts[0]
    assert energy.claim == "energy_conservation" and 0 < energy.bound <= 1e-5 and energy.step is None


def test_the_frames_are_the_trace_the_command_writes(tmp_path):
    s = lagra.Scene.from_file(SCENES / "oscillator.lagra")
    r = s.run(steps=3000)
    trace = tmp_path / "t.jsonl"
    assert cli("run", SCENES / "oscillator.lagra", "--steps", 3000, "--trace", trace).returncode == 0
    lines = [json.loads(line) for line in trace.read_text().splitlines()]
    assert r.positions.shape == (len(lines), 2, 3)
    assert r.positions.dtype == np.float64 and r.positions.flags["C_CONTIGUOUS"]
    # the arrays are the frames' own storage, handed over, not copied into a fresh array
    assert not r.positions.flags["OWNDATA"]
    assert np.array_equal(r.positions, np.array([line["x"] for line in lines]))
    assert np.array_equal(r.velocities, np.array([line["v"] for line in lines]))
    assert np.array_equal(r.energies, np.array([line["energy"] for line in lines]))
    assert list(r.steps) == [line["step"] for line in lines]


def test_a_parameter_set_by_name_moves_the_prediction():
    s = lagra.Scene.from_file(SCENES / "oscillator.lagra")
    before = s.run().report["predictions"][0]
    s.set("harmonic.k", 4 * s.terms[0]["params"]["k"])
    # at the same ω·dt, so that the energy claim holds as before
    r = s.run(dt=s.dt / 2)
    assert r.passed, [v.line for v in r.verdicts]
    after = r.report["predictions"][0]
    # ω doubles: the predicted period halves, and the measured one follows it
    assert after["predicted"] == pytest.approx(before["predicted"] / 2, rel=1e-3), (before, after)
    assert after["rel_diff"] < 1e-3


def test_the_gradient_is_the_commands():
    s = lagra.Scene.from_file(SCENES / "oscillator.lagra")
    g = s.gradient("energy@end", ["harmonic.k", "body[0].velocity.x"])
    theirs = json.loads(cli("grad", SCENES / "oscillator.lagra", "--objective", "energy@end", "--wrt", "harmonic.k,body[0].velocity.x", "--json").stdout)
    assert g["gradient"] == theirs["gradient"]


def test_a_certificate_re_checks(tmp_path):
    cert, states = tmp_path / "c.json", tmp_path / "s.bin"
    assert cli("run", SCENES / "oscillator.lagra", "--certificate", cert, "--states", states).returncode == 0
    checked = lagra.check(cert, states)
    assert checked.agrees and "AGREES with the certificate" in checked.text
    with pytest.raises(ValueError, match="cannot read"):
        lagra.check(tmp_path / "missing.json")
    states.write_bytes(states.read_bytes()[:-5])
    with pytest.raises(ValueError, match="truncated|corrupt|checksum"):
        lagra.check(cert, states)


def test_bad_input_is_a_clear_python_error(tmp_path):
    with pytest.raises(FileNotFoundError, match="no_such.lagra: no such file"):
        lagra.Scene.from_file(tmp_path / "no_such.lagra")
    broken = "scene x {\n  entity { position: [0, 0, 0], mass: -1 }\n  solver { dt: 1 }\n}\n"
    with pytest.raises(lagra.SceneError, match=r"bad\.lagra:2:39: entity\.mass must be positive, got -1") as e:
        lagra.Scene.from_str(broken, "bad.lagra")
    assert isinstance(e.value, ValueError)
    s = lagra.Scene.from_file(SCENES / "kepler.lagra")
    with pytest.raises(lagra.SceneError, match="gravity has no parameter `H`"):
        s.set("gravity.H", 1.0)
    with pytest.raises(lagra.SceneError, match="body 7 does not exist"):
        s.set("body[7].mass", 1.0)
    with pytest.raises(ValueError, match=r"positions must have shape \(2, 3\), one row per body; got \[3, 3\]"):
        s.positions = np.zeros((3, 3))
    with pytest.raises(ValueError, match="2-D array"):
        s.velocities = np.zeros(6)
    with pytest.raises(ValueError, match="body 1 is not finite"):
        s.positions = np.array([[0.0, 0, 0], [np.nan, 0, 0]])
    with pytest.raises(ValueError, match="steps must be at least 1"):
        s.run(steps=0)
    with pytest.raises(ValueError, match="dt must be positive"):
        s.run(dt=-1.0)
    # a failed setting leaves the scene as it was
    assert s.terms[0]["params"]["G"] == 1.0
    assert s.run(steps=10).report["steps"] == 10


def test_a_new_initial_state_is_used():
    s = lagra.Scene.from_file(SCENES / "oscillator.lagra")
    x = s.positions.copy()
    x[1, 0] += 0.1
    s.positions = x
    r = s.run(steps=1)
    assert np.array_equal(r.positions[0], x)


def test_progress_and_a_callback_every_n_steps(capsys):
    s = lagra.Scene.from_file(SCENES / "lj_liquid.lagra")
    seen = []
    s.run(steps=200, progress=True, callback=lambda step, st: seen.append((step, st["t"], st["positions"].shape)), every=50)
    assert [step for step, _, _ in seen] == [50, 100, 150, 200]
    assert all(shape == (256, 3) for _, _, shape in seen)
    assert seen[0][1] == pytest.approx(50 * s.dt)
    assert "200/200" in capsys.readouterr().err


def test_an_error_in_the_callback_stops_the_run_and_is_raised():
    s = lagra.Scene.from_file(SCENES / "lj_liquid.lagra")

    def boom(step, state):
        raise RuntimeError(f"stop at {step}")

    with pytest.raises(RuntimeError, match="stop at 10"):
        s.run(steps=100, callback=boom, every=10)


def test_ctrl_c_stops_a_run_cleanly():
    s = lagra.Scene.from_file(SCENES / "lj_liquid.lagra")
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    start = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        s.run(steps=5_000_000)
    assert time.monotonic() - start < 5.0, "the run did not stop at Ctrl-C"
    # and the scene still runs afterwards
    assert s.run(steps=10).report["steps"] == 10


def test_ctrl_c_leaves_a_restart_that_resumes_to_the_unbroken_run(tmp_path):
    s = lagra.Scene.from_file(SCENES / "lj_liquid.lagra")
    restart = tmp_path / "r.bin"
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            s.run(steps=2_000_000, restart=str(restart))
    finally:
        timer.cancel()
    assert restart.exists(), "Ctrl-C wrote no restart file"
    # cut again at a step of our choosing, and resumed from there to the end
    s.run(steps=600, until=250, restart=str(restart))
    resumed = s.run(steps=600, resume=str(restart))
    whole = s.run(steps=600)
    assert resumed.report["steps"] == 600
    assert (resumed.positions[-1] == whole.positions[-1]).all()
    assert (resumed.velocities[-1] == whole.velocities[-1]).all()
    assert [c["line"] for c in resumed.report["claims"]] == [c["line"] for c in whole.report["claims"]]
    other = lagra.Scene.from_file(SCENES / "kepler.lagra")
    with pytest.raises(lagra.SceneError, match="another scene"):
        other.run(resume=str(restart))


def test_the_gil_is_released_while_it_runs():
    s = lagra.Scene.from_file(SCENES / "lj_liquid.lagra")
    done = threading.Event()
    worker = threading.Thread(target=lambda: (s.run(steps=3000), done.set()))
    ticks = 0
    worker.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.001)
    worker.join()
    assert ticks > 20, f"the main thread ran {ticks} times while the run went on"


def test_frames_write_in_formats_ase_reads(tmp_path):
    ase_io = pytest.importorskip("ase.io")
    r = lagra.Scene.from_file(SCENES / "lj_liquid.lagra").run(steps=300, frame_every=100)
    box = 6.71838476553
    for name, fmt in [("t.xyz", "extxyz"), ("t.lammpstrj", "lammps-dump-text")]:
        path = tmp_path / name
        r.write(path)
        frames = ase_io.read(path, index=":", format=fmt)
        assert len(frames) == 4
        for k, atoms in enumerate(frames):
            assert np.allclose(atoms.cell.lengths(), [box] * 3, rtol=0, atol=1e-12)
            assert np.array_equal(atoms.positions, r.positions[k]), name
    with pytest.raises(ValueError, match=r"\.jsonl \(Lagra's own\), \.xyz"):
        r.write(tmp_path / "t.csv")


def test_the_command_writes_the_same_formats(tmp_path):
    ase_io = pytest.importorskip("ase.io")
    path = tmp_path / "k.xyz"
    # 500 steps are too few for Kepler's predictions (exit 1): the trace is what is read here
    assert cli("run", SCENES / "kepler.lagra", "--steps", 500, "--trace", path).returncode in (0, 1)
    frames = ase_io.read(path, index=":")
    r = lagra.Scene.from_file(SCENES / "kepler.lagra").run(steps=500)
    assert len(frames) == r.positions.shape[0]
    assert np.array_equal(frames[-1].positions, r.positions[-1])
    assert frames[-1].info["step"] == 500


def test_rigid_bodies_have_their_orientations_in_the_arrays_and_the_files(tmp_path):
    ase_io = pytest.importorskip("ase.io")
    top = SCENES / "spinning_top.lagra"
    r = lagra.Scene.from_file(top).run(steps=2000)
    q = r.orientations
    assert q.shape == (r.positions.shape[0], 1, 4)
    assert np.allclose(np.linalg.norm(q, axis=2), 1.0, rtol=0, atol=1e-12)
    assert not np.allclose(q[0], q[-1]), "the brick turns"
    # the files carry them, the same bits as the command's trace
    path = tmp_path / "top.xyz"
    r.write(path)
    frames = ase_io.read(path, index=":")
    assert np.array_equal(frames[-1].arrays["quaternions"][0], q[-1][0])
    command = tmp_path / "command.xyz"
    assert cli("run", top, "--steps", 2000, "--trace", command).returncode in (0, 1)
    assert command.read_text() == path.read_text()
    # point masses have none
    assert lagra.Scene.from_file(SCENES / "kepler.lagra").run(steps=10).orientations is None


def test_a_thermostatted_run_has_its_observables():
    r = lagra.Scene.from_file(SCENES / "lj_nvt.lagra").run(steps=2000)
    o = r.observables
    assert o["kinetic_temperature"]["mean"] == pytest.approx(1.0, abs=0.05)
    assert o["pressure"]["stderr"] > 0
    assert r.verdicts[0].line.startswith("energy_conservation PASS  max|ΔH′|/|H′₀|")


def test_the_certified_bounds_per_checkpoint():
    r = lagra.Scene.from_file(SCENES / "kepler.lagra").run(steps=2000)
    steps, lo, hi, tol = r.bounds["energy_conservation"]
    assert list(steps[:3]) == [1, 2, 3] and len(steps) == 2000
    assert (lo <= hi).all() and (hi <= tol).all()
    assert hi.max() == pytest.approx(r.verdicts[0].bound, rel=1e-9)
    assert "distance" in r.bounds


def test_the_example_saves_its_plot(tmp_path):
    out = tmp_path / "orbit.png"
    done = subprocess.run([sys.executable, str(ROOT / "examples" / "kepler_orbit.py"), str(out)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert out.stat().st_size > 10_000 and out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
