"""The coupling layer's law bonds on several MPI ranks of an engine's worker: each rank evaluates
the bonds of the atoms it owns.

A bond belongs to the rank that owns its first particle, a particle to the rank LAMMPS made it
local to (both fixed when the bonds are shared out). Per step, on every rank, the models in
their order:

- a law family: each rank runs the bonds' pass over its own bonds only
  (``LawBonds.evaluate_only``: every bond is evaluated once, by one rank); the force vectors
  ("slots") of the bonds that act on another rank's particles are then summed over the ranks,
  each rank giving its own rows and zeros for the rest; the particles' pass then sums, for each
  particle, all the slots aimed at it, in the order one rank sums them;
- a ply family's initiation reads each particle's stress from the last tractions of all its
  bonds: after its step, the tractions of the bonds at a particle whose bonds have several
  owners are summed over the ranks the same way;
- the other models (impactors, loads: cheap, and stateful in ways that do not split) run on
  every rank alike.

Then each rank keeps the force rows of its own particles, which it holds complete and summed in
one rank's order, and one Allreduce adds them up (x + 0 = x): the forces are those of one rank
bit for bit.

A rank's rows of the bonds it does not own are stale. Their states are gathered when the
orchestrator asks for them (``states``): every rank then takes the whole state, and the bonds
are shared out again from the atoms each rank owns at that moment (LAMMPS moves atoms between
ranks as they cross the subdomains). The work and snapback counts each rank accumulates are
summed there (ranks other than 0 start from zero).

Today's worker still gathers every atom onto every rank each step (backends/lammps.py: x, v, f
are full copies), so every position is at hand; a partitioned engine would hand each rank its
own and its ghost atoms instead, with these same bond shares and exchanges.
"""
from __future__ import annotations

import numpy as np

from physics.law_bonds import WORK, LawBonds

from .model_step import model_states, set_model_states

BOND_ROWS = ("damage", "delta", "traction", "t_failed", "mirror_force", "law_m0", "law_mf", "law_crushed")
SUMMED = (*WORK, "law_snapback")


class _Family:
    """One law family's share: owner (nb,) rank of each bond; slots (e,) the bonds whose slots
    reach another rank's particle and their buffer; stress (s,) the bonds whose tractions a
    particle of several owners reads (ply families) and their buffer."""

    def __init__(self, bonds: LawBonds, owner: np.ndarray, particle_owner: np.ndarray, rank: int):
        self.bonds, self.owner = bonds, owner
        bonds.evaluate_only(owner == rank)
        P = bonds._plan
        targets = [bonds._loc[:, 0], bonds._loc[:, 1]]  # the particles each bond's slots act on
        for a, b in zip(P.dir_a, P.dir_b):
            targets += [bonds._loc[a, 0], bonds._loc[a, 1], bonds._loc[b, 0], bonds._loc[b, 1]]
        at = particle_owner[bonds.ids]  # (np,) rank of each particle of the family
        reach_out = np.zeros(len(owner), bool)
        for t in targets:
            reach_out |= at[t] != owner
        self.slots = np.flatnonzero(reach_out)
        self.slot_buffer = np.zeros((len(self.slots),) + P.slots.shape[1:])
        self.slot_theirs = np.flatnonzero(owner[self.slots] != rank)  # rows of the buffer other ranks give
        self.stress = np.zeros(0, np.int64)
        if hasattr(bonds.law, "initiate"):
            ends = bonds._loc.ravel()
            hi = np.full(len(bonds.ids), -1)
            lo = np.full(len(bonds.ids), np.iinfo(np.int64).max)
            np.maximum.at(hi, ends, np.repeat(owner, 2))
            np.minimum.at(lo, ends, np.repeat(owner, 2))
            mixed = hi != lo  # particles whose bonds have several owners
            self.stress = np.flatnonzero(mixed[bonds._loc].any(axis=1))
        self.stress_buffer = np.zeros((len(self.stress), 3))
        self.stress_theirs = np.flatnonzero(owner[self.stress] != rank)


