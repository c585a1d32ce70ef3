"""Tie schemes across the transition interface: how interface particles follow the FEM.

A tie has three duties inside the coupled step (coupling/participants/clock.py calls them at every DEM
step, after the engine computed its forces and before it moves): ``fast_force`` returns the
nodal force (n_nodes, dim) N the DEM exerts on the FEM through the tie at this instant
(given the nodes' positions (n_nodes, dim) m where the tie ``reads_nodes``, else None);
``follow`` runs after the FEM drift and tells the engine how the interface particles move
next; ``energy`` is what the tie stores (J). ``node_mass`` is the particle mass the tie
adds to the FEM nodes, and ``critical_dt`` the step limit the tie itself imposes.

Schemes: KinematicTie (default; interface particles slaved, x_p = sum N_a x_a, their
masses shared to the nodes) and PenaltyTie (the seed paper's node-to-face transition
contact: free interface particles held to their host points by springs of stiffness k).
An overlapping (bridging / Arlequin) scheme would be a third class with the same duties.
"""
from __future__ import annotations

import numpy as np

from .transition import TransitionInterface


class KinematicTie:
    """Interface particles slaved to the FEM: forces returned by the transpose map."""

    name = "kinematic"
    reads_nodes = False  # fast_force needs no nodal positions (the clock passes None)

    def __init__(self, interface: TransitionInterface, dem, particle_mass: np.ndarray, seeded: int = 0):
        self.itf, self.dem = interface, dem
        self.seeded = seeded  # the interface's last rows: a growing zone's reserve (coupling/study/seeded.py)
        self.node_mass = interface.share_mass(particle_mass[interface.ids])
        self._F = np.zeros((len(interface.ids), 3))  # the interface particles' forces, each step
        dem.prescribe(interface.ids)

    def critical_dt(self, fem_mass: np.ndarray) -> float:
        return np.inf

    def fast_force(self, x_nodes: np.ndarray) -> np.ndarray:
        self.dem.forces_into(self.itf.ids, self._F)  # into this tie's buffer: nothing allocated per step
        return self.itf.to_nodes(self._F)

    def follow(self, v_nodes: np.ndarray) -> None:
        self.dem.set_velocities(self.itf.ids, self.itf.to_particles(v_nodes))

    def energy(self) -> float:
        return 0.0

    def free_particles(self, n: int) -> np.ndarray:
        """(n,) weights of particles whose momentum the DEM side carries (0 for slaved ones)."""
        w = np.ones(n)
        w[self.itf.ids] = 0.0
        return w


class PenaltyTie:
    """Free interface particles held to their FEM host points x_h = sum N_a x_a by springs:
    F_p = k (x_h - x_p) on the particle, the opposite force back to the nodes by the transpose map."""

    name = "penalty"
    seeded = 0
    reads_nodes = True  # fast_force stretches its springs to the nodes' positions

    def __init__(self, interface: TransitionInterface, dem, particle_mass: np.ndarray, stiffness: float):
        self.itf, self.dem, self.k = interface, dem, float(stiffness)
        self.m_p = particle_mass[interface.ids]
        self.node_mass = np.zeros(interface.W.shape[1])
        k = len(interface.ids)
        # each step's arrays: the particles' positions, the springs' stretch and force
        self._x_p, self._stretch, self._F = np.zeros((k, 3)), np.zeros((k, 3)), np.zeros((k, 3))
        # an engine's in-place read (LIGGGHTS, LAMMPS, YADE in process); a worker's answers by message
        self._read = getattr(dem, "positions_into", None)

    def critical_dt(self, fem_mass: np.ndarray) -> float:
        """Gershgorin bound of the tie springs alone, particle against its lightest host node."""
        host_min = np.array([fem_mass[row.indices].min() for row in self.itf.W])
        w2 = self.k * (1.0 / self.m_p + np.asarray(np.abs(self.itf.W).sum(axis=1)).ravel() / host_min)
        return 2.0 / np.sqrt(w2.max())

    def fast_force(self, x_nodes: np.ndarray) -> np.ndarray:
        ids = self.itf.ids
        if self._read is not None:
            self._read(ids, self._x_p)
        else:
            self._x_p[:] = self.dem.positions_of(ids)
        np.subtract(self.itf.to_particles(x_nodes), self._x_p, out=self._stretch)
        np.multiply(self._stretch, self.k, out=self._F)
        self.dem.add_forces(ids, self._F)
        f = self.itf.to_nodes(self._F)  # the interface's buffer, turned into the reaction on the nodes
        return np.negative(f, out=f)

    def follow(self, v_nodes: np.ndarray) -> None:
        pass

    def energy(self) -> float:
        return 0.5 * self.k * float(np.sum(self._stretch**2))

    def free_particles(self, n: int) -> np.ndarray:
        return np.ones(n)
