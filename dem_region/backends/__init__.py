"""One word picks a DEM engine: name -> adapter module, imported lazily.

Only the adapter module of an engine imports that engine.
"""
from __future__ import annotations

import importlib

from .base import DemBackend, EngineUnavailable

# name -> (module, class, what a user does when it is missing)
_REGISTRY = {
    "yade": ("dem_region.backends.yade", "YadeBackend", "./scripts/setup.sh (Debian packages yade, python3-yade)"),
    "liggghts": ("dem_region.backends.liggghts", "LiggghtsBackend",
                 "./scripts/setup.sh (Debian packages liggghts, libliggghts-dev)"),
    "lammps": (None, None, "not implemented yet (issue #8)"),
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


def make_backend(name: str, process: str = "auto") -> DemBackend:
    """An engine instance, in this process or in a worker process (same contract)."""
    cls = get_backend(name)  # validates the name and that the engine loads here
    if process in ("auto", "in-process"):
        return cls()
    from .remote import RemoteBackend
    return RemoteBackend(name)
