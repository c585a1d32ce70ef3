"""Central-difference (velocity-Verlet form) integration of a FemRegion with lumped mass.

One step is split into the phases the coupled clock orders (ARCHITECTURE.md):
``kick_drift`` (v_{n+1/2} = v_n + dt/2 a_n, prescribed velocities, u_{n+1} = u_n + dt v_{n+1/2}),
``compute_forces`` (internal, external, damping and any coupling force at t_{n+1}) and
``kick`` (v_{n+1} = v_{n+1/2} + dt/2 a_{n+1}). Alone they are the standard explicit scheme;
with a DEM zone the interface stages sit between them.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
import scipy.sparse as sp

from .bulk_viscosity import BulkViscosity
from .kernels import add_first_columns, axpy, residual_finish, residual_start, respa_kicks, respa_kicks_drift, \
    scale_rows, kinetic_energy as nodal_kinetic_energy
from physics.impactor import FLAT, RigidImpactor
from physics.kernels import add_at, impactor_on_nodes
from .region import FemRegion
from .stable_step import assembled_critical_dt, largest_frequency_squared

TimeFunction = Callable[[float], float]


def at_rest(t: float) -> float:
    """The velocity of a fixed or symmetry support (m/s): zero at any time."""
    return 0.0


@dataclass
class PrescribedMotion:
    """Velocity v(t) (m/s) on flat DOFs ``dofs``; v(t) = 0 (at_rest, the default) is a fixed /
    symmetry support."""

    dofs: np.ndarray
    velocity: TimeFunction = at_rest


def displacement_history(d: TimeFunction, h: float = 1e-9) -> TimeFunction:
    """Prescribed displacement d(t) (m) as the velocity history a PrescribedMotion takes
    (central difference over h seconds; d must be smooth on that scale)."""
    return lambda t: (d(t + 0.5 * h) - d(t - 0.5 * h)) / h


@dataclass
class NodalLoad:
    """Force ``amplitude * curve(t)`` (N) on flat DOFs ``dofs``; amplitude: scalar or (len(dofs),)."""

    dofs: np.ndarray
    amplitude: np.ndarray | float
    curve: TimeFunction = staticmethod(lambda t: 1.0)


@dataclass
class FemState:
    """u, v, a, f_ext: (n_nodes, dim) in m, m/s, m/s^2, N; t in s. A checkpoint is a copy."""

    u: np.ndarray
    v: np.ndarray
    a: np.ndarray
    f_ext: np.ndarray
    t: float = 0.0
    step: int = 0

    def copy(self) -> "FemState":
        return FemState(self.u.copy(), self.v.copy(), self.a.copy(), self.f_ext.copy(), self.t, self.step)


@dataclass
class EnergyLedger:
    """Energy accounts (J), accumulated by the trapezoidal rule over each step's displacement."""

    kinetic: float = 0.0
    internal: float = 0.0
    external_work: float = 0.0
    support_work: float = 0.0
    damping: float = 0.0


