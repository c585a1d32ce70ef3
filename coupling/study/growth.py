"""A damage zone that grows during the run (``zone.grow = true``; the beams and the bonded
beams, 2D and 3D, the plates' box zones and the discs' squares).

At each FEM step (``zone.grow_every``: 1, or every so many steps and at each history sample)
the far field's failure indices are evaluated on the FEM's displacement at that step:
Hoffman's ply index when the zone's plies fail, and Hashin's interlaminar index when the
far-field plies are tied (a cohesive far field delaminates by itself), the indices placement
uses (study/placement.py); a bonded beam's body by Hoffman and its adhesive by Hashin's index
on the bottom element row (fields.BondedIndices); at a check, only on the elements that begin
within the margin of the edge, unless one of them grows the zone. When an element that begins
within ``zone.margin`` of the zone's edge reaches ``zone.grow_at``, or an impactor's contact
patch (the farthest particle it touches) comes closer than the margin to the edge, the zone grows
over them and the margin, in whole particle spacings, up to ``zone.grow_to`` (a plate's box:
the distance from the centre is max(|x|, |y|), so the square grows over them): the coupled
model of the grown zone is built, continues from the current state, and the old one is closed.
A check between samples holds only the FEM's state (the clock's u_snapshot): a conversion it
asks for is made at the next FEM step, where the clock takes its whole snapshot (the energies
and the momentum the conversion books; ``pending``, kept in checkpoints).
The margin (0: the laminate's thickness, a bonded beam's depth, or four particle sizes) is
placement's.

The far field is meshed at the particle spacing out to grow_to (assemble._along), so the grown
far field is the old mesh less the columns that became particles. What carries over:
- FEM: each remaining node's displacement, velocity before the step's kicks, time and ledger,
  and the cohesive node pairs' state.
- Particles: the old ones keep their positions, velocities and bonds' state (matched by their
  lattice position). The new ones, and the old interface column (slaved to the FEM until
  now), take the FEM's displacement and velocity at their place (the old elements' shape
  functions); their bonds' rest lengths are the lattice's, so they carry the elements'
  strain. An interlaminar bond where the far field had a cohesive node pair takes its softening
  state (the same fraction of the way from onset to decohesion: HashinCohesiveLaw.damage_on).
- Impactors and particle loads: their state; the particles they act on get their last
  contact or load state.
- Momentum: each component of the converted particles' velocities is shifted by one common
  value, over the particles free in it (not those on a symmetry plane normal to it, whose
  component is held at zero), so that the total momentum equals the old model's at that step
  (to round-off). The energy that changes
  (the elements' strain energy against the bonds', the masses' new distribution) is reported
  for each conversion; the ledger carries the work and the dissipation over.

One approximation: the new model's first engine step evaluates the models (law bonds,
impactors) again at the step the old one ended on, as a start does (no step behind it): the
law bonds give the same forces, an impactor touches the particles from the position its last
move took it to (a contact force one substep late, on that substep only).
"""
from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
from scipy.spatial import cKDTree

from physics.kernels import damaged_reach, flagged_reach, touched_reach
from physics.law_bonds import WORK

from ..params import CaseError
from ..simulation import energy_scale
from .fields import BondedIndices, ElementIndex, FemIndices
from .placement import criteria


def matches(a: np.ndarray, b: np.ndarray, tol: float) -> np.ndarray:
    """(len(b),) the row of ``a`` (k, dim) at each row of ``b`` within ``tol``, or -1."""
    if len(a) == 0:
        return np.full(len(b), -1)
    dist, i = cKDTree(a).query(b, distance_upper_bound=tol)
    return np.where(np.isfinite(dist), i, -1)


