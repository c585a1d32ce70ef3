"""What the two LAMMPS-family adapters (LIGGGHTS in-process, LAMMPS in its worker) share:
the interface data on zero-copy views of x, v, f and a store/force fix.

Both engines step with velocity Verlet and the coupling hook runs after the step's force
evaluation and final half kick, so an added force goes into f (the next first half kick uses
it) plus its missing final half kick dt/2 f/m into v: velocity Verlet with the force included.
Held particles (``fix setforce``) report the force before the setforce (store/force) plus what
was added; partial prescriptions (a symmetry plane) hold only some components.
Needs: X, V, F, _store, _added (n, 3); mass (n,); prescribed ids; _partial {id: components};
scene; dt; name; _cmd(text), _group(name, ids); _setup_needed; _state() (the per-atom
arrays a checkpoint saves) and _after_setup() (refresh views after a setup run).

Checkpoints save those arrays (positions, velocities, forces, spins, torques, the stored
forces), not the engine's restart file: a restart file does not carry the fixes, so the
scene is rebuilt from its description on resume and the arrays are written back after a
setup run at the restored positions. Contact history (the tangential springs of touching
unbonded particles) is not in them, so checkpoints of Hertz contact scenes are refused.
"""
from __future__ import annotations

import os

import numpy as np


class VerletArrays:
    hertz_scenes = True  # the adapter builds Hertz contact scenes

    def critical_dt(self) -> float:
        return self.scene.critical_dt()

    def set_dt(self, dt: float) -> None:
        self.dt = float(dt)
        self._cmd(f"timestep {self.dt:.17g}")

    def _unsupported(self, scene) -> str | None:
        """What of ``scene`` this adapter cannot build (refused as bad input), or None."""
        if scene.contact != "linear" and not self.hertz_scenes:
            return "Hertz contact scenes"
        if np.isfinite(scene.bond_strength).any():
            return "native bond breakage"
        if scene.local_damping:
            return "Cundall damping (virtual calibration tests)"
        if scene.walls:
            return "walls"
        return None

    # -- checkpoint ----------------------------------------------------------------------------
    restart_file = "dem.npz"

    def checkpoint(self, path) -> None:
        """Save the per-atom state atomically (a kill mid-write leaves the last one intact)."""
        if self.scene.contact == "hertz_mindlin":
            raise NotImplementedError(f"{self.name} adapter: checkpoints of Hertz contact scenes (contact history)")
        tmp = f"{path}.tmp.npz"
        np.savez(tmp, store=self._store, **self._state())
        os.replace(tmp, path)

    def restore(self, path) -> None:
        """Write a checkpoint back: positions, a setup run there (neighbour lists; it also
        recomputes the forces), then the saved velocities, forces, spins and stored forces,
        so the next step starts from exactly the saved state."""
        saved = np.load(path)
        self._state()["x"][:] = saved["x"]
        self._cmd("run 0 post no")
        self._after_setup()
        for name, view in self._state().items():
            view[:] = saved[name]
        self._store[:] = saved["store"]
        self._setup_needed = False

    def _group(self, name: str, ids: np.ndarray) -> None:
        ids = np.asarray(ids, int) + 1
        for chunk in np.array_split(ids, max(1, len(ids) // 500)):  # keep command lines short
            self._cmd(f"group {name} id {' '.join(map(str, chunk.tolist()))}")

    def prescribe(self, ids: np.ndarray, dofs: str = "xyz") -> None:
        ids = np.asarray(ids, int)
        self._setup_needed = True  # fixes added after a run need a setup
        if dofs != "xyz":  # only these components are driven (e.g. a symmetry plane)
            k = len(self._partial)
            self._group(f"part{k}", ids)
            comps = " ".join("0.0" if c in dofs else "NULL" for c in "xyz")
            self._cmd(f"fix part{k} part{k} setforce {comps}")
            for i in ids.tolist():
                self._partial[i] = ["xyz".index(c) for c in dofs]
            return
        if len(self.prescribed):
            raise NotImplementedError(f"{self.name} adapter: one fully prescribed set (the interface) per scene")
        self.prescribed = ids
        self._group("iface", ids)
        self._cmd("fix hold iface setforce 0 0 0")

    def set_velocities(self, ids: np.ndarray, v: np.ndarray) -> None:
        ids, v = np.asarray(ids, int), np.asarray(v, float).reshape(-1, 3)
        if not (self._partial and np.isin(ids, list(self._partial)).any()):
            self.V[ids] = v
            return
        for row, i in enumerate(ids.tolist()):
            comps = self._partial.get(i)
            if comps is None:
                self.V[i] = v[row]
            else:
                self.V[i, comps] = v[row, comps]

    def add_forces(self, ids: np.ndarray, F: np.ndarray) -> None:
        """Forces F (k, 3) N added to particles ``ids`` at this step (call from the hook)."""
        ids, F = np.asarray(ids, int), np.asarray(F, float).reshape(-1, 3)
        np.add.at(self._added, ids, F)
        # held: the interface (written velocities) and the fixed group (clamps) take no motion
        held = np.isin(ids, self.prescribed) | np.isin(ids, self.scene.groups.get("fixed", np.zeros(0, int)))
        free, Ff = ids[~held], F[~held].copy()
        if self.scene.plane:
            Ff[:, 2] = 0.0
        for i in set(free.tolist()) & self._partial.keys():
            Ff[np.ix_(free == i, self._partial[i])] = 0.0  # driven components take no force
        np.add.at(self.F, free, Ff)
        np.add.at(self.V, free, 0.5 * self.dt * Ff / self.mass[free, None])

    def forces(self, ids: np.ndarray) -> np.ndarray:
        """(k, 3) N: the engine's force before any setforce, plus what was added this step."""
        ids = np.asarray(ids, int)
        return self._store[ids] + self._added[ids]

    def positions_of(self, ids: np.ndarray) -> np.ndarray:
        return self.X[np.asarray(ids, int)].copy()

    def positions(self) -> np.ndarray:
        return self.X.copy()

    def velocities(self) -> np.ndarray:
        """Leapfrog half-step velocities v_{k-1/2} = v_k - dt/2 f_k / m (held particles: as written)."""
        v = self.V - 0.5 * self.dt * self.F / self.mass[:, None]
        v[self.prescribed] = self.V[self.prescribed]
        return v

    def _free_mass_velocity(self) -> tuple[np.ndarray, np.ndarray]:
        """(masses with held and fixed particles zeroed, velocities with driven components
        zeroed): what the kinetic energy of the DEM side counts."""
        m = self.mass.copy()
        m[self.prescribed] = 0.0
        m[self.scene.groups.get("fixed", np.zeros(0, int))] = 0.0
        V = self.V.copy()
        for i, comps in self._partial.items():
            V[i, comps] = 0.0
        return m, V

    def _bond_energy(self) -> float:
        """J, harmonic bonds K (r - r0)^2."""
        if not len(self.scene.bonds):
            return 0.0
        i, j = self.scene.bonds.T
        r = np.linalg.norm(self.X[i] - self.X[j], axis=1)
        return float(np.sum(self._bond_K * (r - self._bond_r0) ** 2))