class RankLaws:
    """models (the hosted list) split over the ranks of ``comm`` (mpi4py); the backend's
    ``owned()``: (k,) the particle ids this rank owns now."""

    def __init__(self, comm, backend, models: list):
        from mpi4py import MPI
        self.comm, self.backend, self.models = comm, backend, models
        self._sum, self._max, self._in_place = MPI.SUM, MPI.MAX, MPI.IN_PLACE
        self.rank = comm.Get_rank()
        self.share()

    def share(self) -> None:
        """Bonds and particles shared out from the atoms each rank owns now; the counts that are
        summed zeroed on ranks other than 0."""
        laws = [m for m in self.models if isinstance(m, LawBonds)]
        owner = np.full(self.backend.scene.n, -1, np.int64)  # every particle's (impactors' and loads' too)
        owner[np.asarray(self.backend.owned(), np.int64)] = self.rank
        self.comm.Allreduce(self._in_place, owner, op=self._max)
        if np.any(owner[np.unique(np.concatenate([b.pairs.ravel() for b in laws]))] < 0) if laws else False:
            raise RuntimeError("rank laws: a bonded particle that no rank owns")
        self.particle_owner = owner
        self.families = {id(b): _Family(b, owner[b.pairs[:, 0]], owner, self.rank) for b in laws}
        self._foreign = None  # the ModelStep's rows of other ranks' particles (at the first step)
        if self.rank != 0:
            for b in laws:
                for k in WORK:
                    setattr(b, k, 0.0)
                if hasattr(b.law, "snapback"):
                    b.law.snapback = 0

    def apply(self, view, dt: float) -> None:
        """One step of the models on the ModelStep ``view`` (its x read, its f zeroed); f then
        holds every rank's forces."""
        for m in self.models:
            fam = self.families.get(id(m))
            if fam is None:
                m.apply(view, dt)
                continue
            m.apply(view, dt, self._swap_slots)
            if len(fam.stress):
                self._swap_rows(m.traction, fam.stress, fam.stress_buffer, fam.stress_theirs)
        if self._foreign is None:
            self._foreign = np.flatnonzero(self.particle_owner[view.ids] != self.rank) if len(view.ids) else \
                np.zeros(0, np.int64)
        view.f[self._foreign] = 0.0
        self.comm.Allreduce(self._in_place, view.f, op=self._sum)

    def _swap_slots(self, bonds: LawBonds) -> None:
        fam = self.families[id(bonds)]
        if len(fam.slots):
            self._swap_rows(bonds._plan.slots, fam.slots, fam.slot_buffer, fam.slot_theirs)

    def _swap_rows(self, a: np.ndarray, rows: np.ndarray, buf: np.ndarray, theirs: np.ndarray) -> None:
        """a[rows] made every rank's: each rank gives the rows of its own bonds (``theirs``: the
        buffer's rows of other ranks' bonds, zeroed), summed."""
        np.take(a, rows, axis=0, out=buf)
        buf[theirs] = 0.0
        self.comm.Allreduce(self._in_place, buf, op=self._sum)
        a[rows] = buf

    def states(self) -> list[dict]:
        """Every model's state (model_states form), the law bonds' rows from their owners and
        their counts summed; collective. The bonds are then shared out again (share)."""
        states = model_states(self.models)
        laws = [(d, self.families[id(m)].owner) for m, d in zip(self.models, states) if id(m) in self.families]
        parts = self.comm.allgather([{k: np.asarray(d[k])[o == self.rank] for k in BOND_ROWS if k in d}
                                     | {k: d[k] for k in SUMMED if k in d} for d, o in laws])
        for i, (d, o) in enumerate(laws):
            for k in BOND_ROWS:
                if k in d:
                    full = np.array(d[k])
                    for r, part in enumerate(parts):
                        full[o == r] = part[i][k]
                    d[k] = full
            for k in SUMMED:
                if k in d:
                    d[k] = type(d[k])(sum(part[i][k] for part in parts))
        set_model_states(self.models, states)  # every rank the whole state, then shared out anew
        self.share()
        return states

    def set_states(self, states: list[dict]) -> None:
        """A checkpoint's states on every rank, then the bonds shared out (collective)."""
        set_model_states(self.models, states)
        self.share()

    def shares(self) -> list[int]:
        """Bonds this rank evaluates, per law family."""
        return [int(np.count_nonzero(f.owner == self.rank)) for f in self.families.values()]