def _node_keys(region, pairs) -> np.ndarray:
    """(n, dim + 1) each FEM node's position and its side of a doubled interface (0 below, 1
    above), apart by more than any tolerance: the two copies of a cohesive pair differ."""
    side = np.zeros(region.n_nodes)
    if pairs is not None and len(pairs):
        side[pairs[:, 1]] = 1.0
    else:  # a crack's doubled nodes (a specimen's, behind its window): the side their elements lie on
        X, t = region.X, region.mesh.t
        twins = cKDTree(X).query_pairs(1e-9 * float(np.ptp(X, axis=0).max()), output_type="ndarray").ravel()
        mid = np.bincount(t.ravel(), np.broadcast_to(X[t, -1].mean(axis=0), t.shape).ravel(), len(X)) / \
            np.maximum(np.bincount(t.ravel(), minlength=len(X)), 1)
        side[twins] = np.where(mid[twins] > X[twins, -1], 1.0, 0.0)
    return np.column_stack([region.X, side * 1e3])


def _bond_map(old_pairs: np.ndarray, new_pairs: np.ndarray, particle: np.ndarray) -> np.ndarray:
    """(len(new_pairs),) the old bond joining the same particles as each new one, or -1;
    particle: (n_new,) each new particle's old id (-1: new)."""
    n = int(max(old_pairs.max(initial=0), 0)) + 1
    keys = np.sort(old_pairs, axis=1) @ np.array([n, 1])
    order = np.argsort(keys)
    ends = particle[new_pairs]
    want = np.sort(ends, axis=1) @ np.array([n, 1])
    at = np.clip(np.searchsorted(keys[order], want), 0, len(keys) - 1)
    hit = (ends >= 0).all(axis=1) & (keys[order][at] == want)
    return np.where(hit, order[at], -1)


_BOND_ROWS = ("damage", "delta", "traction", "t_failed", "force")


def _carry_bonds(new, old, rows: np.ndarray, law_rows: bool = True) -> None:
    """New LawBonds' rows ``rows >= 0`` set to the old bonds' state there, and their ledger (the
    work done so far, the friction's and the dampers' shares, the time) the old one's."""
    at, src = np.flatnonzero(rows >= 0), rows[rows >= 0]
    for k in _BOND_ROWS:
        getattr(new, k)[at] = getattr(old, k)[src]
    for k in (*WORK, "time"):
        setattr(new, k, getattr(old, k))
    if law_rows:
        for k in ("m0", "mf", "crushed"):
            if hasattr(new.law, k) and hasattr(old.law, k):
                getattr(new.law, k)[at] = getattr(old.law, k)[src]


# a conversion that changes the stored energy by more than this (relative to the total) warns
# (measured: 1e-4 to 2e-3; 3.7e-2 on the full seed beam while a softening pair's damage, not its
# softening state, was carried)
JUMP_WARNING = 1e-2


