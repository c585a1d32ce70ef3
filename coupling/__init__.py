"""The orchestrator: case files, the coupled clock, scenes, outputs and the command line."""
import os
import tempfile
from pathlib import Path

# One BLAS thread: the orchestrator's matrices are small, and OpenBLAS's second thread spins
# on the core an in-process engine or the LAMMPS worker needs (measured on beam_impact_3d_coarse:
# 24 s of system time in a 28 s run, 9 % slower). Set before numpy loads OpenBLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def _writable(d: Path) -> bool:
    try:
        d.mkdir(parents=True, exist_ok=True)
        return os.access(d, os.W_OK | os.X_OK)
    except OSError:
        return False


def _user_cache() -> Path:
    """A cache directory this user can write: $FEMDEM_CACHE_DIR, else $XDG_CACHE_HOME/femdem or
    ~/.cache/femdem, else (no writable home, e.g. a service account) one in the temporary
    directory, per user."""
    given = os.environ.get("FEMDEM_CACHE_DIR")
    home = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "femdem"
    for d in ([Path(given)] if given else []) + [home, Path(tempfile.gettempdir()) / f"femdem-cache-{os.getuid()}"]:
        if _writable(d):
            return d
    raise SystemExit("femdem: no writable cache directory (set FEMDEM_CACHE_DIR to one)")


# YADE reads $HOME at start (KeyError where a scheduler's environment has none): the account's
os.environ.setdefault("HOME", str(Path.home()))
# OpenMPI's start in process (LIGGGHTS, YADE) finds its helpers on PATH: without the system's
# directories it aborted before MPI_Init and the process exited 1 with nothing said
_path = [d for d in os.environ.get("PATH", "").split(os.pathsep) if d]
os.environ["PATH"] = os.pathsep.join(_path + [d for d in os.defpath.split(os.pathsep) if d and d not in _path])

# numba caches compiled kernels next to the sources by default: not writable for an ordinary
# user of a system-wide install, and with no writable home numba fails at import. Set before
# any package imports numba; engine worker processes inherit it.
CACHE = _user_cache()
os.environ["FEMDEM_CACHE_DIR"] = str(CACHE)
for _var, _sub in (("NUMBA_CACHE_DIR", "numba"), ("MPLCONFIGDIR", "matplotlib")):
    if not _writable(Path(os.environ.get(_var) or CACHE / _sub)):  # e.g. inherited from another user
        os.environ[_var] = str(CACHE / _sub)
    os.environ.setdefault(_var, str(CACHE / _sub))
# in it, a directory per version of the kernels' sources (numba's own check misses a change in
# a kernel's callee: physics/kernel_cache.py)
from physics.kernel_cache import PREFIX as _PREFIX, cache_dir as _kernel_cache  # noqa: E402 (standard library only)

_base = Path(os.environ["NUMBA_CACHE_DIR"])
_own = (_base.parent if _base.name.startswith(_PREFIX) else _base) == CACHE / "numba"  # (not one a user named)
os.environ["NUMBA_CACHE_DIR"] = str(_kernel_cache(_base, own=_own))
