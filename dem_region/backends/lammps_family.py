"""What the two LAMMPS-family adapters (LIGGGHTS in-process, LAMMPS in its worker) share:
the interface data on zero-copy views of x, v, f and a store/force fix.

Both engines step with velocity Verlet and the coupling hook runs after the step's force
evaluation and final half kick, so an added force goes into f (the next first half kick uses
it) plus its missing final half kick dt/2 f/m into v: velocity Verlet with the force included.
Held particles (``fix setforce``) report the force before the setforce (store/force) plus what
was added; partial prescriptions (a symmetry plane) hold only some components.
Needs: X, V, F, _store, _added (n, 3); mass (n,); prescribed ids; _driven (n, 3) bool (the
components partial prescriptions hold) and _n_partial (how many there are);
scene; dt; name; _cmd(text), _group(name, ids); _setup_needed; _state() (the per-atom
arrays a checkpoint saves) and _after_setup() (refresh views after a setup run).

What neither engine has natively is done here on the same arrays, as added forces (velocity
Verlet with the force included): brittle bonds (a bond of finite ``bond_strength`` is a
harmonic spring evaluated in numpy, the engine carries a placeholder of zero stiffness; it
breaks when its tensile force reaches the strength, as YADE's fragile CohFrictPhys, and a
broken pair keeps only a compression spring so it cannot interpenetrate) and Cundall's local
non-viscous damping for the quasi-static virtual tests (f_d = -alpha |f| sign(v) per
component on the total force, YADE's NewtonIntegrator damping). Call ``_hook_phase(between)``
after every engine step.

Checkpoints save those arrays (positions, velocities, forces, spins, torques, the stored
forces), not the engine's restart file: a restart file does not carry the fixes, so the
scene is rebuilt from its description on resume and the arrays are written back after a
setup run at the restored positions. Contact history (the tangential springs of touching
unbonded particles) is not in them, so checkpoints of Hertz contact scenes are refused.
"""
from __future__ import annotations

import os

import numpy as np

from ..kernels import add_held_forces, free_kinetic_energy, gather_forces, put_components, spring_energy, take_rows