class Growth:
    """The zone of one coupled run as it grows: decides, converts, and keeps the record
    (each conversion's time, half width, energy and momentum jumps) and the ledger's offsets."""

    def __init__(self, study, p: dict, dem: str, built, sim):
        self.study, self.p, self.dem = study, p, dem
        self.d, self.limit, self.margin = self._extent(built)
        self.grow_at = p["zone.grow_at"]
        self.every = p.get("zone.grow_every", 0)  # clock steps between checks (0: each history sample)
        self.half_width = float(built.lattice.x[:, 0].max())
        self.events: list[tuple[float, float, float, float]] = []  # (t s, half width m, dE / E, |dP| / |P|)
        self.offset = {"external_work": 0.0, "dissipated": 0.0}  # J, the ledger's accounts carried over
        self.limit_warning = ""
        self.step0 = 0  # the loop step the current model started at
        self.pending = -1  # the loop step a check asked to convert at (its whole snapshot), -1: none
        self.wall = 0.0  # s spent converting (building the grown zones' models)
        # released (study/seeded.py): the engine holds the reserve from the start and goes on
        # across conversions; rebuild: a new engine for each zone
        self.release = p.get("zone.conversion") == "release"
        # the particles' positions and velocities the current model's engine was built with
        # (None: the first zone, from rest); a resume builds it from the same ones, so that
        # what an engine derives at its build (its bonds' rest lengths) is the same
        self.engine_start: tuple[np.ndarray, np.ndarray] | None = None
        self._bind(sim, built)

    # a quarter's symmetry planes (x = 0; in 3D also y = 0) hold their normal velocity
    symmetric = True
    plane = False  # a plate's square zone (the distance from the centre is max(|x|, |y|))
    limit_name = "zone.grow_to"
    reach_name = "the contact patch or the zone's damage"  # what contact_reach and damage_reach measure

    def _extent(self, built) -> tuple[float, float, float]:
        """(particle spacing, the zone's growth limit, its margin) m."""
        from . import assemble, bonded
        from .disc import grow_limit as disc_limit  # (the package's name disc is the assembler)
        p, bb = self.p, built.bonded
        H = built.lam.thickness if bb is None else bb.depth
        shape = p["geometry.shape"]
        self.plane = shape in ("plate", "disc")  # a square zone about the centre, not a strip along x
        limit = bonded.grow_limit(p, bb) if bb is not None else disc_limit(p, built) if shape == "disc" else \
            assemble.plate_grow_limit(p, built) if self.plane else assemble.grow_limit(p, built)
        return built.t, limit, p["zone.margin"] or max(4 * built.t, H)

    # -- the current model ---------------------------------------------------------------------
    def _bind(self, sim, built) -> None:
        self.sim, self.built = sim, built
        sim.growth = self
        # its clock counts FEM steps from its own start: the run's last one, in its count
        built.clock.last_window = sim.n_steps - self.step0
        # the participants' snapshots at the checks between samples too, counted in the run's steps
        built.clock.check_every, built.clock.first_step = self.every, self.step0
        built.clock.full_at = self.pending
        sim.probes["zone_half_width"] = lambda: self.half_width
        energies = sim.energies
        sim.energies = lambda: {k: v + self.offset.get(k, 0.0) for k, v in energies().items()}
        region = built.dyn.region
        self._bind_criteria(built)
        self._bond_reach = self._reaches(built)
        X = region.X[region.mesh.t.T]  # (nel, nodes, dim)
        # each element's nearest and farthest distance from the centre: along x, or max(x, y) (a square)
        self._x0, self._x1 = X[:, :, 0].min(axis=1), X[:, :, 0].max(axis=1)
        if self.plane:
            self._x0, self._x1 = np.maximum(self._x0, X[:, :, 1].min(axis=1)), np.maximum(self._x1, X[:, :, 1].max(axis=1))
        self._order = np.argsort(self._x0, kind="stable")  # (the elements from the centre out: flagged_reach)
        self._x0_sorted = self._x0[self._order]
        # the impactors whose contact patch is followed, and the axis of each (0: a sphere's point)
        self._touching = [(m, np.zeros(3) if m.imp.axis is None else np.asarray(m.imp.axis, float))
                          for m in built.impactors.values() if m.imp.shape in ("sphere", "cylinder", "rod")]

    def snap(self, x: float) -> float:
        """m, the first edge a zone may have at or beyond x: whole particle spacings."""
        return float(np.ceil(x / self.d - 1e-9) * self.d)

    def _bind_criteria(self, built) -> None:
        region = built.dyn.region
        if built.bonded is None:
            fi, which = FemIndices(region, built.lam, built.dim), criteria(self.p, built)
            self._index = ElementIndex(region, fi.ply_stress, "Hoffman" in which, "interlaminar" in which, fi.k,
                                       fi.Z0, fi.R0)
        else:  # the body's Hoffman, the adhesive's interlaminar index on the bottom row
            fi = BondedIndices(region, built.bonded, built.dim)
            self._index = ElementIndex(region, fi.ply_stress, True, fi.bottom, fi.k, fi.Z0, fi.R0)
        self._indices = fi  # (the criteria one by one, in numpy: (hashin, hoffman) of centroid strains)

    def index(self, u: np.ndarray) -> np.ndarray:
        """(nel,) the far field's failure index that decides growth, at FEM displacement u
        (a buffer rewritten at each call)."""
        return self._index(u)

    def _p(self, half_width: float) -> dict:
        """The parameters of the zone at ``half_width``, at the run's own step and substeps."""
        clock = self.built.clock
        q = dict(self.p, **{"zone.half_width": half_width, "clock.dt": self.sim.dt, "clock.substeps": clock.m})
        if "zone.placement" in q:  # (placed once: the grown zone is a box)
            q["zone.placement"] = "box"
        return q

    def _assemble(self, half_width: float, start=None, error=CaseError):
        """(Simulation, Built) of the zone at ``half_width``, continued from ``start``."""
        try:
            return self.study.assemble(self._p(half_width), "coupled", self.dem, start)
        except CaseError as exc:  # the grown zone's model cannot be built: the run cannot go on as asked
            # (mid-run, an error: the run keeps its directory, its checkpoint and its history)
            raise error(f"zone.grow = true: the zone grown to {half_width * 1e3:.4g} mm cannot be modelled "
                        f"({exc})") from None

    # -- at each sample and check -----------------------------------------------------------------
    def contact_reach(self) -> float:
        """m: the farthest particle an impactor touches (its patch: 0 while it touches the
        symmetry plane's column alone), -1 without contact; a flat-faced rod's patch is its face
        (the particles under it) from the start, as placement takes a punch's."""
        reach = -1.0
        for m, axis in self._touching:
            x = m.last_positions()  # (the engine's, kept by the model: no call to a worker)
            x = self.built.backend.positions_of(m.ids) if x is None else x
            reach = max(reach, touched_reach(x, np.asarray(m.imp.x, float), axis, float(m.imp.radius),
                                             2 if self.plane else 1))
        return reach

    def _reaches(self, built) -> list:
        """[(LawBonds, each bond's reach from the centre, its nearer end's (nb,) m)] of the
        families damage_reach reads (probes.uncarried)."""
        from .probes import uncarried
        x = built.lattice.x
        r = np.abs(x[:, : 2 if self.plane else 1]).max(axis=1)
        return [(b, np.ascontiguousarray(r[b.pairs].min(axis=1))) for b in uncarried(built)]

    def damage_reach(self) -> float:
        """m: the farthest damaged bond of the zone whose damage the far field could not carry on
        (probes.uncarried: the plies', and the interlaminar ones over tied far-field plies), by
        its nearer end; -1 if none. Damage that comes within the margin of the edge grows the
        zone as the far field's index does: the rod's punch through a disc cracks the plies
        out from its edge before any element beyond reaches grow_at."""
        return max((damaged_reach(r, b.damage) for b, r in self._bond_reach), default=-1.0)

    def __call__(self, step: int):
        """The Simulation of the grown zone if the far field, the contact or the zone's own damage
        asks for it at this sample or check, else None: an element within the margin of the
        zone's edge at grow_at, or a contact patch or damage the far field cannot carry on closer
        than the margin to the edge. At a check that holds only the FEM's state, a conversion
        asked for is deferred to the next step (None now, ``pending`` set)."""
        clock = self.built.clock
        self.pending = -1
        u, w = clock.u_snapshot, self.half_width
        # the elements that begin within the margin of the edge decide, unless one of them grows
        # the zone: then the grown edge's margin reaches further, and every element is evaluated
        near_edge = self._order[: np.searchsorted(self._x0_sorted, w + self.margin, side="right")]
        index = self._index(u, near_edge)
        reach = flagged_reach(index, self._order, self._x0, self._x1, self.grow_at, w, self.margin)
        if reach > w * (1 + 1e-9):
            index = self.index(u)
            reach = flagged_reach(index, self._order, self._x0, self._x1, self.grow_at, w, self.margin)
        contact = max(self.contact_reach(), self.damage_reach())
        near = contact >= 0 and contact + self.margin > w * (1 + 1e-9)  # (none: nothing to follow)
        if reach <= w * (1 + 1e-9) and not near:
            return None
        reach = max(reach, contact)
        target = min(self.snap(reach + self.margin), self.limit)
        if target <= w * (1 + 1e-9):
            if not self.limit_warning:
                self.limit_warning = (
                    f"zone.grow: at t = {clock.t_snapshot:.4g} s the far field (index {self.index(u).max(initial=0.0):.2f}) or "
                    f"{self.reach_name} ({max(contact, 0.0) * 1e3:.3g} mm) asks for the zone out to x = "
                    f"{(reach + self.margin) * 1e3:.4g} mm, beyond {self.limit_name} = {self.limit * 1e3:.4g} mm: the zone "
                    "grows no further")
                self.sim.warnings.append(self.limit_warning)
            return None
        if not clock.snapshot_full:  # a check between samples: the conversion at the next FEM step,
            self.pending = clock.full_at = step + 1  # where the clock takes the whole snapshot (run_clock stops there)
            return None
        return self.convert(float(target), step)

    def convert(self, half_width: float, step: int):
        """The coupled model of the zone grown to ``half_width`` (m), continued from the state at
        loop step ``step``; the old model is closed."""
        t0 = time.perf_counter()
        old_sim, old = self.sim, self.built
        old_sim.sync() if old_sim.sync is not None else None
        before = old_sim.energies()
        transfer = _Transfer(old, old.clock.momentum_snapshot, self.symmetric, self.release)
        if old_sim.timing_correction is not None:  # read now: a rebuild closes its worker, a release's
            booked = old_sim.timing_correction()  # new clock resets the worker's books (run_clock books it after)
            old_sim.timing_correction = lambda: booked
        if not self.release:  # the old engine closed first: YADE runs one scene per process
            old_sim.close()
        sim, built = self._assemble(half_width, transfer, error=RuntimeError)
        old_sim.close = lambda: self.sim.close()  # whoever holds the first model closes the current one
        self.engine_start, self.step0 = transfer.engine_start, step
        old_sim.warnings.extend(w for w in sim.warnings if w not in old_sim.warnings)
        sim.warnings = old_sim.warnings  # (one list: the first model's, which the run's caller holds)
        self.half_width = float(built.lattice.x[:, 0].max())
        self._bind(sim, built)
        clock = built.clock
        clock.interface_work += old.clock.interface_work  # the tie's work over the whole run
        clock.interface_work_snapshot += old.clock.interface_work
        after = sim.energies()
        for k in self.offset:
            self.offset[k] += before[k] - after[k]
        stored = lambda e: e["kinetic"] + e["internal"]
        P_old, P_new = old.clock.momentum_snapshot, built.clock.momentum_snapshot
        self.events.append((float(built.clock.t_snapshot), self.half_width,
                            (stored(after) - stored(before)) / max(energy_scale(before), 1e-300),
                            float(np.linalg.norm(P_new - P_old) / max(np.linalg.norm(P_old), 1e-300))))
        t, _, jump, _ = self.events[-1]
        if abs(jump) > JUMP_WARNING:
            sim.warnings.append(
                f"zone.grow: the conversion at t = {t:.4g} s changed the stored energy by {jump:.2g} of the total "
                f"(more than {JUMP_WARNING:g}): the converted far field was {transfer.softening}; the elements' "
                "strain and motion map onto the particles only approximately: compare with a larger starting zone")
        self.wall += time.perf_counter() - t0
        return sim

    # -- checkpoints ----------------------------------------------------------------------------
    def state(self) -> dict:
        d = {"half_width": self.half_width, "events": np.array(self.events).reshape(-1, 4),
             "offset": np.array([self.offset["external_work"], self.offset["dissipated"]]),
             "limit_warning": np.frombuffer(self.limit_warning.encode(), np.uint8), "step0": self.step0,
             "pending": self.pending}
        if self.engine_start is not None:
            d["engine_x"], d["engine_v"] = self.engine_start
        return d

    def rebuild(self, state: dict, sim):
        """The Simulation a resume restores: the zone as it had grown by the checkpoint (``sim``,
        the first zone's, is closed); its state then comes from the checkpoint."""
        self.events = [tuple(float(x) for x in row) for row in np.asarray(state["events"]).reshape(-1, 4)]
        off = np.asarray(state["offset"], float)
        self.offset = {"external_work": float(off[0]), "dissipated": float(off[1])}
        self.limit_warning = bytes(np.asarray(state["limit_warning"], np.uint8)).decode()
        self.step0 = int(state["step0"])
        self.pending = self.built.clock.full_at = int(state.get("pending", -1))
        if self.limit_warning and self.limit_warning not in sim.warnings:
            sim.warnings.append(self.limit_warning)
        w = float(state["half_width"])
        if abs(w - self.half_width) <= 1e-9 * w:
            return sim
        if self.release:  # the first zone's engine holds the reserve: released up to the zone's edge
            new, built = self._assemble(w, _Released(self.built.clock))
        else:
            sim.close()
            self.engine_start = (np.asarray(state["engine_x"]), np.asarray(state["engine_v"]))
            new, built = self._assemble(w, _Replay(*self.engine_start))
        new.warnings = sim.warnings
        sim.close = lambda: self.sim.close()
        self.half_width = w
        self._bind(new, built)
        return new

    def qoi(self) -> dict[str, float]:
        e = np.array(self.events).reshape(-1, 4)
        return {"zone_conversions": float(len(e)), "zone_grown_half_width": self.half_width,
                "zone_first_conversion_time": float(e[0, 0]) if len(e) else -1.0,
                "zone_conversion_energy_jump": float(np.abs(e[:, 2]).max(initial=0.0)),
                "zone_conversion_momentum_jump": float(e[:, 3].max(initial=0.0)),
                "zone_conversion_wall_s": self.wall}

    def history(self) -> dict[str, np.ndarray]:
        e = np.array(self.events).reshape(-1, 4)
        return {"zone.conversion_time": e[:, 0], "zone.conversion_half_width": e[:, 1],
                "zone.conversion_energy_jump": e[:, 2], "zone.conversion_momentum_jump": e[:, 3]}


