"""The coupled clock step with a kinematic tie (interface particles slaved to the FEM).

One clock step, in the order that makes it a monolithic central-difference step:

1. DEM engine: forces at x_n (inside ``backend.advance``), then ``between``:
   a. interface.forces_to_fem   f_a = sum_p N_a(xi_p) F_p        (transpose map)
   b. fem.forces                f_int(u_n), f_ext(t_n) + interface force -> a_n
   c. fem.kick                  v_n = v_{n-1/2} + dt/2 a_n        (skipped at n = 0)
   d. fem.kick_drift            v_{n+1/2} = v_n + dt/2 a_n, u_{n+1} = u_n + dt v_{n+1/2}
   e. interface.velocity_to_dem v_p = sum_a N_a v_a               (consistent map)
2. DEM engine: every particle moves to x_{n+1} (interface ones with v_p).

Interface particle masses are shared to the FEM nodes by the same weights.
"""
from __future__ import annotations

import time

from dem_region.backends.base import DemBackend
from fem_region.explicit import ExplicitDynamics
from interfaces.transition import TransitionInterface

from .simulation import Stage


class KinematicTie:
    """Synchronous (one DEM step per FEM step) kinematic coupling of one FEM and one DEM side."""

    def __init__(self, fem: ExplicitDynamics, dem: DemBackend, interface: TransitionInterface, dt: float):
        self.fem, self.dem, self.itf, self.dt = fem, dem, interface, dt
        self.started = False
        self.inner = {"fem": 0.0, "interface": 0.0}
        dem.prescribe(interface.ids)
        dem.set_dt(dt)

    def _between(self) -> None:
        clock = time.perf_counter
        fem, itf, dt = self.fem, self.itf, self.dt
        t0 = clock()
        fem.f_coupling = itf.to_nodes(self.dem.forces(itf.ids))
        t1 = clock()
        fem.compute_forces()
        if self.started:
            fem.kick(dt)
        fem.kick_drift(dt)
        self.started = True
        t2 = clock()
        self.dem.set_velocities(itf.ids, itf.to_particles(fem.state.v))
        t3 = clock()
        self.inner["interface"] += (t1 - t0) + (t3 - t2)
        self.inner["fem"] += t2 - t1

    def stages(self) -> list[Stage]:
        return [Stage("dem.step (with the FEM step inside its coupling hook)", "dem",
                      lambda: self.dem.advance(self._between))]

    def energies(self) -> dict[str, float]:
        """Ledger of the coupled system: the interface work is internal and cancels."""
        f = self.fem.energies()
        d = self.dem.energies()
        return {"kinetic": f["kinetic"] + d["kinetic"], "internal": f["internal"] + d["elastic"],
                "external_work": f["external_work"], "dissipated": f["dissipated"] + d["dissipated"]}

    def timing_correction(self) -> dict[str, float]:
        """Move the time spent inside the hook out of the DEM bucket."""
        inner = sum(self.inner.values())
        return {"dem": -inner, **self.inner}
