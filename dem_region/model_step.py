"""What the coupling layer's models (law bonds, impactors, loads) see of an engine during one
hook: their particles' positions in one bulk read, their forces in one bulk write. Used where
the particles live: in the orchestrator beside an in-process engine, or inside the engine's
worker process (``backends.remote.RemoteBackend.host_models``)."""
from __future__ import annotations

import numpy as np

from physics.kernels import add_rows


class ModelStep:
    """What the coupling-layer models see of the engine during one hook: the positions of the
    union of their particles read in one bulk call into ``x`` (k, 3) m, their forces summed in
    ``f`` (k, 3) N and handed over in one call. Law bonds work on these arrays in place
    (``rows_of``); impactors and loads through positions_of / add_forces. Engines with array
    access (``bulk_arrays``) take every row each step (the same ids array: their write plan is
    built once; a zero row adds nothing); the others only the loaded rows (YADE costs ~1 us per
    particle per call from Python)."""

    def __init__(self, backend, models, ranks=None):
        """ranks: a rank_laws.RankLaws that runs the models on this MPI rank's share."""
        self.backend, self.ranks = backend, ranks
        self.ids = np.unique(np.concatenate([m.ids for m in models])) if models else np.zeros(0, int)
        self._index = np.full(int(self.ids.max()) + 1 if len(self.ids) else 0, -1)
        self._index[self.ids] = np.arange(len(self.ids))
        self.x, self.f = np.zeros((len(self.ids), 3)), np.zeros((len(self.ids), 3))
        self._read = getattr(backend, "read_positions", None)
        self._bulk = getattr(backend, "bulk_arrays", False)

    def run(self, models, dt: float) -> None:
        if not models:
            return
        if self._read is not None:
            self._read(self.ids, self.x)
        else:
            self.x[:] = self.backend.positions_of(self.ids)
        self.f[:] = 0.0
        if self.ranks is not None:
            self.ranks.apply(self, dt)
        else:
            for model in models:
                model.apply(self, dt)
        if self._bulk:
            self.backend.add_forces(self.ids, self.f)
            return
        loaded = np.flatnonzero(np.any(self.f != 0.0, axis=1))
        if loaded.size:
            self.backend.add_forces(self.ids[loaded], self.f[loaded])

    def rows_of(self, ids: np.ndarray) -> np.ndarray:
        return self._index[np.asarray(ids, int)]

    def positions_of(self, ids: np.ndarray) -> np.ndarray:
        return self.x[self._index[np.asarray(ids, int)]]

    def add_forces(self, ids: np.ndarray, F: np.ndarray) -> None:
        add_rows(self.f, self._index[np.asarray(ids, int)], np.ascontiguousarray(F, float).reshape(-1, 3))


def hosted_by(backend, models) -> bool:
    """True if ``backend`` (an engine in a worker) took ``models`` to run beside its particles;
    False: the caller evaluates them (an in-process engine, several ranks, a model the worker
    cannot rebuild)."""
    return bool(models) and hasattr(backend, "host_models") and backend.host_models(list(models))


def model_states(models) -> list[dict]:
    """Each model's state as its checkpoint holds it, plus the last force a probe reads."""
    out = []
    for m in models:
        d = dict(m.checkpoint_state())
        if isinstance(getattr(m, "force", None), np.ndarray):
            d["mirror_force"] = m.force
        out.append(d)
    return out


def set_model_states(models, states: list[dict]) -> None:
    """Models made equal to ``states`` (from model_states): a checkpoint restored, or the
    orchestrator's copies of models that run in an engine's worker brought up to date. The
    arrays may be views on a shared block the next sync rewrites: each model's restore_state
    copies what it keeps (tests/test_wire.py holds every hosted model to that)."""
    for m, d in zip(models, states):
        d = dict(d)
        force = d.pop("mirror_force", None)
        m.restore_state(d)
        if force is not None:  # into the array the model holds (a law family's: a view of its slots)
            if isinstance(getattr(m, "force", None), np.ndarray) and m.force.shape == np.shape(force):
                m.force[...] = force
            else:
                m.force = np.array(force)