class _Replay:
    """A resume's start: the engine built from the particles' state at the conversion (the
    checkpoint then restores everything)."""

    def __init__(self, x: np.ndarray, v: np.ndarray):
        self.x, self.v = x, v

    def __call__(self, fem, scene, itf, models):
        return replace(scene, x=self.x, velocity=self.v)


class _Released:
    """A resume's start on the first zone's engine (its particles seeded): the particles of the
    zone the checkpoint holds are released there (the checkpoint then restores everything)."""

    def __init__(self, first_clock):
        self.engine, self.slaved = first_clock.dem, first_clock.tie.itf.ids

    def __call__(self, fem, scene, itf, models):
        self.engine.release(np.setdiff1d(self.slaved, itf.ids))


class _Transfer:
    """The state of the old model at its last FEM step, handed to the grown zone's model as it
    is built (coupled_simulation's ``start``). ``release``: the particles are seeded (study/
    seeded.py): the old model's engine goes on, the converted particles released in it."""

    def __init__(self, old, momentum: np.ndarray, symmetric: bool = True, release: bool = False):
        clock = old.clock
        backend = clock.dem  # (every particle the engine holds: a seeded zone's reserve too)
        self.symmetric = symmetric
        region = old.dyn.region
        self.old, self.momentum = old, np.array(momentum, float)
        self.region, self.pairs = region, old.fem_pairs
        self.u, self.v, self.t = clock.u_snapshot.copy(), clock.v_start_snapshot.copy(), float(clock.t_snapshot)
        self.fem_state = old.dyn.checkpoint_state()
        self.x, self.vel = backend.positions(), backend.velocities()
        self.X = backend.scene.x if release else old.lattice.x
        self.engine = backend if release else None
        self.softening = "elastic at its interfaces"  # what the converted far field's cohesive pairs carried
        self.slaved = np.zeros(len(self.X), bool)
        self.slaved[clock.tie.itf.ids] = True

    def __call__(self, fem, scene, itf, models):
        from interfaces.transition import TransitionInterface
        d = float(np.min(scene.radius)) * 2
        tol = 1e-6 * d
        # FEM: the remaining nodes, as they were
        node = matches(_node_keys(self.region, self.pairs), _node_keys(fem.region, self._new_pairs(fem)), tol)
        if np.any(node < 0):
            raise CaseError("zone.grow = true: the grown far field is not a part of the old one (a mesh line "
                            "off the particle spacing)")
        s, old = fem.state, self.fem_state
        s.u[:], s.v[:], s.a[:] = self.u[node], self.v[node], 0.0
        s.t, s.step = self.t, int(old["step"])
        fem.ledger = type(fem.ledger)(**{k: float(v) for k, v in old["ledger"].items()})
        fem._u_at_forces, fem._t_at_forces, fem._dt = s.u.copy(), s.t, float(old["_dt"])
        if np.shape(old["_reaction_prev"]) == np.shape(fem._reaction_prev):  # the same supported DOFs
            fem._reaction_prev = np.array(old["_reaction_prev"])
        self._carry_node_bonds(fem, node)
        # particles: the old ones as they are; the new and the formerly slaved at the FEM's field
        was = matches(self.X, scene.x, tol)
        x, v = scene.x.copy(), np.zeros_like(scene.x)
        kept = was >= 0
        x[kept], v[kept] = self.x[was[kept]], self.vel[was[kept]]
        converted = ~kept | (kept & self.slaved[np.maximum(was, 0)])
        if self.engine is not None:  # seeded: those still slaved take the new tie's velocities
            converted[itf.ids] = False
        ids = np.flatnonzero(converted)
        W = TransitionInterface.build(self.region, scene.x, ids).W
        dim = self.region.dim
        x[ids, :dim] = scene.x[ids, :dim] + W @ self.u
        v[ids, :dim] = W @ self.v
        # the symmetry planes (x = 0; in 3D also y = 0) hold their normal component from the
        # engine's start (coupled_simulation's hold): none there, and none given there below
        on_plane = (np.abs(scene.x[:, : dim - 1]) < tol) & self.symmetric  # (n, planes)
        v[:, : dim - 1][on_plane] = 0.0
        self._carry_models(models, was, x)
        # momentum: the converted (now free) particles take up what the new split of the mass changed
        free = np.ones(scene.n, bool)
        free[itf.ids] = False
        P = np.zeros(3)
        P[:dim] = fem.m @ s.v
        P += scene.mass[free] @ v[free] + sum((m.momentum() for m in models), np.zeros(3))
        held = np.column_stack([on_plane, np.zeros(scene.n, bool)])  # (n, dim): the planes' normals
        for c in range(dim):  # per component, over the particles free in it
            shifted = converted & free & ~held[:, c]
            if shifted.any():
                v[shifted, c] += (self.momentum[c] - P[c]) / scene.mass[shifted].sum()
        if self.engine is not None:  # seeded: released where the FEM carried them (x: to round-off)
            self.engine.release(np.setdiff1d(np.flatnonzero(self.slaved), itf.ids))
            self.engine.set_all_velocities(v)
            self.engine_start = None
            return None
        self.engine_start = (x, v)
        return replace(scene, x=x, velocity=v)

    def _new_pairs(self, fem):
        bonds = [m for m in fem.node_forces if hasattr(m, "bonds")]
        return bonds[0].bonds.pairs if bonds else None

    def _carry_node_bonds(self, fem, node: np.ndarray) -> None:
        """The cohesive far field's node pairs that remain keep their state."""
        new = [m for m in fem.node_forces if hasattr(m, "bonds")]
        old = [m for m in self.old.dyn.node_forces if hasattr(m, "bonds")]
        if not new or not old:
            return
        rows = _bond_map(old[0].bonds.pairs, new[0].bonds.pairs, node)
        _carry_bonds(new[0].bonds, old[0].bonds, rows)
        new[0].last = old[0].last

    def _carry_models(self, models, was: np.ndarray, x: np.ndarray) -> None:
        """Law bonds, impactors and particle loads (the same in the same order in both models)."""
        for new, old in zip(models, self.old.models):
            if hasattr(new, "pairs"):
                rows = _bond_map(old.pairs, new.pairs, was)
                _carry_bonds(new, old, rows)
                if hasattr(new.law, "snapback"):
                    new.law.snapback = old.law.snapback
                if old is self.old.inter:
                    self._inter_from_node_pairs(new, rows)
            else:
                self._carry_impactor(new, old, was, x)

    def _inter_from_node_pairs(self, inter, rows: np.ndarray) -> None:
        """Interlaminar bonds new to the particles take the softening state of the cohesive
        node pair at their place (the far field delaminated there): HashinCohesiveLaw.damage_on."""
        bonds = [m.bonds for m in self.old.dyn.node_forces if hasattr(m, "bonds")]
        fresh = np.flatnonzero(rows < 0)
        if not bonds or not fresh.size:
            return
        pairs = bonds[0].pairs
        at = self.region.X[pairs[:, 0]]
        mid = 0.5 * (inter.X[inter.pairs[fresh, 0]] + inter.X[inter.pairs[fresh, 1]])[:, : at.shape[1]]
        src = matches(at, mid, 1e-6 * float(np.ptp(at[:, 0]) + 1e-3))
        hit, src = fresh[src >= 0], src[src >= 0]
        pair = bonds[0]
        # the same point of the softening branch (the same fraction of the way from onset to
        # decohesion), not the same damage: the particle bond is softer than the pair
        inter.damage[hit] = pair.law.damage_on(inter.law, pair.damage[src])
        inter.t_failed[hit] = pair.t_failed[src]
        if len(hit):
            self.softening = f"delaminating (cohesive pairs' damage up to {pair.damage[src].max():.2f})"

    @staticmethod
    def _carry_impactor(new, old, was: np.ndarray, x: np.ndarray) -> None:
        """An impactor's or a particle load's state, its rows (x_prev, f_prev: one per particle
        it acts on) moved to the same particles in the new model."""
        state = old.checkpoint_state()
        if old._x_prev is None and not hasattr(old, "imp"):  # a load not started: its time and work
            new.restore_state(state)
            return
        if old._x_prev is None:  # not started: nothing but its own motion
            new.imp.x, new.imp.v = np.array(state["x"]), np.array(state["v"])
            new.work, new.stored, new.time = old.work, old.stored, old.time
            return
        src = was[new.ids]
        rank = np.full(int(max(old.ids.max(), src.max(initial=0))) + 1, -1)
        rank[old.ids] = np.arange(len(old.ids))
        row = np.where(src >= 0, rank[np.maximum(src, 0)], -1)
        x_prev, f_prev = x[new.ids].copy(), np.zeros((len(new.ids), 3))
        x_prev[row >= 0] = np.asarray(state["x_prev"])[row[row >= 0]]
        f_prev[row >= 0] = np.asarray(state["f_prev"])[row[row >= 0]]
        new.restore_state(dict(state, x_prev=x_prev, f_prev=f_prev))
