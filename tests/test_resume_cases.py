"""Every bundled case survives SIGKILL: killed after its first checkpoint (or, for the
procedures that have none, while it runs), ``--resume`` finishes it to the uninterrupted
result, bit for bit: the same history, the same XDMF frames, the same summary numbers. The
runs start from another working directory with a relative ``--out``, so a worker process
(the LAMMPS engine, ``dem.process=worker``) writes its restart files where the run lives.

The full-size seed cases are represented by their coarse variants; the cases that take more
than about 20 s uninterrupted run with ``-m slow``."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from coupling.case import bundled_cases

ROOT = Path(__file__).resolve().parent.parent
FULL = {"beam_impact", "beam_impact_3d", "cfrp_beam_impact", "cfrp_beam_impact_3d", "panel_buckling", "rod_impact",
        "dcb", "enf", "mixed_mode"}  # each has a coarse variant below
SLOW = {"panel_buckling_coarse", "cfrp_beam_impact_3d_coarse", "beam_impact_3d_coarse", "dcb_coarse", "enf_coarse",
        "mixed_mode_coarse", "rod_impact_coarse", "beam_impact_coarse", "coupled_vibration", "bonded_beam_bending",
        "ply_fracture", "column_buckling", "cfrp_beam_impact_coarse", "bond_strength"}
# with -m slow too (the suite's budget): the Chung-Ooi test 3 is test 2's scene (a sphere on a
# fixed one) with other constants, and free_vibration's resume is tests/test_restart.py's first
SLOW |= {"chung_ooi_3", "free_vibration"}
# and (the suite's ten minutes, session 44) all but one case of each kind: the suite resumes an
# all-FEM case (bar_wave), an all-DEM one (block_impact) and a coupled one (interface_patch); the
# others of each kind resume the same code with -m slow (coupled_vibration, rod_impact_coarse
# and a grown zone resume in tests/test_restart.py and tests/test_growth.py)
SLOW |= {"cantilever", "bonded_block_modulus", "chung_ooi_1", "chung_ooi_2", "chain_consistency",
         "coupled_free_flight", "interface_wave"}
CASES = [pytest.param(c, marks=pytest.mark.slow) if c in SLOW else c for c in bundled_cases() if c not in FULL]
ENV = {**os.environ, "PYTHONPATH": str(ROOT)}


def _femdem(cwd, *args, wait=True):
    cmd = [sys.executable, "-m", "coupling.cli", *args, "--quiet"]
    if wait:
        return subprocess.run(cmd, cwd=cwd, env=ENV, capture_output=True, text=True)
    return subprocess.Popen(cmd, cwd=cwd, env=ENV, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def _results(run: Path) -> dict:
    out = {}
    with h5py.File(run / "history.h5") as h:
        out.update({f"history/{k}": v[:] for k, v in h["history"].items()})
    if (run / "fields.h5").exists():  # every frame's arrays (meshio's XDMF reader cannot read line3 cells)
        with h5py.File(run / "fields.h5") as f:
            f.visititems(lambda name, d: out.__setitem__(f"fields/{name}", d[()]) if isinstance(d, h5py.Dataset)
                         else None)
    s = json.loads((run / "summary.json").read_text())
    out.update({f"qoi/{k}": np.array(v, float) for k, v in s["qoi"].items()})
    out["status"] = np.array(s["status"] == "ok")
    return out


def _same(a, b) -> bool:
    """Equal to the bit, a quantity that is nan in both (a crack that never came) included."""
    if a.dtype.kind == "f" and b.dtype.kind == "f":
        return np.array_equal(a, b, equal_nan=True)
    return np.array_equal(a, b)


def _kill_when(proc, ready, timeout=600):
    t0 = time.time()
    while time.time() - t0 < timeout and proc.poll() is None:
        if ready():
            proc.send_signal(signal.SIGKILL)
            proc.wait()
            return True
        time.sleep(0.02)
    return False


@pytest.mark.parametrize("case", CASES)
def test_killed_case_resumes_to_the_uninterrupted_result(tmp_path, case):
    here = tmp_path / "elsewhere"  # not the project: relative paths must still work
    here.mkdir()
    every = ["--set", "output.checkpoint_every=500"]  # early, and not thousands of them
    straight = _femdem(here, "run", case, *every, "--out", "straight")
    if straight.returncode == 2 and "output.checkpoint_every" in straight.stderr:  # cannot checkpoint
        every = []
        straight = _femdem(here, "run", case, "--out", "straight")
    assert straight.returncode == 0, straight.stderr
    # killed after its first checkpoint; a case too short to be caught there (or a procedure,
    # which has none) is killed as soon as it has started, and resumes from the beginning
    for out, ready in (("killed", lambda d: (d / "checkpoint" / "state.h5").exists()),
                       ("killed-early", lambda d: (d / "run.json").exists())):
        proc = _femdem(here, "run", case, *every, "--out", out, wait=False)
        partial = here / f"{out}.partial"
        if _kill_when(proc, lambda: ready(partial)):
            break
    else:
        pytest.fail("the run finished before it could be killed, twice")
    killed = here / out
    assert not killed.exists()
    r = _femdem(tmp_path, "run", "--resume", str(partial))  # from yet another directory, absolute
    assert r.returncode == 0, r.stderr
    a, b = _results(here / "straight"), _results(killed)
    assert a.keys() == b.keys()
    # whether a calibration came from the user's cache depends on what ran before (the first
    # run on a fresh machine computes it, the resumed one finds it): the calibrated values
    # themselves are compared
    for k in set(a) - {"history/calibration_cache_hit"}:
        assert _same(a[k], b[k]), k
    leftovers = {p.name for p in killed.iterdir()} - {"summary.json", "history.h5", "fields.xdmf", "fields.h5",
                                                                  "plots", "run.json"}
    assert not leftovers, leftovers  # no checkpoint, lock, scratch or engine files left in a finished run


# two ranks with -m slow (36 s, the suite's budget): the suite resumes one rank bit for bit, and
# tests/test_engines.py holds several ranks to one
@pytest.mark.parametrize("ranks", [1, pytest.param(2, marks=pytest.mark.slow)])
def test_models_hosted_in_the_lammps_worker_resume_bit_for_bit(tmp_path, ranks):
    """The law bonds and the impactor run inside the LAMMPS worker (on two ranks: each rank the
    bonds of its atoms); a checkpoint takes their state from there and a resume puts it back:
    killed after the first checkpoint, resumed, the coarse beam's impact equals the
    uninterrupted run, to the bit on one rank; on two, to 1e-12 of each quantity's scale (a
    restored LAMMPS spreads its atoms over the ranks anew and sums their forces in another
    order: tests/test_restart.py)."""
    args = ["run", "beam_impact_coarse", "--dem", "lammps", "--set", "clock.t_end=2.4e-5",
            "--set", "output.checkpoint_every=600", "--set", f"dem.ranks={ranks}"]  # about 1,660 steps: the
    # impactor in contact from the start
    assert (r := _femdem(tmp_path, *args, "--out", "straight")).returncode == 0, r.stderr
    proc = _femdem(tmp_path, *args, "--out", "killed", wait=False)
    assert _kill_when(proc, lambda: (tmp_path / "killed.partial" / "checkpoint" / "state.h5").exists())
    r = _femdem(tmp_path, "run", "--resume", "killed.partial")
    assert r.returncode == 0, r.stderr
    a, b = _results(tmp_path / "straight"), _results(tmp_path / "killed")
    assert a.keys() == b.keys()
    for k in a:
        if ranks == 1 or a[k].dtype.kind != "f":
            assert _same(a[k], b[k]), k
        else:
            family = [j for j in a if j.startswith("history/momentum_")] if "momentum_" in k else [k]
            scale = 1.0 if k.endswith("balance_error_rel") else max(np.abs(a[j]).max(initial=0.0) for j in family)
            assert np.allclose(a[k], b[k], rtol=0, atol=1e-12 * max(scale, 1e-300), equal_nan=True), k


def test_resume_after_the_engine_worker_alone_was_killed(tmp_path):
    """The engine's worker process dies: the run ends with status error and keeps its last
    checkpoint; --resume finishes it to the uninterrupted result."""
    args = ["run", "coupled_vibration", "--set", "dem.process=worker", "--set", "run.steps=3000",
            "--set", "output.checkpoint_every=1000", "--set", "clock.substeps=2"]
    assert _femdem(tmp_path, *args, "--out", "straight").returncode == 0
    proc = _femdem(tmp_path, *args, "--out", "killed", wait=False)
    partial = tmp_path / "killed.partial"

    def worker_after_checkpoint():
        if not (partial / "checkpoint" / "state.h5").exists():
            return False
        ps = subprocess.run(["pgrep", "-P", str(proc.pid), "-f", "dem_region.worker"], capture_output=True, text=True)
        for pid in ps.stdout.split():
            os.kill(int(pid), signal.SIGKILL)
        return bool(ps.stdout.split())

    t0 = time.time()
    while proc.poll() is None and time.time() - t0 < 120 and not worker_after_checkpoint():
        time.sleep(0.02)
    proc.wait(timeout=120)
    assert proc.returncode == 1
    s = json.loads((tmp_path / "killed" / "summary.json").read_text())
    assert s["status"] == "error" and (tmp_path / "killed" / "checkpoint").exists()
    r = _femdem(tmp_path, "run", "--resume", "killed")
    assert r.returncode == 0, r.stderr
    a, b = _results(tmp_path / "straight"), _results(tmp_path / "killed")
    for k in a:
        assert _same(a[k], b[k]), k


def test_a_running_run_cannot_be_resumed_or_shared(tmp_path):
    """While a run lives, --resume of its directory and a second run into the same --out are
    refused (exit 2, one line); the running run is untouched and finishes."""
    args = ["run", "coupled_vibration", "--set", "run.steps=20000"]
    proc = _femdem(tmp_path, *args, "--out", "r", wait=False)
    t0 = time.time()
    while not (tmp_path / "r.partial" / "run.json").exists() and time.time() - t0 < 60:
        time.sleep(0.05)
    for other in (["run", "--resume", "r.partial"], [*args, "--out", "r"]):
        r = _femdem(tmp_path, *other)
        assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    proc.wait(timeout=300)
    assert proc.returncode == 0 and (tmp_path / "r" / "summary.json").exists()


def test_runs_started_together_get_their_own_directories(tmp_path):
    """Two runs of the same case started in the same second with the default --out: two
    directories, two results, the engine in each name."""
    procs = [_femdem(tmp_path, "run", "coupled_free_flight", "--set", "run.steps=50", wait=False) for _ in range(2)]
    for p in procs:
        p.wait(timeout=120)
        assert p.returncode == 0
    dirs = sorted((tmp_path / "runs").iterdir())
    assert len(dirs) == 2 and all("liggghts" in d.name and (d / "summary.json").exists() for d in dirs), dirs


def _npz_damages(engine: Path) -> dict:
    """LIGGGHTS' and LAMMPS' engine file (dem.npz): truncated, an array missing, another
    model's particles."""
    good = engine.read_bytes()
    arrays = dict(np.load(engine))
    fewer = {k: v[:10] if v.ndim and len(v) == len(arrays["x"]) else v for k, v in arrays.items()}
    return {"truncated": lambda: engine.write_bytes(good[: len(good) // 2]),
            "an array missing": lambda: np.savez(engine, **{k: v for k, v in list(arrays.items())[1:]}),
            "another model's particles": lambda: np.savez(engine, **fewer)}


def _yade_damages(engine: Path) -> dict:
    """YADE's saved scene (dem.yade.bz2): truncated, absent."""
    good = engine.read_bytes()
    return {"truncated": lambda: engine.write_bytes(good[: len(good) // 2]), "absent": engine.unlink}


@pytest.mark.parametrize("dem", ["liggghts", pytest.param("lammps", marks=pytest.mark.slow),
                                 pytest.param("yade", marks=pytest.mark.slow)])
def test_a_damaged_checkpoint_is_refused_and_left_to_resume(tmp_path, dem):
    """A checkpoint whose engine file is truncated, or lacks an array, or holds another
    model's particles, cannot be restored: --resume says so in one line naming the
    checkpoint (exit 2, it was an exit 1 with nothing on stderr; on LAMMPS' worker and YADE
    an exit 1 that published the run as failed) and leaves the run as it was; with the file
    put back the run resumes and finishes."""
    args = ["run", "beam_impact_coarse", "--dem", dem, "--set", "clock.t_end=2.4e-5",
            "--set", "output.checkpoint_every=600"]
    proc = _femdem(tmp_path, *args, "--out", "killed", wait=False)
    partial = tmp_path / "killed.partial"
    engine = partial / "checkpoint" / ("dem.yade.bz2" if dem == "yade" else "dem.npz")
    assert _kill_when(proc, lambda: (partial / "checkpoint" / "state.h5").exists() and engine.exists())
    good = engine.read_bytes()
    for what, damage in (_yade_damages if dem == "yade" else _npz_damages)(engine).items():
        damage()
        r = _femdem(tmp_path, "run", "--resume", "killed.partial")
        assert r.returncode == 2, (what, r.returncode, r.stdout, r.stderr)
        assert r.stderr.count("\n") == 1 and "--resume" in r.stderr and "checkpoint" in r.stderr, (what, r.stderr)
        assert partial.is_dir() and (partial / "checkpoint" / "state.h5").exists(), what
        engine.write_bytes(good)
    r = _femdem(tmp_path, "run", "--resume", "killed.partial")
    assert r.returncode == 0, r.stderr
    assert json.loads((tmp_path / "killed" / "summary.json").read_text())["status"] == "ok"
