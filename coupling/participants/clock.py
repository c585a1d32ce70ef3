"""The coupled clock: impulse multiple time stepping of a FEM and a DEM participant.

r-RESPA (Tuckerman, Berne & Martyna 1992): the FEM's own forces are "slow" and kick the FEM
velocities once per FEM step dt = m dt_dem; the forces the tie carries between DEM and FEM
are "fast" and kick the FEM nodes at every DEM step (the DEM engine applies its side itself).
Kicks and drifts alternate, so the scheme is symplectic, conserves momentum exactly for any
m, and with m = 1 and the kinematic tie it is the monolithic central-difference step.

With m > 1 the internal forces of the band of elements that touch the interface nodes are
fast forces too (an element partition, Belytschko, Yen & Mullen 1979). A slow impulse on a
node that the DEM moves at every substep resonates with the DEM modes of period near
2 dt / k (Biesiadecki & Skeel 1993): measured on the linearised coupled step of
panel_buckling_coarse, energy x 6e6 in 20,000 FEM steps at m = 3. With the band fast, the
slow impulses land one element away, on nodes that only the soft FEM couples to the DEM:
the same test stays bounded for m = 3, 4 there and up to m = 31 on a chain of DEM bonds
1000 x stiffer than its elements (tests/test_hard_cases.py runs both).

The engine calls ``between`` after it computed the forces at x_k and before it moves (see
the back-end contract). For DEM step k:

   a. tie.fast_force            f = sum_p N_a(xi_p) F_p - f_int,band(u_k)   (fast forces)
   b. if k = n m: fem.forces    f_int(u_n), f_ext(t_n) -> a_n; energy snapshot at t_n;
                  slow kick     v += dt (a_n + f_int,band(u_n) / M)
   c. fast kick                 v += dt_dem f / M
   d. fem.drift                 u += dt_dem v                 (prescribed velocities applied)
   e. tie.follow                kinematic: v_p = sum_a N_a v_a for the engine's next move
"""
from __future__ import annotations

import time

import numpy as np

from dem_region.backends.base import DemBackend
from fem_region.explicit import ExplicitDynamics
from fem_region.kernels import respa_kicks

from ..simulation import Stage, run_stages
from .dem import ModelStep, hosted_by, worker_seconds


def interface_band(region, W) -> np.ndarray:
    """(k,) the elements with a node among the interface's host nodes (the columns of the
    particle-to-node weights W (n_itf, n_nodes) that carry weight)."""
    import scipy.sparse as sp
    host = np.zeros(region.n_nodes, bool)
    host[np.unique(sp.csr_matrix(W).indices)] = True
    return np.flatnonzero(host[region.mesh.t.T].any(axis=1))


