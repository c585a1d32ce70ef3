"""Checkpoint and restart: a run killed with SIGKILL continues from its last checkpoint and
reproduces the uninterrupted run bit for bit (FEM side and every engine on one process; LAMMPS
on two ranks to round-off: the restored atoms are spread and their neighbour lists rebuilt
afresh, which changes the order of the force sums)."""
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parent.parent


def _femdem(*args):
    return subprocess.run([sys.executable, "-m", "coupling.cli", *args], cwd=ROOT, capture_output=True, text=True)


def _history(run):
    with h5py.File(run / "history.h5") as h:
        return {k: v[:] for k, v in h["history"].items()}


def _kill_after_checkpoint(args, out: Path, timeout=120):
    proc = subprocess.Popen([sys.executable, "-m", "coupling.cli", *args, "--out", str(out), "--quiet"], cwd=ROOT)
    partial = out.with_name(out.name + ".partial")
    t0 = time.time()
    while time.time() - t0 < timeout:
        if (partial / "checkpoint" / "state.h5").exists():
            time.sleep(0.3)
            proc.send_signal(signal.SIGKILL)
            proc.wait()
            return partial
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    proc.kill()
    raise AssertionError("no checkpoint appeared before the run ended")


@pytest.mark.parametrize("case, sets", [
    ("free_vibration", ["run.steps=40000", "output.checkpoint_every=4000", "output.history_every=100"]),
    ("coupled_vibration --dem liggghts", ["run.steps=4000", "output.checkpoint_every=400", "clock.substeps=2",
                                          "output.history_every=20"]),
    # (-m slow, the suite's ten minutes: the suite resumes LAMMPS' worker with its hosted laws,
    # tests/test_resume_cases.py)
    pytest.param("coupled_vibration --dem lammps", ["run.steps=2000", "output.checkpoint_every=400",
                                                    "clock.substeps=2", "output.history_every=20"],
                 marks=pytest.mark.slow),
    # law bonds on FEM nodes (the layers' interface) carry damage that the checkpoint must keep
    ("rod_impact_coarse", ["output.checkpoint_every=300", "output.history_every=20"]),
    pytest.param("coupled_vibration --dem lammps", ["run.steps=4000", "output.checkpoint_every=400", "clock.substeps=2",
                                                    "output.history_every=20", "dem.ranks=2"], marks=pytest.mark.slow),
    # YADE with the coupling layer's laws and impactor on its particles: their forces are in the
    # force container its own file does not hold (kept beside it since session 36)
    pytest.param("beam_impact_coarse --dem yade", ["clock.t_end=4e-5", "output.checkpoint_every=300"],
                 marks=pytest.mark.slow),
])
def test_killed_run_resumes_bit_identical(tmp_path, case, sets):
    exact = "dem.ranks=2" not in sets
    args = ["run", *case.split()] + sum((["--set", s] for s in sets), [])
    ref = tmp_path / "straight"
    assert _femdem(*args, "--out", str(ref), "--quiet").returncode == 0
    out = tmp_path / "killed"
    partial = _kill_after_checkpoint(args, out)
    assert not out.exists() and (partial / "run.json").exists()
    r = _femdem("run", "--resume", str(partial), "--quiet")
    assert r.returncode == 0, r.stderr
    a, b = _history(ref), _history(out)
    assert a["time"].shape == b["time"].shape
    for k in a:
        if exact:
            assert np.array_equal(a[k], b[k]), k
        else:  # round-off of reordered sums, against the quantity's scale (a ratio: 1; a momentum
            # component: the largest component, the others are round-off themselves)
            family = [j for j in a if j.startswith("momentum_")] if k.startswith("momentum_") else [k]
            scale = max(max(np.abs(a[j]).max() for j in family), 1.0 if k.endswith("_rel") else 1e-300)
            assert np.allclose(a[k], b[k], rtol=0, atol=1e-9 * scale), k
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "ok" and not (out / "checkpoint").exists()


def test_resume_refuses_what_it_cannot_continue(tmp_path):
    r = _femdem("run", "--resume", str(tmp_path / "nothing"))
    assert r.returncode == 2 and "--resume" in r.stderr and len(r.stderr.strip().splitlines()) == 1
