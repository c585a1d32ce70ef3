"""Bond laws evaluated by the coupling layer on any engine (the engine only integrates).

An engine that lacks a law (softening, mixed-mode decohesion, friction on the broken faces)
still carries the particles: each step this module reads the positions of the bonded
particles (``positions_of``), evaluates the law vectorised over the bonds and adds the bond
forces (``add_forces``) before the engine's next move. Call ``apply`` from the engine's
coupling hook, where forces are those of the current positions (back-end contract).

Kinematics (small rotation of the bond axis, the regime of an interface before and during
decohesion): the separation of bond b is the change of the branch vector,
delta = (x_j - x_i) - (X_j - X_i), split on the initial unit normal n0 (opening dn > 0)
and the tangential slip ds. The traction t (Pa) acts on an area A (m^2): F_j = -A t,
F_i = +A t, so momentum is exact.

Interface bonds (``along``: each bond's neighbours along the interface) measure the slip
free of rotation: a pair of particles a distance h apart across the interface moves apart
tangentially by h du_n/ds under a rigid rotation (and under bending), which is not slip. The
slip is ds = (delta . e_t) + h d(u_n)/ds with the derivative of the pairs' mean normal
displacement by central differences along the interface (e_t from the previous to the next
pair): the engineering shear strain of the layer times h. Its work-conjugate forces include
normal forces on the neighbouring pairs, the couple that balances the pair's shear couple,
so angular momentum is exact too. (A shear spring on the raw relative translation resists
rotation instead: a [0_6/90_4/0_6] lattice cantilever with such interfaces came out 2.35 x
too compliant; with this slip it is within 5 % of the FEM.)

Finite rotation (``finite_rotation=True``, for bonds that turn by more than their strain, e.g.
at the tips of a buckling delamination, where a tip rotation theta gives the fixed-normal split
a spurious compression d theta^2 / 2): the law is evaluated in a frame that turns with the
material. A central bond (no ``along``: PlyBondLaw) opens by |x_j - x_i| - |X_j - X_i| along its
reference normal and pushes along its current axis. An interface bond (``along``, one tangent,
x-y plane) is measured in the frame turned by the angle theta of its neighbour pairs' chord
(the same chord as the slope term, which it replaces: to first order they are the same slip),
delta = R(theta)^T (x_j - x_i) - (X_j - X_i); its forces are the exact gradient of the bond
energy, including the frame's spin, A (dPsi/dtheta) dtheta/dx on the four neighbour particles.
A rigid motion of any size then gives no force, and momentum and angular momentum are exact.

Energy is measured, not assumed: the work of the bond forces on the separations is summed
by the trapezoidal rule; the stored energy is the elastic part of the current traction;
dissipated = work - stored (decohesion plus friction).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import kernels, law_kernels
from .laws import friction_traction


_LAW_STATE = ("m0", "mf", "crushed", "snapback")  # what a stateful law carries between steps
# the bonds' work accounts (J): the whole, and the friction's and the dampers' shares of it; what
# a checkpoint keeps, a grown zone carries over and MPI ranks sum
WORK = ("work", "friction_work", "damping_work")
INDEX = np.int32  # the fused step's index arrays: half the bytes a bond reads of int64's


@dataclass
class LawBonds:
    """pairs (nb, 2) particle ids; X (n, 3) reference positions m; normal (nb, 3) unit,
    from i to j; area (nb,) m^2; law: HashinCohesiveLaw or PlyBondLaw; volume: (n,) m^3, the
    lattice cell of each particle, needed by laws that initiate on the particle stress
    (PlyBondLaw: Love-Weber stress of the law bonds' forces); friction: Coulomb coefficient on
    failed bonds in compression; v_reg: m/s, friction regularisation; scale: factor on the
    reported energies (slice thickness -> full width); label: family name in outputs;
    damping: (nb,) Pa s/m, a damper on each bond's opening rate while it has softened and not
    failed, at contact (in compression now or at the last step) (None: none): the ringing
    control of penalty pairs (participants.fem.pair_damping)."""

    pairs: np.ndarray
    X: np.ndarray
    normal: np.ndarray
    area: np.ndarray
    law: object
    friction: float = 0.0
    volume: np.ndarray | None = None
    along: np.ndarray | None = None  # (nb, 2 t): previous / next bond along each of t tangents, -1 at an end
    v_reg: float = 1e-3
    label: str = "interlaminar"
    finite_rotation: bool = False  # corotated kinematics (module docstring)
    damping: np.ndarray | None = None

    def __post_init__(self):
        self.pairs = np.asarray(self.pairs, int).reshape(-1, 2)
        nb = len(self.pairs)
        self.normal = np.asarray(self.normal, float).reshape(nb, 3)
        self.normal = self.normal / np.linalg.norm(self.normal, axis=1)[:, None]
        self.area = np.broadcast_to(np.asarray(self.area, float), (nb,)).copy()
        self.damping = np.zeros(nb) if self.damping is None else \
            np.broadcast_to(np.asarray(self.damping, float), (nb,)).copy()
        self.ids, inverse = np.unique(self.pairs, return_inverse=True)
        self._loc = inverse.reshape(-1, 2)  # bond end -> row of self.ids
        X = np.asarray(self.X, float)
        self.d0 = X[self.pairs[:, 1]] - X[self.pairs[:, 0]]
        self.K_each = np.array(np.broadcast_to(np.asarray(self.law.K, float), (nb,)))  # Pa/m, each bond's stiffness
        self.damage = np.zeros(nb)
        self.delta = np.zeros((nb, 3))  # separation at the last evaluation, m
        self.traction = np.zeros((nb, 3))  # Pa
        self.work = 0.0  # J, work of the bond forces on the separations (slice)
        self.friction_work = 0.0  # J, its share done by the tangential tractions of failed bonds
        self.damping_work = 0.0  # J, its share done by the dampers
        self.t_failed = np.full(nb, np.nan)  # s, when each bond reached full decohesion
        self.force = np.zeros((nb, 3))  # N on each bond's second particle at the last evaluation
        self.time = 0.0
        self._plan, self._bound = None, None  # the fused step's buffers, and the arrays it is bound to
        if self.along is not None:  # one (previous, next) pair of columns per tangent direction
            self.along = np.asarray(self.along, int).reshape(nb, -1)
            mid = 0.5 * (X[self.pairs[:, 0]] + X[self.pairs[:, 1]])
            self._dirs = []  # (a, b, e_t, h / span) per tangent direction
            for prev, nxt in self.along.reshape(nb, -1, 2).transpose(1, 2, 0):
                a = np.where(prev >= 0, prev, np.arange(nb))
                b = np.where(nxt >= 0, nxt, np.arange(nb))
                e = mid[b] - mid[a]
                span = np.linalg.norm(e, axis=1)
                if np.any(span == 0):
                    raise ValueError("an interface bond has no neighbour along the interface")
                self._dirs.append((a, b, e / span[:, None], np.linalg.norm(self.d0, axis=1) / span))
            self._X_mid = mid
        if self.finite_rotation:
            if self.along is not None and len(self._dirs) != 1:
                raise ValueError("finite rotation of an interface frame is built for one tangent (a 2D x-y slice)")
            if self.along is None and hasattr(self.law, "R0"):
                raise ValueError("finite rotation needs a central law or an interface with neighbours (along)")
            if self.along is not None:
                a, b = self._dirs[0][:2]
                self._s0 = mid[b] - mid[a]  # reference chord of the neighbour pairs
                # the current frame, rewritten in place each step: corotated branch vectors,
                # cos / sin of the turn, chord
                self._local, self._rot, self._chord = np.empty((nb, 3)), np.empty((nb, 2)), np.empty((nb, 3))
            self._L0 = np.linalg.norm(self.d0, axis=1)
        if hasattr(self.law, "initiate"):
            if self.volume is None:
                raise ValueError("this law initiates on the particle stress: give the particles' volume")
            self._cell = np.asarray(self.volume, float)[self.ids]

    # -- the law -------------------------------------------------------------------------------
    def split(self, delta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(opening dn (nb,), slip ds (nb, 3)) of separations delta (nb, 3)."""
        dn = np.einsum("bi,bi->b", delta, self.normal)
        return dn, delta - dn[:, None] * self.normal

    def evaluate_reference(self, x: np.ndarray, dt: float) -> np.ndarray:
        """The readable reference of the fused step (vectorised numpy, the law through
        tractions_fast): update the bonds from the positions x (len(ids), 3) m of the bonded
        particles after a step of dt s; returns the force (nb, 3) N on each bond's second
        particle. The tests and benchmarks/coupled_step.py hold the kernels to it."""
        i, j = self._loc.T
        if self.finite_rotation:
            delta = self._corotate(x)
        else:
            delta = x[j] - x[i] - self.d0
        if self.along is not None and not self.finite_rotation:  # rotation-free slip: + h d(u_n)/ds
            un = np.einsum("bi,bi->b", 0.5 * (x[i] + x[j]) - self._X_mid, self.normal)
            for a, b, e_t, h_span in self._dirs:
                delta = delta + (h_span * (un[b] - un[a]))[:, None] * e_t
        if hasattr(self.law, "initiate"):
            self.law.initiate(self.bond_stress(), np.einsum("bi,bi->b", delta, self.normal), self.normal)
        t, d = self.law.tractions_fast(delta, self.normal, self.damage)
        failed = d >= 1.0
        if self.friction > 0 and failed.any() and dt > 0:  # closed crack faces slide with friction
            dn, ds = self.split(delta)
            closed = failed & (dn < 0)
            if closed.any():
                rate = (ds - self.split(self.delta)[1])[closed] / dt
                tn = dn[closed] * np.broadcast_to(self.law.K, dn.shape)[closed]
                # the bond traction acts on the second particle as -A t: friction against its slip
                t[closed] = tn[:, None] * self.normal[closed] - friction_traction(tn, rate, self.friction, self.v_reg)
        if dt > 0 and self.damping.any():  # the dampers of softened bonds at contact
            dn, dn_old = np.einsum("bi,bi->b", delta, self.normal), np.einsum("bi,bi->b", self.delta, self.normal)
            rate = dn - dn_old
            on = (d > 0) & (d < 1) & ((dn < 0) | (dn_old < 0)) & (self.damping > 0)
            q = np.where(on, self.damping / dt * rate, 0.0)
            t = t + q[:, None] * self.normal
            self.damping_work += float(self.area @ (q * rate))
        newly = failed & ~(self.damage >= 1.0)
        self.time += dt
        self.t_failed[newly] = self.time
        self.work += 0.5 * float(np.einsum("b,bi,bi->", self.area, self.traction + t, delta - self.delta))
        # the friction's share: the tangential tractions of failed bonds (of this step's, and the
        # last step's of those failed then)
        tangential = lambda tr: tr - np.einsum("bi,bi->b", tr, self.normal)[:, None] * self.normal
        f = np.where(failed[:, None], tangential(t), 0.0) + np.where((self.damage >= 1.0)[:, None],
                                                                     tangential(self.traction), 0.0)
        self.friction_work += 0.5 * float(np.einsum("b,bi,bi->", self.area, f, delta - self.delta))
        self.delta, self.traction, self.damage = delta, t, d
        self._unbind()  # (new arrays; the law's initiation replaced its index)
        self.force[:] = -self.area[:, None] * (self._to_global(t) if self.finite_rotation else t)
        return self.force

    def _corotate(self, x: np.ndarray) -> np.ndarray:
        """Separations (nb, 3) m in each bond's corotated frame (module docstring); keeps the
        current frame (axis of a central bond, or cos, sin of theta and the chord) for the forces."""
        i, j = self._loc.T
        d = x[j] - x[i]
        if self.along is None:  # central: the stretch along the reference normal
            L = np.linalg.norm(d, axis=1)
            self._axis = d / L[:, None]
            return (L - self._L0)[:, None] * self.normal
        a, b = self._dirs[0][:2]
        return kernels.corotate_2d(x, self._loc, a, b, self._s0, self.d0, self._local, self._rot, self._chord)

    def _to_global(self, t: np.ndarray) -> np.ndarray:
        """Tractions (nb, 3) of the corotated frames turned back to x, y, z."""
        if self.along is None:
            return np.einsum("bi,bi->b", t, self.normal)[:, None] * self._axis
        c, sn = self._rot.T
        return np.column_stack([c * t[:, 0] - sn * t[:, 1], sn * t[:, 0] + c * t[:, 1], t[:, 2]])

    def _add_spin_forces(self, f: np.ndarray) -> None:
        """The frame's share of the forces, into f (len(ids), 3) N: the bond energy's
        derivative A dPsi/dtheta = A (t_x l_y - t_y l_x) (l the corotated branch vector) times
        dtheta/ds = (-s_y, s_x) / |s|^2 on the chord s from the previous pair's midpoint to the
        next's, half on each particle of those pairs (force = minus the gradient)."""
        a, b = self._dirs[0][:2]
        kernels.add_spin_forces(f, self._loc, a, b, self.traction, self._local, self._chord, self.area)

    def apply_reference(self, backend, dt: float) -> None:
        """The reference of ``apply``: read the bonded particles, evaluate_reference, scatter."""
        F = self.evaluate_reference(backend.positions_of(self.ids), dt)
        f = kernels.scatter_pairs(self._loc, F, len(self.ids))
        if self.along is not None and self.finite_rotation:
            self._add_spin_forces(f)
        elif self.along is not None:  # the slip's gradient terms: normal forces on the neighbours
            for a, b, e_t, h_span in self._dirs:
                q = 0.5 * self.area * h_span * np.einsum("bi,bi->b", self.traction, e_t)
                kernels.add_slope_forces(f, self._loc, self.normal, q, a, b)
        loaded = np.flatnonzero(np.any(f != 0.0, axis=1))  # open, failed bonds carry nothing
        backend.add_forces(self.ids[loaded], f[loaded])

    def __getstate__(self) -> dict:
        """Pickled without the fused step's plan and binding (rebuilt on first use where the
        copy runs: an engine's worker process)."""
        d = dict(self.__dict__)
        d["_plan"], d["_bound"] = None, None
        d.pop("_rows", None), d.pop("_end", None)
        if self.force is not None:
            d["force"] = np.array(self.force)  # a view of the plan's slots
        return d

    # -- the fused step (law_kernels) -----------------------------------------------------------
    def apply(self, target, dt: float, between_passes=None) -> None:
        """One step: read the bonded particles' positions, evaluate, add the bond forces. A
        target with particle arrays (``x`` (N, 3) m, ``f`` (N, 3) N, ``rows_of(ids)``: the
        coupling layer's ModelStep, the FEM's nodes) is read and written in place by the fused
        kernels; any other (positions_of / add_forces) through a copy of its particles.
        between_passes(self): called between the bonds' pass and the particles' (the slots
        written, not yet summed: several MPI ranks exchange theirs there, rank_laws)."""
        if hasattr(target, "rows_of"):
            if self._bound is not target:  # bind once: this family's particles as rows of the target's arrays
                self._rows = np.ascontiguousarray(target.rows_of(self.ids), INDEX)
                self._end, self._bound = self._rows[self._loc], target
            self._step(target.x, target.f, self._rows, self._end, dt, between_passes)
            return
        x = np.ascontiguousarray(target.positions_of(self.ids), float)
        f = np.zeros_like(x)
        rows = np.arange(len(self.ids))
        self._step(x, f, rows, self._loc, dt)
        loaded = np.flatnonzero(np.any(f != 0.0, axis=1))  # open, failed bonds carry nothing
        target.add_forces(self.ids[loaded], f[loaded])

    def evaluate(self, x: np.ndarray, dt: float) -> np.ndarray:
        """Update the bonds from the positions x (len(ids), 3) m of the bonded particles after
        a step of dt s; returns the force (nb, 3) N on each bond's second particle."""
        x = np.ascontiguousarray(x, float)
        self._step(x, np.zeros_like(x), np.arange(len(self.ids)), self._loc, dt)
        return self.force

    def _step(self, x, f, rows, end, dt, between_passes=None) -> None:
        """The two fused passes (law_kernels) on positions x (N, 3) m, adding into f (N, 3) N;
        rows (len(ids),) and end (nb, 2): this family's particles and bond ends as rows of x."""
        if self._plan is None:
            self._plan = _FusedPlan(self)
        P = self._plan
        self.time += dt
        if P.arguments is None:
            self._bind()
        one_call = P.serial and between_passes is None  # both passes through the family's compiled plan
        if one_call:
            work, fwork, vwork, snap = law_kernels.family_step(P.compiled, x, end, rows, f, float(dt), self.time)
        else:
            head, tail = P.arguments
            work, fwork, vwork, snap = P.bonds_pass(x, end, *head, float(dt), self.time, *tail)
        self.work += work
        self.friction_work += fwork
        self.damping_work += vwork
        if snap:
            self.law.snapback += int(snap)
        if between_passes is not None:
            between_passes(self)
        if not one_call:
            P.gather_pass(P.slots_flat, P.ptr, P.entry, rows, f)

    def _pass_fields(self) -> dict:
        """The fused passes' arrays and codes (law_kernels.PLAN_FIELDS) as they are now."""
        P, law = self._plan, self.law
        if P.law == law_kernels.PLY:  # the ply law's state (other families: stand-ins)
            state = {"scale": law.strength_scale, "m0": law.m0, "mf": law.mf, "index": law.index,
                     "crushed": law.crushed}
        else:
            state = {"scale": P.none, "m0": P.none, "mf": P.none, "index": P.none, "crushed": P.no}
        return {"loc": P.loc, "d0": self.d0, "normal": self.normal, "area": self.area, "Kb": self.K_each,
                "kin": P.kin, "X_mid": P.X_mid, "dir_a": P.dir_a, "dir_b": P.dir_b, "dir_e": P.dir_e,
                "dir_h": P.dir_h, "un": P.un, "s0": P.s0, "L0": P.L0, "axis": P.axis, "local": P.local,
                "rot": P.rot, "chord": P.chord,
                "law": P.law, "hp": P.hp, "pstress": P.pstress, "inc_ptr": P.inc_ptr, "inc_bond": P.inc_bond,
                "cell": P.cell, "axes": P.axes, "aligned": P.aligned, "ply_axes": P.ply_axes, "hk": P.hk,
                "Gf": P.Gf, **state, "friction": float(self.friction), "v_reg": float(self.v_reg),
                "visc": self.damping, "damage": self.damage, "delta": self.delta, "traction": self.traction,
                "t_failed": self.t_failed, "slots": P.slots, "active": P.active, "slots_flat": P.slots_flat,
                "ptr": P.ptr, "entry": P.entry}

    def _bind(self) -> None:
        """The passes' arguments bound to the arrays the bonds hold now: bonds_pass's as tuples
        before and after (dt, time), and for the serial build the plan as one compiled argument;
        bound again after anything replaces one of those arrays (_unbind)."""
        P, named = self._plan, self._pass_fields()
        fields = [named[k] for k in law_kernels.PLAN_FIELDS]
        at = law_kernels.PLAN_FIELDS.index("visc") + 1  # (bonds_pass takes dt and the time after visc)
        P.arguments = tuple(fields[:at]), tuple(fields[at:-3])
        P.compiled = law_kernels.family_plan(**named) if P.serial else None

    def _unbind(self) -> None:
        if self._plan is not None:
            self._plan.compiled = self._plan.arguments = None

    def evaluate_only(self, mine: np.ndarray) -> None:
        """Evaluate only the bonds ``mine`` (nb,) bool from now on (one MPI rank's share,
        dem_region.rank_laws): the others' slots are zeroed, so they add nothing to the
        forces, and their rows keep what they hold (another rank updates them)."""
        if self._plan is None:
            self._plan = _FusedPlan(self)
        self._plan.active = np.flatnonzero(mine).astype(INDEX)
        self._plan.slots[~np.asarray(mine, bool)] = 0.0
        self._unbind()

    def softened(self) -> np.ndarray:
        """(nb,) share of each bond's softening branch travelled (0: elastic or not initiated,
        1: traction-free), i.e. the share of its fracture energy spent. The damage variable
        d = mf (m - m0) / (m (mf - m0)) of the bilinear laws is near 1 long before the traction
        is gone when mf >> m0 (concrete and adhesives: mf / m0 ~ 300), so crack pictures and
        crack measures use this."""
        if hasattr(self.law, "m0"):
            m0, mf = self.law.m0, self.law.mf
        else:
            dn, ds = self.split(self.delta)
            m0, mf, _ = self.law.onset_and_final(dn, np.linalg.norm(ds, axis=1))
        d = np.clip(self.damage, 0.0, 1.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            m = mf * m0 / (mf - d * (mf - m0))
            s = np.nan_to_num((m - m0) / (mf - m0), nan=1.0, posinf=1.0)
        return np.where(d > 0, np.clip(s, 0.0, 1.0), 0.0)

    def bond_stress(self) -> np.ndarray:
        """(nb, 6) Voigt Pa: mean of the two end particles' Love-Weber stresses,
        sigma_p = (1 / V_p) sum_b (A_b t_b) (x) l_b / 2 over the law bonds of particle p
        (tension positive; tractions of the last evaluation, reference branch vectors l_b)."""
        return kernels.bond_stress(self._loc, self.area[:, None] * self.traction, self.d0, self._cell, len(self.ids))

    # -- bookkeeping -----------------------------------------------------------------------------
    def stored_energy(self) -> float:
        """J, elastic energy of the current tractions: (1 - d) K |delta|^2 / 2 per area, and the
        compressive penalty K dn^2 / 2 (slice)."""
        # compiled (each ledger sample asks every family: ~30 us a family in numpy); the laws'
        # stored_density is its readable form (tests/test_law_kernels.py); only the cohesive
        # law stores energy in shear
        return law_kernels.stored_energy(self.area, self.delta, self.normal, self.damage, self.K_each,
                                         not hasattr(self.law, "initiate"))

    def dissipated_energy(self) -> float:
        """J, decohesion + friction so far (slice)."""
        return self.work - self.stored_energy()

    def decohesion_energy(self) -> float:
        """J, what decohesion alone dissipated so far (slice): the dissipation less the friction
        of closed failed faces and the dampers'."""
        return self.dissipated_energy() - self.friction_work - self.damping_work

    def force_on(self, particles: np.ndarray) -> np.ndarray:
        """(3,) N, total bond force on the set ``particles`` at the last evaluation."""
        mask = np.isin(self.pairs, particles)
        F = getattr(self, "force", np.zeros((len(self.pairs), 3)))
        return F[mask[:, 1]].sum(axis=0) - F[mask[:, 0]].sum(axis=0)

    def energies(self) -> dict[str, float]:
        stored = self.stored_energy()  # (once: each sample of the ledger asks; dissipated_energy's own)
        return {"kinetic": 0.0, "internal": stored, "dissipated": self.work - stored}

    def momentum(self) -> np.ndarray:
        return np.zeros(3)  # equal and opposite forces on particles the engine carries

    def failed(self) -> np.ndarray:
        return self.damage >= 1.0

    def checkpoint_state(self) -> dict:
        d = {"damage": self.damage, "delta": self.delta, "traction": self.traction, "t_failed": self.t_failed,
             "time": self.time, **{k: getattr(self, k) for k in WORK}}
        for k in _LAW_STATE:
            if hasattr(self.law, k):
                d["law_" + k] = getattr(self.law, k)
        return d

    def restore_state(self, d: dict) -> None:
        for k in ("damage", "delta", "traction", "t_failed"):
            setattr(self, k, np.array(d[k], float))
        self.work, self.time = float(d["work"]), float(d["time"])
        for k in WORK[1:]:  # (0 in a checkpoint written before the share was kept)
            setattr(self, k, float(d.get(k, 0.0)))
        for k in _LAW_STATE:
            if "law_" + k in d:
                v = np.array(d["law_" + k])
                setattr(self.law, k, v.astype(type(getattr(self.law, k)[0])) if v.ndim else int(v))
        self._unbind()


class _FusedPlan:
    """What the fused kernels need of one LawBonds, built once: kinematics and law codes,
    neighbour tables, buffers (nothing is allocated per step) and the incidence lists, the
    slots aimed at each particle in the order the reference (apply_reference) adds them."""

    def __init__(self, bonds: LawBonds):
        nb, law = len(bonds.pairs), bonds.law
        big = nb >= law_kernels.PARALLEL_BONDS and law_kernels.THREADS_ALLOWED
        self.serial, self.compiled, self.arguments = not big, None, None  # (LawBonds._bind)
        self.bonds_pass = law_kernels.bonds_pass if big else law_kernels.bonds_pass_serial
        self.gather_pass = law_kernels.gather_pass if big else law_kernels.gather_pass_serial
        self.loc = np.ascontiguousarray(bonds._loc, INDEX)
        self.none, self.no = np.zeros(0), np.zeros(0, bool)  # stand-ins for what a family lacks
        dirs = bonds._dirs if bonds.along is not None else []
        if bonds.finite_rotation:
            self.kin = law_kernels.FRAME_2D if bonds.along is not None else law_kernels.CENTRAL
        else:
            self.kin = law_kernels.FIXED
        self.dir_a = np.array([d[0] for d in dirs], INDEX).reshape(len(dirs), nb)
        self.dir_b = np.array([d[1] for d in dirs], INDEX).reshape(len(dirs), nb)
        self.dir_e = np.array([d[2] for d in dirs], float).reshape(len(dirs), nb, 3)
        self.dir_h = np.array([d[3] for d in dirs], float).reshape(len(dirs), nb)
        self.X_mid = np.ascontiguousarray(getattr(bonds, "_X_mid", np.zeros((nb, 3))))
        self.un = np.zeros(nb)
        self.s0 = np.ascontiguousarray(getattr(bonds, "_s0", np.zeros((nb, 3))))
        self.L0 = np.ascontiguousarray(getattr(bonds, "_L0", np.zeros(nb)))
        self.axis, self.local, self.chord = np.zeros((nb, 3)), np.zeros((nb, 3)), np.zeros((nb, 3))
        self.rot = np.zeros((nb, 2))
        if self.kin == law_kernels.CENTRAL:
            bonds._axis = self.axis
        elif self.kin == law_kernels.FRAME_2D:
            bonds._local, bonds._rot, bonds._chord = self.local, self.rot, self.chord
        n = len(bonds.ids)
        if hasattr(law, "initiate") and not law.never_initiates:
            self.law = law_kernels.PLY
            k = law.strengths
            self.hk = kernels.hoffman_coefficients(tuple(float(v) for v in (k.Xt, k.Xc, k.Yt, k.Yc, k.Zt, k.Zc,
                                                                              k.S23, k.S13, k.S12)))
            self.hp = np.zeros(7)
            self.pstress = np.zeros((n, 6))
            self.cell = np.ascontiguousarray(bonds._cell, float)
            # the few distinct ply orientations, and each bond's (72 bytes less to read per bond)
            self.axes, ply_axes = np.unique(law.axes.reshape(nb, 9), axis=0, return_inverse=True)
            self.axes = np.ascontiguousarray(self.axes.reshape(-1, 3, 3))
            self.ply_axes = np.asarray(ply_axes, INDEX).ravel()
            aligned = [kernels.aligned_voigt(R) for R in self.axes]  # 0 / 90 plies: no rotation to do
            self.aligned = (np.array(aligned, INDEX) if all(a is not None for a in aligned)
                            else np.full((1, 6), -1, INDEX))
            self.Gf = np.ascontiguousarray(law.Gf)
            # each particle's bonds in bond order (its Love-Weber stress)
            ends = self.loc.ravel()
            order = np.argsort(ends, kind="stable")
            self.inc_bond = (order // 2).astype(INDEX)
            self.inc_ptr = np.concatenate([[0], np.cumsum(np.bincount(ends, minlength=n))]).astype(INDEX)
        else:
            elastic = hasattr(law, "initiate")
            self.law = law_kernels.ELASTIC if elastic else law_kernels.HASHIN
            self.hk = (1.0,) * 9
            self.hp = np.zeros(7) if elastic else \
                np.array([law.K, law.Z0, law.R0, law.GIc, law.GIIc, law.eta, float(law.mixed_mode == "bk")])
            self.pstress, self.cell = np.zeros((0, 6)), np.zeros(0)
            self.axes, self.ply_axes, self.Gf = np.zeros((0, 3, 3)), np.zeros(0, INDEX), np.zeros((0, 1))
            self.aligned = np.full((1, 6), -1, INDEX)
            self.inc_bond, self.inc_ptr = np.zeros(0, INDEX), np.zeros(n + 1, INDEX)
        # slots: 0 the force on the second end (the first takes minus it), then per tangent one
        # on the next pair (b) and one on the previous pair (a); entries sorted by (particle,
        # phase, bond, order), each 2 x slot (+ 1: minus sign)
        S = 1 + 2 * len(dirs)
        if 2 * nb * S >= 2**31:
            raise ValueError(f"{nb} law bonds: past the fused step's 32-bit indices")
        self.slots = np.zeros((nb, S, 3))
        self.slots_flat = self.slots.reshape(nb * S, 3)
        self.active = np.arange(nb, dtype=INDEX)  # the bonds this process evaluates (LawBonds.evaluate_only)
        bonds.force = self.slots[:, 0]
        m = np.arange(nb)
        part, key = [self.loc[:, 1], self.loc[:, 0]], [(0, 0), (0, 1)]
        slot = [2 * m * S, 2 * m * S + 1]
        # the reference's order within a bond: slope terms b0, b1, a0, a1; spin b0, a0, b1, a1
        order = (0, 2, 1, 3) if self.kin == law_kernels.FRAME_2D else (0, 1, 2, 3)
        for t in range(len(dirs)):
            for (prev, e), sub in zip(((0, 0), (0, 1), (1, 0), (1, 1)), order):  # prev: 0 pair b, 1 pair a
                part.append(self.loc[(self.dir_a if prev else self.dir_b)[t], e])
                key.append((1 + t, sub))
                slot.append(2 * (m * S + 1 + 2 * t + prev))
        particle = np.concatenate(part)
        phase = np.concatenate([np.full(nb, k[0]) for k in key])
        sub = np.concatenate([np.full(nb, k[1]) for k in key])
        bond = np.tile(m, len(key))
        by = np.lexsort((sub, bond, phase, particle))
        self.entry = np.concatenate(slot)[by].astype(INDEX)
        self.ptr = np.concatenate([[0], np.cumsum(np.bincount(particle, minlength=n))]).astype(INDEX)