class CoupledClock:
    """One FEM participant, one DEM participant, one tie; m DEM steps per FEM step."""

    fast_band = True  # the interface band's elements among the fast forces (False: the ablation
    # that benchmarks/subcycling.py measures; the scheme of earlier sessions)

    def __init__(self, fem: ExplicitDynamics, dem: DemBackend, tie, dt_fem: float, substeps: int = 1,
                 models: tuple = ()):
        self.fem, self.dem, self.tie = fem, dem, tie
        # coupling-layer models acting on the engine's particles (LawBonds, ParticleImpactor)
        self.models = list(models)
        # in an engine's worker the models run there, on the engine's arrays (only the
        # interface crosses each step); here they are copies, synced before they are read
        self.sync_s = 0.0  # s syncing them inside the hook (moved from the fem to the transport bucket)
        self.hosted = hosted_by(dem, self.models)
        self._model_step = ModelStep(dem, [] if self.hosted else self.models)
        self.m, self.dt = int(substeps), dt_fem
        self.dt_dem = dt_fem / self.m
        self.k = 0  # DEM steps whose forces have been handed over
        self.interface_work = 0.0  # J, work of the tie forces on the FEM (internal to the system)
        self.snapshot: dict[str, float] = {}
        self.momentum_snapshot = np.zeros(3)
        self.snapshot_every = 1  # FEM steps between snapshots (the history interval) ...
        self.last_window = -1  # ... and at this FEM step
        self.check_every = 0  # a growing zone's checks between samples (0: none): FEM steps between them,
        self.first_step = 0  # counted in the run's steps, of which this clock's first is this one; a
        # check takes only the FEM's state (u_snapshot, t_snapshot), and asks for the whole snapshot
        self.full_at = -1  # at this FEM step of the run's count when it wants to convert (-1: none)
        self.snapshot_full = False  # the last snapshot is the whole one (not a check's state only)
        self._m_dem = dem.scene.mass * tie.free_particles(dem.scene.n)
        # the elements touching the interface nodes are fast forces too: then no slow impulse
        # lands on a node the DEM moves, and the scheme does not resonate (see module doc)
        band = self.m > 1 and self.fast_band
        # (the particles the tie holds to the zone; not a growing zone's seeded ones beyond it,
        # which the FEM moves and which push back nothing: study/seeded.py)
        tied = tie.itf.W[: len(tie.itf.ids) - tie.seeded]
        self.band_elements = interface_band(fem.region, tied) if band else np.zeros(0, int)
        self._band = fem.region.element_force(self.band_elements) if self.band_elements.size else None
        shape = fem.state.v.shape  # the kicks' buffers (respa_kicks), rewritten at every DEM step
        self._f_fast, self._a_slow, self._no_band = np.zeros(shape), np.zeros(shape), np.zeros((0, shape[1]))
        self._x_nodes = np.zeros(shape)  # the nodes' positions, m
        # one DEM step's work inside the engine's hook (after its forces at x_k, before it
        # moves), in this order; each stage is timed (summary.json "stages")
        self.hook_stages = [
            *([] if self.hosted else [Stage("laws", "models", self._laws)]),  # first: the interface forces include theirs
            Stage("interface.read", "interface", self._read_interface),
            Stage("fem.forces", "fem", self._fem_forces),
            Stage("fem.kick_drift", "fem", self._fem_kick_drift),
            Stage("interface.write", "interface", self._write_interface)]
        self._slow, self._band_f = True, self._no_band
        dem.set_dt(self.dt_dem)
        dem.start(self._between)
        # the first hook ran at set-up, outside the clock's engine stage: not to be counted
        # (numba compiling there made the engine bucket negative)
        for stage in self.hook_stages:
            stage.seconds = 0.0
        if hasattr(dem, "reset_worker_seconds"):
            dem.reset_worker_seconds()
        self.sync_s = 0.0

    def _between(self) -> None:
        run_stages(self.hook_stages)

    def _laws(self) -> None:
        self._model_step.run(self.models, self.dt_dem if self.k else 0.0)

    def _read_interface(self) -> None:
        """The tie's forces from the particles on the FEM nodes at x_k (fast forces)."""
        fem = self.fem
        x = np.add(fem.region.X, fem.state.u, out=self._x_nodes) if self.tie.reads_nodes else None
        self.f_tie = self.tie.fast_force(x)

    def _fem_forces(self) -> None:
        """The band's forces at every DEM step; at a FEM step (every m-th) the FEM's own
        forces at t_n, and the ledger's snapshot there."""
        fem = self.fem
        self._band_f = self._no_band if self._band is None else self._band(fem.state.u)
        self._slow = self.k % self.m == 0
        if self._slow:
            fem.compute_forces()
            n = self.k // self.m
            r = n + self.first_step  # in the run's count
            if r % self.snapshot_every == 0 or n == self.last_window or r == self.full_at:  # at t_n, before the kicks
                self._kicks(self._band_f, True, False)
                self._snapshot(self._f_fast, self._a_slow)
            elif self.check_every and r % self.check_every == 0:  # a growth check: the FEM's state only
                np.copyto(self.u_snapshot, fem.state.u)
                self.t_snapshot, self.snapshot_full = fem.state.t, False

    def _fem_kick_drift(self) -> None:
        fem = self.fem
        fem.respa_drift(self.dt_dem, self.f_tie, self._band_f, self.dt, self._slow, self._f_fast, self._a_slow)
        self.interface_work += self.dt_dem * float(np.vdot(self.f_tie, fem.state.v))

    def _write_interface(self) -> None:
        """Kinematic tie: the interface particles' velocities for the engine's next move."""
        self.tie.follow(self.fem.state.v)
        self.k += 1

    def _kicks(self, band: np.ndarray, slow: bool, kick: bool) -> None:
        """f_fast = f_tie - band, a_slow (at a FEM step) and, with ``kick``, the FEM's kicks."""
        s = self.fem.state
        respa_kicks(s.v, s.a, self.f_tie, band, self.fem.m, self.dt, self.dt_dem, slow, kick, self._f_fast,
                    self._a_slow)

    def _snapshot(self, f_fast: np.ndarray, a_slow: np.ndarray) -> None:
        """Energies, momentum and FEM state at t_n = k dt_dem, all at that time level: the
        leapfrog velocities lag half a step and are completed with the forces at t_n."""
        fem = self.fem
        self.sync_models()
        self.u_snapshot = fem.state.u.copy()  # the FEM drifts ahead of the engine
        # the FEM's velocity and time before this step's kicks: where a grown zone's model
        # continues from (coupling/study/growth.py)
        self.v_start_snapshot, self.t_snapshot = fem.state.v.copy(), fem.state.t
        self.snapshot_full = True
        P = np.zeros(3)
        P[: fem.region.dim] = fem.m @ fem.state.v
        self.momentum_snapshot = P + self._m_dem @ self.dem.velocities() + sum((m.momentum() for m in self.models),
                                                                                np.zeros(3))
        v_n = self.v_snapshot = fem.state.v + 0.5 * self.dt * a_slow + 0.5 * self.dt_dem * f_fast / fem.m[:, None]
        f = fem.energies()
        d = self.dem.energies()
        kin_fem = 0.5 * float(np.einsum("n,ni,ni->", fem.m, v_n, v_n))
        e = [m.energies() for m in self.models]
        total = lambda key: sum(x[key] for x in e)
        self.snapshot = {"kinetic": kin_fem + d["kinetic"] + total("kinetic"),
                         "internal": f["internal"] + d["elastic"] + self.tie.energy() + total("internal"),
                         "external_work": f["external_work"] + sum(x.get("external_work", 0.0) for x in e),
                         "dissipated": f["dissipated"] + d["dissipated"] + total("dissipated")}
        self.interface_work_snapshot = self.interface_work

    # -- checkpoint ---------------------------------------------------------------------------
    _SCALARS = ("k", "interface_work", "interface_work_snapshot")
    _ARRAYS = ("momentum_snapshot", "u_snapshot", "v_snapshot", "f_tie")

    def sync_models(self) -> None:
        """The models' copies here equal to the engine worker's (when it hosts them)."""
        if self.hosted:
            t0 = time.perf_counter()
            self.dem.sync_models(self.models)
            self.sync_s += time.perf_counter() - t0

    def checkpoint_state(self) -> dict:
        self.sync_models()
        d = {"fem": self.fem.checkpoint_state(), "snapshot": dict(self.snapshot),
             **{k: getattr(self, k) for k in self._SCALARS + self._ARRAYS if hasattr(self, k)}}
        if hasattr(self.tie, "_stretch"):
            d["tie_stretch"] = self.tie._stretch
        d["models"] = [m.checkpoint_state() for m in self.models]
        return d

    def restore_state(self, d: dict, engine_checkpoint) -> None:
        self.fem.restore_state(d["fem"])
        self.snapshot = {k: float(v) for k, v in d["snapshot"].items()}
        for k in self._SCALARS:
            if k in d:
                setattr(self, k, type(getattr(self, k, 0.0))(d[k]) if k != "k" else int(d[k]))
        for k in self._ARRAYS:
            if k in d:
                setattr(self, k, np.array(d[k]))
        if "tie_stretch" in d:
            self.tie._stretch = np.array(d["tie_stretch"])
        for m, state in zip(self.models, d.get("models", [])):
            m.restore_state(state)
        if self.hosted:
            self.dem.set_models_state(d.get("models", []))
        self.dem.restore(engine_checkpoint)

    def step(self, n: int = 1) -> None:
        """n FEM steps = n m DEM steps, in one advance of the engine (the whole coupled step
        runs in its hook)."""
        self.dem.advance(self._between, n * self.m)

    def stages(self) -> list[Stage]:
        """One FEM step: m engine steps, each running ``hook_stages`` inside its hook."""
        return [Stage(f"engine.step x {self.m}", "dem", self.step, substages=self.hook_stages, repeat=self.step)]

    def energies(self) -> dict[str, float]:
        """Ledger of the coupled system at the last snapshot (the tie's work is internal)."""
        return self.snapshot

    def momentum(self) -> np.ndarray:
        """(3,) kg m/s of FEM nodes and DEM particles at the last snapshot (leapfrog
        half-step velocities, which carry every impulse handed over so far)."""
        return self.momentum_snapshot

    def timing_correction(self) -> dict[str, float]:
        """A worker's transport, the models it hosts and its interface reads and writes, out of
        the engine's bucket; the hosted models' syncs at the ledger's snapshots (run inside the
        fem.forces stage) into the transport's."""
        out = worker_seconds(self.dem)
        out["transport"] = out.get("transport", 0.0) + self.sync_s
        out["fem"] = -self.sync_s
        return out
