"""The coupled clock step with a kinematic tie (interface particles slaved to the FEM).

Impulse multiple time stepping (r-RESPA, Tuckerman, Berne & Martyna 1992): the FEM's own
forces are "slow" and kick the FEM velocities once per FEM step dt = m dt_dem; the forces the
DEM exerts on the interface are "fast" and kick the FEM nodes at every DEM step by the
transpose map. Both are leapfrog kicks between drifts, so the scheme is symplectic,
conserves momentum exactly for any m, and for m = 1 it is the monolithic central-difference
step of the whole system.

The engine calls ``between`` after it computed the forces at x_k (see the back-end
contract). There, for DEM step k:

   a. interface.forces_to_fem   f_a = sum_p N_a(xi_p) F_p(x_k)               (transpose map)
   b. if k = n m: fem.forces    f_int(u_n), f_ext(t_n) -> a_n; energy snapshot at t_n;
                  fem.slow_kick v += dt a_n
   c. fem.fast_kick             v_a += dt_dem f_a / M_a                        (interface nodes)
   d. fem.drift                 u += dt_dem v                 (prescribed velocities applied)
   e. interface.velocity_to_dem v_p = sum_a N_a v_a                            (consistent map)

and the engine's next move carries the interface particles with v_p, so x_p = sum N_a x_a
holds at every DEM step. Interface particle masses are shared to the nodes by the same weights.
"""
from __future__ import annotations

import time

import numpy as np

from dem_region.backends.base import DemBackend
from fem_region.explicit import ExplicitDynamics
from interfaces.transition import TransitionInterface

from .simulation import Stage


class KinematicTie:
    """Kinematic coupling of one FEM and one DEM participant, m DEM steps per FEM step."""

    def __init__(self, fem: ExplicitDynamics, dem: DemBackend, interface: TransitionInterface,
                 dt_fem: float, substeps: int = 1):
        self.fem, self.dem, self.itf = fem, dem, interface
        self.m, self.dt = int(substeps), dt_fem
        self.dt_dem = dt_fem / self.m
        self.k = 0  # DEM steps whose forces have been handed over
        self.inner = {"fem": 0.0, "interface": 0.0}
        self.snapshot: dict[str, float] = {}
        self.momentum_snapshot = np.zeros(3)
        self.snapshot_every = 1  # FEM steps between energy snapshots (the history interval) ...
        self.last_window = -1  # ... and at this FEM step
        dem.prescribe(interface.ids)
        dem.set_dt(self.dt_dem)
        m = dem.scene.mass.copy()
        m[interface.ids] = 0.0
        self._m_free = m
        dem.start(self._between)

    def _between(self) -> None:
        clock = time.perf_counter
        fem, itf = self.fem, self.itf
        t0 = clock()
        f_itf = self.f_itf = itf.to_nodes(self.dem.forces(itf.ids))
        t1 = clock()
        if self.k % self.m == 0:
            fem.compute_forces()  # the FEM's own forces at t_n (f_coupling stays zero)
            n = self.k // self.m
            if n % self.snapshot_every == 0 or n == self.last_window:
                self._snapshot(f_itf)
            fem.state.v += self.dt * fem.state.a
        fem.state.v += self.dt_dem * f_itf / fem.m[:, None]
        fem.drift(self.dt_dem)
        t2 = clock()
        self.dem.set_velocities(itf.ids, itf.to_particles(fem.state.v))
        self.k += 1
        self.inner["interface"] += (t1 - t0) + (clock() - t2)
        self.inner["fem"] += t2 - t1

    def _snapshot(self, f_itf: np.ndarray) -> None:
        """Energies and momentum at t_n = k dt_dem, all at that time level: the leapfrog
        velocities lag half a step and are completed with the forces at t_n."""
        fem = self.fem
        self.u_snapshot = fem.state.u.copy()  # FEM displacement at t_n (the FEM drifts ahead)
        P = np.zeros(3)
        P[: fem.region.dim] = fem.m @ fem.state.v
        self.momentum_snapshot = P + self._m_free @ self.dem.velocities()
        v_n = self.v_snapshot = fem.state.v + 0.5 * self.dt * fem.state.a + 0.5 * self.dt_dem * f_itf / fem.m[:, None]
        f = fem.energies()
        d = self.dem.energies()
        kin_fem = 0.5 * float(np.einsum("n,ni,ni->", fem.m, v_n, v_n))
        self.snapshot = {"kinetic": kin_fem + d["kinetic"], "internal": f["internal"] + d["elastic"],
                         "external_work": f["external_work"], "dissipated": f["dissipated"] + d["dissipated"]}

    def step(self) -> None:
        """One FEM step = m DEM steps."""
        for _ in range(self.m):
            self.dem.advance(self._between)

    def stages(self) -> list[Stage]:
        return [Stage("dem.step x m (FEM kicks, drift and interface maps in the engine's hook)", "dem", self.step)]

    def energies(self) -> dict[str, float]:
        """Ledger of the coupled system at the last snapshot (the interface work is internal)."""
        return self.snapshot

    def momentum(self) -> np.ndarray:
        """(3,) kg m/s of FEM nodes and free particles at the last snapshot (leapfrog
        half-step velocities, which carry every impulse handed over so far)."""
        return self.momentum_snapshot

    def timing_correction(self) -> dict[str, float]:
        """Move the time spent inside the hook out of the DEM bucket."""
        inner = sum(self.inner.values())
        return {"dem": -inner, **self.inner}