@dataclass
class ExplicitDynamics:
    """An explicit FEM participant: region + supports + loads + damping + state.

    alpha, beta: Rayleigh damping C = alpha M + beta K (1/s, s); kinetic_damping: dynamic
    relaxation by zeroing all velocities at each kinetic-energy peak (quasi-static runs).
    extra_mass: (n_nodes,) kg added at nodes (e.g. interface particle masses shared to nodes);
    bulk_viscosity: shock viscosity (BulkViscosity) or None; mass_scaling_dt: s, if > 0 the
    density of every element whose stable step is below it is scaled up to reach it (the
    added mass is reported by ``added_mass``).
    """

    region: FemRegion
    supports: list[PrescribedMotion] = field(default_factory=list)
    loads: list[NodalLoad] = field(default_factory=list)
    alpha: float = 0.0
    beta: float = 0.0
    kinetic_damping: bool = False
    extra_mass: np.ndarray | None = None
    bulk_viscosity: BulkViscosity | None = None
    mass_scaling_dt: float = 0.0
    impactors: list[RigidImpactor] = field(default_factory=list)
    # forces of models between nodes (e.g. cohesive bonds joining two meshes): callables
    # giving (n_nodes, dim) N at the current state; their energy is the models' to report
    node_forces: list = field(default_factory=list)
    # (ndof, ndof) N/m, the stiffest those models get as springs between nodes (add_springs):
    # part of the assembled stable step
    springs: sp.spmatrix | None = None
    # s, a limit of the step those models set themselves (e.g. their dampers': pair_step_limit)
    spring_dt_limit: float = np.inf

    def __post_init__(self):
        r = self.region
        self.density_scale, self.added_mass = None, np.zeros(r.n_nodes)
        if self.mass_scaling_dt > 0:
            self.density_scale, self.added_mass = r.mass_scaling(self.mass_scaling_dt)
        self.m = r.mass + self.added_mass + (0.0 if self.extra_mass is None else self.extra_mass)
        zero = np.zeros((r.n_nodes, r.dim))
        self.state = FemState(zero.copy(), zero.copy(), zero.copy(), zero.copy())
        self.ledger = EnergyLedger()
        self._prescribed = np.unique(np.concatenate([s.dofs for s in self.supports])) if self.supports else np.zeros(0, int)
        self._u_at_forces, self._t_at_forces, self._dt = zero.copy(), 0.0, 0.0
        self._surface = r.mesh.boundary_nodes() if self.impactors else np.zeros(0, int)
        for imp in self.impactors:
            imp.restrict(self._surface)
        self._contact_prev = [(np.zeros((len(self._surface), r.dim)), np.zeros(r.dim)) for _ in self.impactors]
        self._contact_work = 0.0  # net work of the contact forces on both bodies (J)
        self._contact_energy = 0.0  # stored penalty energy (J)
        self._reaction_prev = np.zeros(self._prescribed.size)
        self._ke_prev = 0.0
        # the step's buffers, rewritten in place (the step allocates little: on small meshes a
        # step is ruled by the count of numpy operations, not their size)
        self._du, self._f_int, self._f = zero.copy(), zero.copy(), zero.copy()
        self._f_ext = (zero.copy(), zero.copy())  # the loads of this step and the last, in turn
        self._f_damp, self._Kv = zero.copy(), zero.copy()  # damping's force, and K v for its beta term
        self._a_rest = np.zeros(self._prescribed.size)  # the prescribed DOFs' acceleration when none moves
        self._moving = [sup for sup in self.supports if sup.velocity is not at_rest]
        rest = [sup.dofs for sup in self.supports if sup.velocity is at_rest]
        rest = np.unique(np.concatenate(rest)) if rest else np.zeros(0, int)
        # the fixed DOFs set in one operation, then the moving supports in their order (the same
        # as the supports' order unless a DOF is both fixed and moving: then each in turn)
        overlap = any(np.isin(sup.dofs, rest).any() for sup in self._moving)
        self._rest_dofs = None if overlap else rest
        # each support's DOFs as places in the prescribed ones: their accelerations set in order
        self._a_pres = np.zeros(self._prescribed.size)
        self._pres_place = [np.searchsorted(self._prescribed, sup.dofs) for sup in self.supports]
        self._contact_buffers = [tuple((np.zeros((len(self._surface), r.dim)), np.zeros(r.dim)) for _ in range(2))
                                 for _ in self.impactors]
        self._xs, self._vs = np.zeros((len(self._surface), r.dim)), np.zeros((len(self._surface), r.dim))
        self._no_node_forces = np.zeros((0, 3))
        self._no_footprint = np.zeros(0)  # (an impactor's penalty on every contact node)

    def add_nodal_mass(self, extra: np.ndarray) -> None:
        """Add (n_nodes,) kg at the nodes (interface particle masses shared by a tie)."""
        self.m = self.m + extra
        self.ledger.kinetic = self.kinetic_energy()

    def set_initial_velocity(self, v: np.ndarray) -> None:
        """v: (n_nodes, dim) m/s at t = 0."""
        self.state.v[:] = v
        self.ledger.kinetic = self.kinetic_energy()

    def add_springs(self, K: sp.spmatrix, limit: float = np.inf) -> None:
        """Add K (ndof, ndof) N/m, springs between nodes at their stiffest, to the stable step;
        ``limit`` (s): a step they must not exceed on their own account."""
        self.springs = K if self.springs is None else self.springs + K
        self.spring_dt_limit = min(self.spring_dt_limit, limit)

    def critical_dt(self) -> float:
        """Stable step (s) of the assembled model (the elements' stiffness with the springs, the
        nodes' masses with what mass scaling and ties add: fem_region.stable_step), within the
        impactors' own limit and the springs' (spring_dt_limit), reduced for the damping of the
        stiffness-proportional term and of the viscous hourglass form: dt = 2 / w (sqrt(1 + xi^2) -
        xi), xi = beta w / 2 + c / (2 w) with c the largest rate of M^-1/2 C M^-1/2 (the hourglass
        modes have no stiffness to bound them: a one-point beam, one ply per element, took 1.1 x
        the step it keeps, and its energy grew without bound)."""
        K = self.region.K if self.springs is None else self.region.K + self.springs
        dt = assembled_critical_dt(K, self.m, self.region.dim)
        for imp in self.impactors:
            dt = min(dt, imp.critical_dt(self.m[self._surface]))
        rate = largest_frequency_squared(self.region.hourglass_damping(), self.m, self.region.dim) \
            if self.region.viscous_hourglass else 0.0  # (1/s: the matrix is a damping one)
        if self.beta > 0 or rate > 0:
            w = 2.0 / dt
            xi = 0.5 * self.beta * w + 0.5 * rate / w
            dt = 2.0 / w * (np.sqrt(1 + xi * xi) - xi)
        return min(dt, self.spring_dt_limit)

    def external_force(self, t: float, out: np.ndarray) -> np.ndarray:
        """``out`` (n_nodes, dim) N <- the loads at time t (s), returned itself (the step tells its
        two buffers apart by identity); each load's values go through a buffer of its own."""
        f = out.reshape(-1)
        f[:] = 0.0
        plan = getattr(self, "_load_values", [])  # (load, its dofs, a buffer of its values) per load
        if len(plan) != len(self.loads) or any(p[0] is not load for p, load in zip(plan, self.loads)):
            plan = self._load_values = [(load, np.ascontiguousarray(load.dofs, np.int64), np.empty(len(load.dofs)))
                                        for load in self.loads]
        for load, dofs, values in plan:
            np.multiply(load.amplitude, load.curve(t), out=values)
            add_at(f, dofs, values)
        return out

    # -- the phases of one step ----------------------------------------------------------------
    def half_kick(self, dt: float) -> None:
        """v += dt/2 a (nodes and impactors)."""
        axpy(self.state.v, 0.5 * dt, self.state.a)
        for imp in self.impactors:
            imp.v += 0.5 * dt * imp.a

    def drift(self, dt: float) -> None:
        """u += dt v with the prescribed velocities at the mid-point of the drift; t += dt."""
        s = self.state
        for imp in self.impactors:
            imp.x += dt * imp.v
        self._set_prescribed_velocities(s.t + 0.5 * dt)
        axpy(s.u, dt, s.v)
        s.t += dt

    def respa_drift(self, dt_fast: float, f_tie, band, dt: float, slow: bool, f_fast, a_slow) -> None:
        """The impulse clock's kicks of one fast step (fem_region.kernels.respa_kicks: f_tie, band
        (n_nodes, dim) N, a FEM step of dt s when ``slow``; f_fast, a_slow out) and the drift over
        dt_fast s after them: one compiled pass where nothing moves on its own (no impactor, no
        moving support), else the kicks and ``drift`` in turn."""
        s = self.state
        if self.impactors or self._moving:  # (_rest_dofs is None only beside a moving support)
            respa_kicks(s.v, s.a, f_tie, band, self.m, dt, dt_fast, slow, True, f_fast, a_slow)
            self.drift(dt_fast)
            return
        respa_kicks_drift(s.v, s.a, f_tie, band, self.m, dt, dt_fast, slow, f_fast, a_slow, s.u, self._rest_dofs)
        s.t += dt_fast

    def _set_prescribed_velocities(self, t: float) -> None:
        """The supports' velocities at time t (s) on their DOFs."""
        vflat = self.state.v.reshape(-1)
        if self._rest_dofs is None:
            for sup in self.supports:
                vflat[sup.dofs] = sup.velocity(t)
            return
        vflat[self._rest_dofs] = 0.0
        for sup in self._moving:
            vflat[sup.dofs] = sup.velocity(t)

    def kick_drift(self, dt: float) -> None:
        """v_{n+1/2} = v_n + dt/2 a_n, then u_{n+1} = u_n + dt v_{n+1/2}."""
        self.half_kick(dt)
        self.drift(dt)
        self.state.step += 1

    def compute_forces(self) -> None:
        """Forces at the new configuration; a = f / m except on prescribed DOFs."""
        s, L = self.state, self.ledger
        f_int = self.region.internal_force(s.u, out=self._f_int)
        du = self._du  # the motion since the last force evaluation
        self._dt = s.t - self._t_at_forces
        if self.loads:  # into the buffer the last step's loads are not in
            np.subtract(s.u, self._u_at_forces, out=du)
            f_ext = self.external_force(s.t, self._f_ext[1] if s.f_ext is self._f_ext[0] else self._f_ext[0])
            L.external_work += 0.5 * float(np.vdot(np.add(s.f_ext, f_ext, out=self._f), du))
            f = np.subtract(f_ext, f_int, out=self._f)
        else:  # nothing applied: no work; s.f_ext stays zero
            f_ext, f = s.f_ext, self._f
            residual_start(s.u, self._u_at_forces, f_int, du, f)
        f_damp = self._damping_force(s.v)
        if f_damp is not None:
            L.damping += float(np.vdot(f_damp, du))
            f -= f_damp
        if self.impactors:
            self._contact(du, f)
        node_f = self._no_node_forces  # (the last model's forces are added in the pass below)
        for model in self.node_forces:
            if node_f.size:
                add_first_columns(f, node_f)
            node_f = model()
        L.support_work += residual_finish(f, node_f, self.m, s.a, s.u, self._u_at_forces, *self._support_arguments())
        s.f_ext = f_ext
        self.f_int = f_int
        self._t_at_forces = s.t

    def _support_arguments(self) -> tuple:
        """residual_finish's arguments of the prescribed DOFs (dofs, their masses, accelerations,
        the last and this evaluation's reactions, the motion du): the reaction goes into the
        buffer the last one is not in."""
        P = self._prescribed
        if getattr(self, "_m_prescribed_of", None) is not self.m:  # the prescribed DOFs' masses, per mass array
            self._m_prescribed, self._m_prescribed_of = self.m.repeat(self.region.dim)[P], self.m
            self._pres_r = [np.zeros(P.size) for _ in range(2)]
        r0, r1 = self._pres_r
        reaction = r1 if self._reaction_prev is r0 else r0
        prev, self._reaction_prev = self._reaction_prev, reaction
        return P, self._m_prescribed, self._prescribed_acceleration(), prev, reaction, self._du

    def reaction(self, dofs: np.ndarray) -> float:
        """N, sum of the support reactions on flat DOFs ``dofs`` (all prescribed) at the last
        force evaluation: what the supports apply beyond the residual force."""
        return float(self._reaction_prev[np.isin(self._prescribed, dofs)].sum())

    def _contact(self, du: np.ndarray, f: np.ndarray) -> None:
        """Penalty contact forces on the surface nodes, added to f (n_nodes, dim) N; impactor
        accelerations; contact ledger. du (n_nodes, dim) m: the nodes' motion since the last."""
        S, r, s = self._surface, self.region, self.state
        self._contact_energy = 0.0
        for k, imp in enumerate(self.impactors):
            fc_prev, F_prev = self._contact_prev[k]
            flat = imp.shape in FLAT
            if imp.on_nodes_compiled:  # one compiled pass, into the buffer the last step's forces are not in
                a, b = self._contact_buffers[k]
                fc, F = b if fc_prev is a[0] else a
                footprint = self._no_footprint if imp._k is None else imp._k
                pen2, work = impactor_on_nodes(r.X, s.u, s.v, du, S, self._xs, self._vs, imp.x, imp.contact_axis,
                                               imp.v, float(imp.radius), flat, float(imp.depth) if flat else 0.0,
                                               footprint, float(imp.penalty), float(imp.friction),
                                               float(imp.slip_velocity**2), fc, fc_prev, f, F)
                energy = 0.5 * (imp.penalty * pen2 if imp._k is None else pen2)
            else:
                fc, energy = imp.forces(r.X[S] + s.u[S], s.v[S])
                F = -fc.sum(axis=0)
                work = float(np.vdot(fc_prev + fc, du[S]))
                f[S] += fc
            dx, imp.x_at_forces = imp.x - imp.x_at_forces, imp.x.copy()
            self._contact_work += 0.5 * (work + (F_prev + F) @ dx)
            self._contact_prev[k] = (fc, F)
            imp.a = F / imp.mass
            self._contact_energy += energy

    def _prescribed_acceleration(self) -> np.ndarray:
        """Acceleration of the prescribed DOFs at t_n: central difference of v(t) over dt."""
        t, dt = self.state.t, getattr(self, "_dt", 0.0)
        if not self._moving or dt <= 0:
            return self._a_rest
        a = self._a_pres  # (in its buffer: nothing of the mesh's size allocated per step)
        for sup, place in zip(self.supports, self._pres_place):
            a[place] = (sup.velocity(t + 0.5 * dt) - sup.velocity(t - 0.5 * dt)) / dt
        return a

    def kick(self, dt: float) -> None:
        """v_{n+1} = v_{n+1/2} + dt/2 a_{n+1}; kinetic-energy ledger; dynamic relaxation."""
        s = self.state
        self.half_kick(dt)
        if self._prescribed.size:
            self._set_prescribed_velocities(s.t)
        ke = self.kinetic_energy()
        if self.kinetic_damping and ke < self._ke_prev:
            s.v[:] = 0.0  # past a kinetic-energy peak: restart from rest (dynamic relaxation)
            ke = 0.0
        self._ke_prev = ke
        self.ledger.kinetic = ke

    def step(self, dt: float) -> None:
        """One uncoupled central-difference step."""
        self.kick_drift(dt)
        self.compute_forces()
        self.kick(dt)

    def start(self) -> None:
        """Accelerations at t = 0 from the initial state (call once before stepping)."""
        self.compute_forces()
        self.ledger = EnergyLedger(kinetic=self.kinetic_energy())

    # -- checkpoint ---------------------------------------------------------------------------
    _PRIVATE = ("_u_at_forces", "_t_at_forces", "_dt", "_reaction_prev", "_ke_prev", "_contact_work",
                "_contact_energy")

    def checkpoint_state(self) -> dict:
        """Everything that evolves: a restore followed by the same steps is bit-identical."""
        s = self.state
        d = {"u": s.u, "v": s.v, "a": s.a, "f_ext": s.f_ext, "t": s.t, "step": s.step,
             "ledger": dict(vars(self.ledger)), **{k: getattr(self, k) for k in self._PRIVATE},
             "impactors": [{"x": i.x, "v": i.v, "a": i.a, "x_at_forces": i.x_at_forces} for i in self.impactors],
             "contact_prev": [{"f": f, "F": F} for f, F in self._contact_prev]}
        if hasattr(self, "f_int"):
            d["f_int"] = self.f_int
        d["node_forces"] = [m.checkpoint_state() for m in self.node_forces if hasattr(m, "checkpoint_state")]
        return d

    def restore_state(self, d: dict) -> None:
        s = self.state
        for k in ("u", "v", "a", "f_ext"):
            getattr(s, k)[:] = d[k]
        s.t, s.step = float(d["t"]), int(d["step"])
        self.ledger = EnergyLedger(**{k: float(v) for k, v in d["ledger"].items()})
        for k in self._PRIVATE:
            v = d[k]
            setattr(self, k, np.array(v) if np.ndim(v) else float(v))
        for imp, st in zip(self.impactors, d.get("impactors", [])):
            imp.x[:], imp.v[:], imp.a[:], imp.x_at_forces[:] = st["x"], st["v"], st["a"], st["x_at_forces"]
        self._contact_prev = [(np.array(c["f"]), np.array(c["F"])) for c in d.get("contact_prev", [])]
        if "f_int" in d:
            self.f_int = np.array(d["f_int"])
        stateful = [m for m in self.node_forces if hasattr(m, "checkpoint_state")]
        for m, st in zip(stateful, d.get("node_forces", [])):
            m.restore_state(st)

    # -- energies ----------------------------------------------------------------------------
    def kinetic_energy(self) -> float:
        return nodal_kinetic_energy(self.m, self.state.v) + sum(imp.kinetic_energy() for imp in self.impactors)

    def momentum(self) -> np.ndarray:
        """(dim,) kg m/s of the FEM nodes and the impactors."""
        return self.m @ self.state.v + sum((imp.momentum() for imp in self.impactors), np.zeros(self.region.dim))

    def energies(self) -> dict[str, float]:
        """The ledger with the current stored strain energy (J)."""
        L = self.ledger
        L.internal = self.region.strain_energy(getattr(self, "_u_at_forces", self.state.u))
        # coupling work is not external to a coupled system: the coupler accounts for it
        # contact: penalty energy is stored; what the contact forces took beyond it is
        # dissipated (friction; a negative value means the contact created energy)
        contact_loss = -self._contact_work - self._contact_energy
        return dict(kinetic=L.kinetic, internal=L.internal + self._contact_energy,
                    external_work=L.external_work + L.support_work, dissipated=L.damping + contact_loss)

    def _damping_force(self, v: np.ndarray) -> np.ndarray | None:
        """(n_nodes, dim) N of Rayleigh damping, viscous hourglass control and bulk viscosity at
        velocity v, or None without any; in its buffer (nothing allocated per step)."""
        if not (self.alpha or self.beta or self.region.viscous_hourglass or self.bulk_viscosity is not None):
            return None
        f = self._f_damp
        if self.alpha:  # alpha M v
            scale_rows(v, self.m, self.alpha, f)
        else:
            f[:] = 0.0
        if self.beta:  # beta K v
            axpy(f, self.beta, self.region.stiffness_times(v, self._Kv))
        self.region.add_hourglass_viscous_force(v, f)
        if self.bulk_viscosity is not None:
            self.bulk_viscosity.add_force(v, f)
        return f
