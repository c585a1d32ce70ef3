"""The compiled kernels' disk cache follows every change of the sources that define kernels
(physics/kernel_cache.py): numba's own check misses a change in a kernel's callee."""
from __future__ import annotations

import os
import subprocess
import sys
import time

from physics.kernel_cache import PREFIX, UNUSED_DAYS, cache_dir, sources_digest

CALLER = "from numba import njit\nfrom .callee import g\n\n\n@njit(cache=True)\ndef f(x):\n    return g(x) + 1.0\n"
CALLEE = "from numba import njit\n\n\n@njit(cache=True)\ndef g(x):\n    return {k} * x\n"


def _tree(root, k):
    pkg = root / "physics"
    pkg.mkdir(parents=True, exist_ok=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "caller.py").write_text(CALLER)
    (pkg / "callee.py").write_text(CALLEE.format(k=k))


def _f_of_one(root, numba_dir) -> float:
    """f(1.0) computed in a fresh process with the kernels cached in numba_dir."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(numba_dir), "PYTHONPATH": str(root)}
    out = subprocess.run([sys.executable, "-c", "from physics.caller import f; print(f(1.0))"], env=env, cwd=root,
                         capture_output=True, text=True, check=True)
    return float(out.stdout)


def test_a_changed_callee_is_compiled_anew(tmp_path):
    """Only the callee's file changes (g: 2 x -> 3 x): numba's cache alone keeps the caller's old
    machine code (the control, which shows the test can fail); the digest's directory does not."""
    root = tmp_path / "src"
    _tree(root, 2.0)
    plain = tmp_path / "plain"
    assert _f_of_one(root, plain) == 3.0 and _f_of_one(root, cache_dir(tmp_path / "digest", root)) == 3.0
    time.sleep(0.01)
    (root / "physics" / "callee.py").write_text(CALLEE.format(k=3.0))
    assert _f_of_one(root, plain) == 3.0  # stale: f(1) = 2 * 1 + 1 still, where g now gives 3
    assert _f_of_one(root, cache_dir(tmp_path / "digest", root)) == 4.0


def test_the_digest_follows_kernel_files_only(tmp_path):
    _tree(tmp_path, 2.0)
    d0 = sources_digest(tmp_path)
    (tmp_path / "physics" / "notes.py").write_text("X = 1  # no kernel here\n")
    assert sources_digest(tmp_path) == d0
    (tmp_path / "physics" / "caller.py").write_text(CALLER + "# a comment\n")
    assert sources_digest(tmp_path) != d0


def test_the_cache_directory_is_inherited_and_old_versions_go(tmp_path):
    _tree(tmp_path, 2.0)
    base = tmp_path / "numba"
    mine = cache_dir(base, tmp_path)
    assert mine.parent == base and mine.name == PREFIX + sources_digest(tmp_path)
    assert cache_dir(mine, tmp_path) == mine  # a child process given the directory keeps it
    old, recent = base / f"{PREFIX}0000000000000000", base / f"{PREFIX}1111111111111111"
    old.mkdir(), recent.mkdir()
    (old / "x.nbi").write_text("")
    then = time.time() - (UNUSED_DAYS + 1) * 86400
    os.utime(old, (then, then))
    cache_dir(base, tmp_path)
    assert not old.exists() and recent.exists() and mine.exists()


def test_the_old_layout_goes_from_the_project_s_own_directory_only(tmp_path):
    """Before the digests, numba wrote its per-package directories (name_<sha1>) straight into
    the project's cache: removed there once unused for UNUSED_DAYS days; in a directory the
    user named (own=False) nothing but the digests' directories is touched."""
    _tree(tmp_path, 2.0)
    then = time.time() - (UNUSED_DAYS + 1) * 86400
    for own in (True, False):
        base = tmp_path / f"numba-{own}"
        legacy = [base / f"{p}_{'ab' * 20}" for p in ("physics", "fem_region", "dem_region")]
        kept = [base / f"physics_{'ab' * 20}_x", base / "someone_elses", base / f"numpy_{'ab' * 20}"]
        recent = base / f"interfaces_{'cd' * 20}"
        for d in legacy + kept + [recent]:
            d.mkdir(parents=True)
            (d / "k.nbi").write_text("")
            if d is not recent:
                os.utime(d, (then, then))
        cache_dir(base, tmp_path, own=own)
        assert all(d.exists() != own for d in legacy)
        assert all(d.exists() for d in kept + [recent])


def test_doctor_says_whether_this_version_s_kernels_are_compiled(tmp_path, monkeypatch, capsys):
    """`femdem doctor` counts the kernels cached for this version, the orchestrator's and the
    LAMMPS worker's; with none it says the next run compiles them."""
    from coupling import doctor
    mine = tmp_path / "numba" / f"{PREFIX}{sources_digest()}"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(mine))
    monkeypatch.setenv("FEMDEM_CACHE_DIR", str(tmp_path))  # (the worker's: numba-lammps in it)
    monkeypatch.setattr(doctor, "report", lambda: {"engines": {}, "mpi": {}, "kernels": doctor.kernels()})
    doctor.doctor()
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 2 and all("none compiled for this version yet" in line for line in out), out
    for k in range(3):
        (mine / f"physics_{k}").mkdir(parents=True)
        (mine / f"physics_{k}" / f"kernels.f-{k}.py311.nbi").write_text("")
    k = doctor.kernels()
    assert k["orchestrator"] == {"dir": str(mine), "cached": 3} and k["lammps worker"]["cached"] == 0
    doctor.doctor()
    assert "3 compiled for this version" in capsys.readouterr().out