class VerletArrays:
    two_sided_walls = True  # a wall of sense 0 acts on both sides
    _writes_files = True  # False on the MPI ranks other than 0 (they hold the same state)

    def critical_dt(self) -> float:
        return self.scene.critical_dt()

    def set_dt(self, dt: float) -> None:
        self.dt = float(dt)
        self._cmd(f"timestep {self.dt:.17g}")

    def _unsupported(self, scene) -> str | None:
        """What of ``scene`` this adapter cannot build (refused as bad input), or None."""
        if not self.two_sided_walls and any(w.sense == 0 for w in scene.walls):
            return "two-sided walls (sense 0)"
        if scene.walls and scene.contact != "hertz_mindlin":
            return "walls in bonded scenes"
        return None

    def _to_engine(self, state: dict | None = None, names=("v", "f")) -> None:
        """Copy arrays written here back into the engine: nothing to do for zero-copy views."""

    def _bond_types(self, scene) -> tuple[np.ndarray, np.ndarray]:
        """(types (t, 2): the engine's kn N/m and rest length m, type of each bond (nb,)). Bonds
        share a type when kn and r0 agree to 13 significant digits; a type's values are the
        means over its bonds, so each bond's rest length is exact to round-off (rounding r0 to
        1e-12 m had left 2e-7 of the bond force on the free particles of a uniformly strained
        lattice)."""
        if not len(scene.bonds):
            return np.zeros((0, 2)), np.zeros(0, int)
        i, j = scene.bonds.T
        values = np.column_stack([self._engine_kn(scene), np.linalg.norm(scene.x[j] - scene.x[i], axis=1)])
        _, btype = np.unique(_significant(values, 13), axis=0, return_inverse=True)
        btype = np.asarray(btype).ravel()
        count = np.bincount(btype)
        types = np.column_stack([np.bincount(btype, values[:, k]) / count for k in (0, 1)])
        return types, btype

    # -- what the engines lack, on their arrays -----------------------------------------------------
    def _engine_kn(self, scene) -> np.ndarray:
        """(nb,) N/m, the engine's harmonic stiffness: breakable bonds are carried here (0 there)."""
        return np.where(np.isfinite(scene.bond_strength), 0.0, scene.kn)

    def _init_extras(self, scene) -> None:
        """State of the brittle bonds and the damping; call at the end of build."""
        self._brittle = np.flatnonzero(np.isfinite(scene.bond_strength))
        b = scene.bonds[self._brittle]
        self._brittle_r0 = np.linalg.norm(scene.x[b[:, 1]] - scene.x[b[:, 0]], axis=1)
        self._brittle_ids = np.concatenate([b[:, 0], b[:, 1]])  # their forces' rows, one array: its plan is kept
        self._brittle_alive = np.ones(len(self._brittle), bool)
        self._broken: list[tuple] = []  # (i, j, t s, x, y, z m)
        self._released = 0.0  # J, elastic energy of the bonds at the moment they broke
        self._time = 0.0
        self._damping = float(scene.local_damping)
        # Hertz contact damping is booked here (neither engine reports it)
        self._track_damping = not len(scene.bonds) and scene.restitution < 1.0
        self._dissipated, self._fd_prev = 0.0, np.zeros((scene.n, 3))

    def _step_begin(self) -> np.ndarray | None:
        """Call before an engine step: clears the added forces; positions for the damping book."""
        self._added[:] = 0.0
        return self.X.copy() if self._track_damping else None

    def _step_end(self, x_old: np.ndarray | None) -> None:
        """Call after an engine step (before ``_hook_phase``)."""
        self._time += self.dt
        if x_old is not None:
            self._book_damping(x_old)

    def _hook_phase(self, between) -> None:
        """After an engine step: brittle bond forces, the orchestrator's hook, then damping on
        the total force."""
        if len(self._brittle):
            self._brittle_forces()
        if between is not None:
            between()
        if self._damping:
            self._cundall()

    def _brittle_stretch(self):
        i, j = self.scene.bonds[self._brittle].T
        d = self.X[j] - self.X[i]
        r = np.linalg.norm(d, axis=1)
        return i, j, d, r, r - self._brittle_r0

    def _brittle_forces(self) -> None:
        i, j, d, r, s = self._brittle_stretch()
        kn = self.scene.kn[self._brittle]
        f = kn * s  # N, tension positive
        newly = self._brittle_alive & (f >= self.scene.bond_strength[self._brittle])
        if newly.any():
            self._released += float(np.sum(0.5 * kn[newly] * s[newly] ** 2))
            self._brittle_alive &= ~newly
            mid = 0.5 * (self.X[i[newly]] + self.X[j[newly]])
            self._broken += [(int(a), int(b), self._time, *m) for a, b, m in zip(i[newly], j[newly], mid.tolist())]
        f = np.where(self._brittle_alive, f, np.minimum(f, 0.0))  # broken: contact in compression only
        Fj = -(f / r)[:, None] * d
        self.add_forces(self._brittle_ids, np.concatenate([-Fj, Fj]))

    def _cundall(self) -> None:
        f_d = -self._damping * np.abs(self.F) * np.sign(self.V)
        self.F += f_d
        self.V += 0.5 * self.dt * f_d / self.mass[:, None]

    def _brittle_energy(self) -> float:
        """J, stored in the brittle bonds (broken ones: only while compressed)."""
        if not len(self._brittle):
            return 0.0
        s = self._brittle_stretch()[4]
        s = np.where(self._brittle_alive, s, np.minimum(s, 0.0))
        return float(np.sum(0.5 * self.scene.kn[self._brittle] * s**2))

    # -- Hertz contacts: elastic part and damping ---------------------------------------------------
    def wall_material(self) -> tuple[float, float]:
        """(E Pa, nu) of the rigid walls: 10^6 x the stiffest particle, as the YADE adapter."""
        return 1e6 * float(self.scene.young.max()), float(self.scene.poisson[0])

    def _hertz(self):
        """(ids (p, 2) with -1 for a wall, elastic Hertz force on the first of each pair (p, 3),
        energy J) of the touching unbonded pairs and particle-wall contacts (R* = R on a plane)."""
        from scipy.spatial import cKDTree
        R, X, E, nu = self.scene.radius, self.X, self.scene.young, self.scene.poisson
        pairs = np.array(sorted(cKDTree(X).query_pairs(2 * R.max())), dtype=int).reshape(-1, 2)
        a, b = pairs.T
        d = X[a] - X[b]
        dist = np.linalg.norm(d, axis=1)
        delta = np.maximum(R[a] + R[b] - dist, 0.0)
        Es = 1.0 / ((1 - nu[a] ** 2) / E[a] + (1 - nu[b] ** 2) / E[b])
        Rs = R[a] * R[b] / (R[a] + R[b])
        n = d / np.where(dist > 0, dist, 1.0)[:, None]
        ids, normals, deltas, Ess, Rss = [pairs], [n], [delta], [Es], [Rs]
        Ew, nuw = self.wall_material()
        for w in self.scene.walls:
            s = X[:, w.axis] - w.position
            touch = np.flatnonzero(np.abs(s) < R)
            nw = np.zeros((len(touch), 3))
            nw[:, w.axis] = np.sign(s[touch])
            ids.append(np.column_stack([touch, np.full(len(touch), -1)]))
            normals.append(nw)
            deltas.append(R[touch] - np.abs(s[touch]))
            Ess.append(1.0 / ((1 - nu[touch] ** 2) / E[touch] + (1 - nuw**2) / Ew))
            Rss.append(R[touch])
        ids, n, delta, Es, Rs = (np.concatenate(v) for v in (ids, normals, deltas, Ess, Rss))
        f = (4.0 / 3.0) * Es * np.sqrt(Rs) * delta**1.5
        energy = float(np.sum((8.0 / 15.0) * Es * np.sqrt(Rs) * delta**2.5))
        return ids.reshape(-1, 2), f[:, None] * n, energy

    def _book_damping(self, x_old: np.ndarray) -> None:
        """Work of the contact damping over the last step: total force minus the elastic Hertz
        force, trapezoidal in time."""
        pairs, f_el, _ = self._hertz()
        F_el = np.zeros_like(self.X)
        np.add.at(F_el, pairs[:, 0], f_el)
        other = pairs[:, 1] >= 0  # walls take no force here
        np.add.at(F_el, pairs[other, 1], -f_el[other])
        f_d = self.F - F_el
        f_d[self.scene.groups.get("fixed", np.zeros(0, int))] = 0.0
        self._dissipated -= float(np.sum(0.5 * (f_d + self._fd_prev) * (self.X - x_old)))
        self._fd_prev = f_d

    def energies(self) -> dict[str, float]:
        """{kinetic (translation + rotation of the free particles), elastic (bonds, or Hertz
        contacts (8/15) E* sqrt(R*) delta^(5/2)), dissipated (contact damping, broken bonds)} J."""
        kinetic = free_kinetic_energy(self.mass, self.scene.radius, self.V, self._omega(), self._held_mask(),
                                      self._driven)
        elastic = self._bond_energy() if len(self.scene.bonds) else self._hertz()[2]
        return {"kinetic": kinetic, "elastic": elastic, "dissipated": self._dissipated + self._released}

    def bond_state(self) -> dict:
        """{intact, broken, broken_list}: rows (i, j, t s, x, y, z m) of the bonds broken so far."""
        return {"intact": len(self.scene.bonds) - len(self._broken), "broken": len(self._broken),
                "broken_list": list(self._broken)}

    # -- checkpoint ----------------------------------------------------------------------------
    restart_file = "dem.npz"

    @property
    def supports_checkpoint(self) -> bool:
        """False for Hertz contact scenes: their contact history is not saved (yet)."""
        return self.scene.contact != "hertz_mindlin"

    def checkpoint(self, path) -> None:
        """Save the per-atom state atomically (a kill mid-write leaves the last one intact)."""
        if self.scene.contact == "hertz_mindlin":
            raise NotImplementedError(f"{self.name} adapter: checkpoints of Hertz contact scenes (contact history)")
        state = self._state()  # (on several ranks a collective call: every rank makes it)
        if not self._writes_files:
            return
        tmp = f"{path}.tmp.npz"
        np.savez(tmp, store=self._store, brittle_alive=self._brittle_alive, released=self._released,
                 time=self._time, broken=np.array(self._broken, float).reshape(-1, 6), **state)
        os.replace(tmp, path)

    def restore(self, path) -> None:
        """Write a checkpoint back: positions, a setup run there (neighbour lists; it also
        recomputes the forces), then the saved velocities, forces, spins and stored forces,
        so the next step starts from exactly the saved state."""
        saved = np.load(path)
        state = self._state()
        state["x"][:] = saved["x"]
        self._to_engine(state, ("x",))
        self._cmd("run 0 post no")
        self._after_setup()
        state = self._state()
        for name, view in state.items():
            view[:] = saved[name]
        self._to_engine(state, tuple(state))
        self._store[:] = saved["store"]
        self._brittle_alive[:] = saved["brittle_alive"]
        self._released, self._time = float(saved["released"]), float(saved["time"])
        self._broken = [(int(a), int(b), *rest) for a, b, *rest in saved["broken"].tolist()]
        self._setup_needed = False

    def _setup_keeping_added(self) -> None:
        """A setup run for the fixes added since the last run (a prescription, a release: call
        before ``_step_begin``). A setup recomputes the engine's own forces, which would drop
        the forces the hook added after the last step from the next step's first half kick
        (one half kick of every law, tie and impactor force lost: a grown zone's engine, started
        with its bonds strained, read a disc's deflection 1.8 % off the other engines'); they
        are put back on the components that move now."""
        added = self._added.copy()
        self._to_engine()
        self._cmd("run 0 post no")
        self._after_setup()
        takes = np.repeat(~self._held_mask()[:, None], 3, axis=1)
        if self.scene.plane:
            takes[:, 2] = False
        if self._n_partial:
            takes &= ~self._driven
        self.F[takes] += added[takes]
        self._setup_needed = False

    def _group(self, name: str, ids: np.ndarray) -> None:
        ids = np.asarray(ids, int) + 1
        for chunk in np.array_split(ids, max(1, len(ids) // 500)):  # keep command lines short
            self._cmd(f"group {name} id {' '.join(map(str, chunk.tolist()))}")

    def prescribe(self, ids: np.ndarray, dofs: str = "xyz") -> None:
        ids = np.asarray(ids, int)
        self._setup_needed = True  # fixes added after a run need a setup
        if dofs != "xyz":  # only these components are driven (e.g. a symmetry plane)
            k, self._n_partial = self._n_partial, self._n_partial + 1
            self._group(f"part{k}", ids)
            comps = " ".join("0.0" if c in dofs else "NULL" for c in "xyz")
            self._cmd(f"fix part{k} part{k} setforce {comps}")
            self._driven[np.ix_(ids, ["xyz".index(c) for c in dofs])] = True
            return
        first = not len(self.prescribed)
        self.prescribed = ids if first else np.union1d(self.prescribed, ids)  # (the interface, a floor)
        self._group("iface", ids)  # (a group named again gains the atoms)
        if first:
            self._cmd("fix hold iface setforce 0 0 0")

    def release(self, ids: np.ndarray) -> None:
        """Particles ``ids`` no longer slaved: they move with their forces again (a symmetry
        plane's partial prescription stays). The held group is made again, not a new one beside
        it (LAMMPS holds at most 32 groups; LIGGGHTS has no ``group clear``), its fix after the
        store/force fix as before."""
        held = np.setdiff1d(self.prescribed, np.asarray(ids, int))
        if len(held) == len(self.prescribed):  # none of them held
            return
        self._setup_needed = True
        self._cmd("unfix hold\ngroup iface delete")
        self.prescribed = np.zeros(0, int)
        if len(held):
            self.prescribe(held)

    def set_all_velocities(self, v: np.ndarray) -> None:
        """Every particle's velocity (n, 3) m/s as ``velocities()`` reports it (v_{k-1/2}), written
        whole, held components too: a model continued on this engine starts from it as a new
        engine built with these velocities would."""
        self.V[:] = np.asarray(v, float).reshape(-1, 3)

    def set_velocities(self, ids: np.ndarray, v: np.ndarray) -> None:
        """Velocities v (k, 3) m/s of particles ``ids``; of a partially prescribed particle
        only its driven components. The plan (which components of which rows) once per ids
        array (the interface's, each step) and prescription; the write compiled."""
        v = np.ascontiguousarray(v, float).reshape(-1, 3)
        if (ids is not getattr(self, "_vel_ids", None) or self._n_partial != self._vel_partial
                or self.prescribed is not self._vel_prescribed):
            rows = np.asarray(ids, int)
            driven = self._driven[rows]
            # a fully prescribed particle's velocity is written whole, on a symmetry plane too
            # (a seeded particle, slaved until its release leaves the plane's hold)
            whole = ~driven.any(axis=1, keepdims=True) | self._held_mask()[rows][:, None]
            at = np.nonzero(driven | whole)
            self._vel_plan = tuple(np.ascontiguousarray(a, np.int64) for a in (rows[at[0]], at[1], at[0]))
            # (ids held: its identity stays its own)
            self._vel_ids, self._vel_partial, self._vel_prescribed = ids, self._n_partial, self.prescribed
        put_components(self.V, *self._vel_plan, v)

    bulk_arrays = True  # positions read and forces written on the engine's arrays (ModelStep)

    def add_forces(self, ids: np.ndarray, F: np.ndarray) -> None:
        """Forces F (k, 3) N added to particles ``ids`` at this step (call from the hook). The
        plan (which components of which rows take motion) is built once per ids array and kept
        per array: the models' and a penalty tie's write in turn at every step."""
        F = np.ascontiguousarray(F, float).reshape(-1, 3)
        held = self._held_mask()
        plans = self.__dict__.setdefault("_plans", {})
        known = plans.get(id(ids))  # (ids, dt, held, partial count, plan)
        # a new set, step or prescription: a new plan
        if known is None or known[0] is not ids or known[1] != self.dt or known[2] is not held \
                or known[3] != self._n_partial:
            plans.pop(id(ids), None)
            if len(plans) >= 8:  # (sets come and go with rebuilt models: keep the few made last)
                plans.pop(next(iter(plans)))
            known = plans[id(ids)] = ids, self.dt, held, self._n_partial, self._force_plan(np.asarray(ids, int))
        rows, takes, mass = known[4]
        add_held_forces(self._added, self.F, self.V, rows, F, takes, 0.5 * self.dt, mass)

    def _force_plan(self, ids: np.ndarray):
        """(rows (k,), takes (k, 3) bool: the components that move, their masses (k,) kg)."""
        # held: the interface (written velocities) and the fixed group (clamps) take no motion
        takes = np.repeat(~self._held_mask()[ids][:, None], 3, axis=1)
        if self.scene.plane:
            takes[:, 2] = False
        if self._n_partial:
            takes &= ~self._driven[ids]  # driven components take no force
        return np.ascontiguousarray(ids, np.int64), takes, np.ascontiguousarray(self.mass[ids], float)

    def read_positions(self, ids: np.ndarray, out: np.ndarray) -> None:
        """out (k, 3) m <- the positions of particles ``ids`` (one bulk copy)."""
        take_rows(out, self.X, ids)

    positions_into = read_positions  # (the penalty tie's read of its particles, each step)

    def _held_mask(self) -> np.ndarray:
        """(n,) bool: the fully prescribed set and the fixed group (rebuilt when the set changes)."""
        if getattr(self, "_held_for", None) is not self.prescribed:
            held = np.zeros(len(self.mass), bool)
            held[self.prescribed] = True
            held[self.scene.groups.get("fixed", np.zeros(0, int))] = True
            self._held, self._held_for = held, self.prescribed
        return self._held

    def forces(self, ids: np.ndarray) -> np.ndarray:
        """(k, 3) N: the engine's force before any setforce, plus what was added this step."""
        ids = np.asarray(ids, np.int64)
        out = np.empty((len(ids), 3))
        gather_forces(out, self._store, self._added, ids)
        return out

    def forces_into(self, ids: np.ndarray, out: np.ndarray) -> None:
        """``forces(ids)`` into out (k, 3) N (the interface's each step: nothing allocated)."""
        gather_forces(out, self._store, self._added, ids)

    def positions_of(self, ids: np.ndarray) -> np.ndarray:
        return self.X[np.asarray(ids, int)].copy()

    def positions(self) -> np.ndarray:
        return self.X.copy()

    def velocities(self) -> np.ndarray:
        """Leapfrog half-step velocities v_{k-1/2} = v_k - dt/2 f_k / m (held particles: as written)."""
        v = self.V - 0.5 * self.dt * self.F / self.mass[:, None]
        v[self.prescribed] = self.V[self.prescribed]
        return v

    def _bond_energy(self) -> float:
        """J, harmonic bonds K (r - r0)^2 and the brittle bonds carried here."""
        if not len(self.scene.bonds):
            return 0.0
        if getattr(self, "_bond_rows", None) is None:
            self._bond_rows = np.ascontiguousarray(self.scene.bonds, np.int64)
        return spring_energy(self.X, self._bond_rows, self._bond_K, self._bond_r0) + self._brittle_energy()


def _significant(a: np.ndarray, digits: int) -> np.ndarray:
    """a rounded to ``digits`` significant digits (zeros stay zero)."""
    a = np.asarray(a, float)
    mag = 10.0 ** np.floor(np.log10(np.where(a != 0, np.abs(a), 1.0)))
    return np.round(a / mag, digits - 1) * mag
