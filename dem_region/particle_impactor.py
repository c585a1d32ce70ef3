"""A rigid impactor striking engine particles, evaluated by the coupling layer (any engine).

The impactor is fem_region's RigidImpactor (penalty normal force, regularised Coulomb
friction) whose contact radius is inflated by the particle radius, so it touches particle
surfaces. Each engine step (from the coupling hook, forces at x_k) it reads the candidate
particles' positions, adds the contact forces to them and moves itself by the same leapfrog
as the engine: V_{k+1/2} = V_{k-1/2} + dt F_k / M, X_{k+1} = X_k + dt V_{k+1/2}, with the
components in ``fixed`` held (a symmetry plane). Its force is minus the sum of the particle
forces, so momentum is exact; the contact work is summed by the trapezoidal rule on both
bodies' displacements, dissipated = work - stored penalty energy (friction).
"""
from __future__ import annotations

import numpy as np

from physics.impactor import FLAT, RigidImpactor
from physics.kernels import impactor_step


class ParticleImpactor:
    """impactor: a 3D RigidImpactor (sphere: a cylinder's section in a plane scene) whose radius
    is the contact radius for particle centres (impactor radius + particle radius);
    candidates: (k,) ids of the particles it may touch; fixed: (3,) bool, DOFs held at zero
    velocity."""

    def __init__(self, impactor: RigidImpactor, candidates: np.ndarray, fixed=(False, False, False)):
        self.imp = impactor
        self.ids = np.asarray(candidates, int)
        self.free = ~np.asarray(fixed, bool)
        self.imp.v = self.imp.v * self.free
        self.force = np.zeros(3)  # N on the impactor at the last evaluation
        self.work = 0.0
        self.stored = 0.0
        self._x_prev = None  # (k, 3) m positions of the last step (None before the first)
        self._bound = None
        self._f_prev = np.zeros((len(self.ids), 3))
        self._X_prev = self.imp.x.copy()
        self._F_prev = np.zeros(3)
        self._F_now = np.zeros(3)  # the compiled path's force on the impactor, each step
        self._free = self.free.astype(float)  # (3,) 1.0 where the impactor moves
        self.time = 0.0

    def __getstate__(self) -> dict:
        """Pickled unbound (the copy binds to the target it is applied on)."""
        d = dict(self.__dict__)
        d["_bound"] = None
        d.pop("_rows", None)
        return d

    def critical_dt(self, particle_mass: np.ndarray) -> float:
        return self.imp.critical_dt(particle_mass[self.ids])

    def ground_stiffness(self, n: int) -> np.ndarray:
        """(n,) N/m: the penalty spring the impactor can add to each of n particles (its
        candidates), on top of their bonds (the stable step's Gershgorin rows)."""
        g = np.zeros(n)
        g[self.ids] = self.imp.penalty
        return g

    def apply(self, backend, dt: float) -> None:
        """One engine step: contact forces on the candidates, then the impactor's leapfrog. On a
        target with particle arrays (the coupling layer's ModelStep: ``x``, ``f``, ``rows_of``)
        one compiled call on those arrays (kernels.impactor_step: every shape); otherwise through
        copies. At the
        start (dt = 0) of a model that carries a state (a grown zone's: study/growth.py) the last
        forces again, on the same particles at the same positions: the engine's start completes
        the step the old model ended on (evaluated anew, the impactor already moved on touched
        deeper: a disc struck at 100 m/s and grown at 0.37 us gained 2.2 % of its energy)."""
        if dt == 0 and self._x_prev is not None:
            touching = np.flatnonzero(np.any(self._f_prev != 0.0, axis=1))
            if touching.size:
                backend.add_forces(self.ids[touching], self._f_prev[touching])
            self.force = self._F_prev
            return
        if hasattr(backend, "rows_of"):  # (every shape has a compiled contact: kernels.particle_gap)
            if self._bound is not backend:  # bind once: the candidates as rows of the target's arrays
                self._rows = np.ascontiguousarray(backend.rows_of(self.ids), np.int64)
                self._bound = backend
            if self._x_prev is None:
                self._x_prev, self._x_now = np.empty((len(self.ids), 3)), np.empty((len(self.ids), 3))
                self._f_prev, self._f_now = np.zeros((len(self.ids), 3)), np.zeros((len(self.ids), 3))
                started = False
            else:
                started = True
            imp = self.imp
            # the contact, then the impactor's work over its last move, X_prev, F_prev <- this step's
            # and its leapfrog, in place
            flat = imp.shape in FLAT
            pen2, dwork, work = impactor_step(
                backend.x, backend.f, self._rows, self._x_now, self._f_now, self._x_prev, self._f_prev, started, dt,
                imp.x, imp.contact_axis, imp.v, float(imp.radius), flat, float(imp.depth) if flat else 0.0,
                float(imp.rounding), float(imp.penalty), float(imp.friction), float(imp.slip_velocity**2),
                self._F_now, self._X_prev, self._F_prev, float(imp.mass), self._free)
            self.stored = 0.5 * imp.penalty * pen2
            # this step's state becomes the last one (buffers swapped, nothing allocated)
            self._x_prev, self._x_now, self._f_prev, self._f_now = self._x_now, self._x_prev, self._f_now, self._f_prev
            if started:
                self.work += 0.5 * (dwork + work)
            self.force = self._F_prev
            if dt > 0:
                self.time += dt
            return
        else:
            x = backend.positions_of(self.ids)
            v = np.zeros_like(x) if self._x_prev is None or dt == 0 else (x - self._x_prev) / dt
            f, self.stored = self.imp.forces(x, v)
            F = -f.sum(axis=0)
            if self._x_prev is not None:
                self.work += 0.5 * float(np.sum((self._f_prev + f) * (x - self._x_prev))
                                         + (self._F_prev + F) @ (self.imp.x - self._X_prev))
            self._x_prev, self._f_prev, self._X_prev, self._F_prev = x, f, self.imp.x.copy(), F
            touching = np.flatnonzero(np.any(f != 0.0, axis=1))
            if touching.size:
                backend.add_forces(self.ids[touching], f[touching])
        self.force = F
        if dt > 0:  # leapfrog, as the engine moves the particles
            self.imp.v = self.imp.v + dt * F / self.imp.mass * self.free
            self.imp.x = self.imp.x + dt * self.imp.v
            self.time += dt

    def last_positions(self) -> np.ndarray | None:
        """(k, 3) m the candidates' positions at the last evaluation (the engine's positions
        between its steps), None before the first: read without a call to the engine (a worker's
        models are the orchestrator's copies, synced)."""
        return self._x_prev

    def energies(self) -> dict[str, float]:
        """J: kinetic (leapfrog half-step velocity), stored penalty energy, friction loss."""
        return {"kinetic": self.imp.kinetic_energy(), "internal": self.stored, "dissipated": -self.work - self.stored}

    def momentum(self) -> np.ndarray:
        return self.imp.momentum()

    def checkpoint_state(self) -> dict:
        d = {"x": self.imp.x, "v": self.imp.v, "work": self.work, "stored": self.stored, "time": self.time,
             "f_prev": self._f_prev, "X_prev": self._X_prev, "F_prev": self._F_prev}
        if self._x_prev is not None:
            d["x_prev"] = self._x_prev
        return d

    def restore_state(self, d: dict) -> None:
        self.imp.x, self.imp.v = np.array(d["x"]), np.array(d["v"])
        self.work, self.stored, self.time = float(d["work"]), float(d["stored"]), float(d["time"])
        self._f_prev, self._X_prev, self._F_prev = np.array(d["f_prev"]), np.array(d["X_prev"]), np.array(d["F_prev"])
        self._x_prev = np.array(d["x_prev"]) if "x_prev" in d else None
        if self._x_prev is not None:  # the compiled path's spare buffers
            self._x_now, self._f_now = np.empty_like(self._x_prev), np.empty_like(self._f_prev)
