"""YADE adapter (in-process; the only module that imports yade).

Bonds become CohFrictPhys interactions created explicitly from the neutral bond list
(``utils.createInteraction``), with their stiffnesses set per bond and their rest gap taken
from the initial configuration (``unp``), so the engine integrates exactly the neutral
scene. The engine list runs the NewtonIntegrator first and the coupling hook (a PyRunner)
last: one ``O.step()`` moves the particles with the forces of x_k, computes the forces at
x_{k+1} and hands over to the orchestrator, which sets the interface velocities for the next
move. (Newton's "forces last reset" warning that this order triggers is silenced.)
"""
from __future__ import annotations

import atexit
import contextlib
import io
import os
import shutil
import signal
import sys
import threading
from pathlib import Path
from typing import Callable

import numpy as np

from ..scene import DemScene

YADE_PY = "/usr/lib/x86_64-linux-gnu/yade-double/py"
_HOOK = "_femdem_between"
_UNBREAKABLE = 1e300


_INTERRUPTS = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def _interrupts_after_the_step():
    """SIGINT and SIGTERM noted while YADE steps, and delivered again (to the handlers they had)
    once the advance's steps are over: a Python handler runs at the next bytecode, which may be in the
    PyRunner's own command, before the hook's ``try`` (an interrupted YADE run ended so as an
    internal error: seen once in CI's suite, session 44)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[int] = []
    previous = {s: signal.signal(s, lambda signum, frame: caught.append(signum)) for s in _INTERRUPTS}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, signal.SIG_DFL if handler is None else handler)
        if caught:
            signal.raise_signal(caught[0])


def _import_yade():
    # one OpenMP thread unless the user asks for more: as fast for the small zones measured
    # here (8.7 s vs 9.0 s wall, half the CPU) and it leaves the other core to the FEM side
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    # the process's OpenMP runtime is YADE's: the law kernels stay serial, and a count set
    # before (an earlier parallel launch in this process) goes back to the one asked for
    from physics import law_kernels
    law_kernels.THREADS_ALLOWED = False
    import ctypes
    try:
        ctypes.CDLL("libgomp.so.1").omp_set_num_threads(int(os.environ["OMP_NUM_THREADS"]))
    except (OSError, ValueError):
        pass
    if YADE_PY not in sys.path:
        sys.path.insert(1, YADE_PY)
    first = "yade" not in sys.modules
    with contextlib.redirect_stdout(io.StringIO()):  # yade prints 'Using python version' on import
        import yade
        import yade.config
        import yade._utils
        from yade import wrapper
    if first:  # YADE makes /tmp/yade-XXXXXX at import and removes it only at its own executable's exit
        atexit.register(shutil.rmtree, os.path.dirname(yade.O.tmpFilename()), ignore_errors=True)
    return yade, wrapper


def _rows(vectors) -> np.ndarray:
    """Vector3 sequence -> (k, 3) array. Indexing the components is 8x faster than tuple(v)
    (measured: 0.61 ms against 4.7 ms for 750 forces)."""
    return np.array([(v[0], v[1], v[2]) for v in vectors], dtype=float).reshape(-1, 3)


class YadeBackend:
    """DEM back-end on YADE's global scene ``O`` (one per process; ``build`` resets it)."""

    name = "yade"
    native_laws = ("elastic",)

    def __init__(self):
        self.yade, self.w = _import_yade()
        self.version = self.yade.config.version
        self.O = self.yade.O
        self._between: Callable[[], None] | None = None
        self._hook_error: BaseException | None = None  # raised in the hook, re-raised after the step
        self._starting = False  # inside start's zero step (energies() completes the half step there too)

    # -- set-up ----------------------------------------------------------------------------
    def build(self, scene: DemScene) -> None:
        import __main__

        O, w, utils = self.O, self.w, self.yade.utils
        O.reset()
        self.scene = scene
        hertz = scene.contact == "hertz_mindlin"
        mats = {}  # one YADE material per distinct (E, nu, rho)
        for key in sorted(set(zip(scene.young.tolist(), scene.poisson.tolist(), scene.density.tolist()))):
            E, nu, rho = key
            common = dict(young=E, poisson=nu, density=rho, frictionAngle=np.radians(scene.friction_deg))
            mats[key] = O.materials.append(w.FrictMat(**common) if hertz else w.CohFrictMat(
                **common, isCohesive=True, momentRotationLaw=False,
                normalCohesion=_UNBREAKABLE, shearCohesion=_UNBREAKABLE))
        V3 = self.yade.Vector3
        self.ids = O.bodies.append([utils.sphere(V3(*x), float(r), material=mats[(E, nu, rho)])
                                    for x, r, E, nu, rho in zip(scene.x, scene.radius, scene.young.tolist(),
                                                                scene.poisson.tolist(), scene.density.tolist())])
        for b, m, I, v in zip(O.bodies, scene.mass, scene.inertia, scene.velocity):
            b.state.mass = float(m)  # per-particle density
            b.state.inertia = V3(I, I, I)
            b.state.vel = V3(*v)
            if scene.plane:
                b.state.blockedDOFs = "zXY"
        for i in scene.groups.get("fixed", []):
            O.bodies[int(i)].state.blockedDOFs = "xyzXYZ"
        if scene.walls:  # rigid planes: a stiff material so that E* = E / (1 - nu^2) of the particle
            wmat = O.materials.append(w.FrictMat(young=1e6 * float(scene.young.max()), poisson=float(scene.poisson[0]),
                                                 density=1.0, frictionAngle=np.radians(scene.friction_deg)))
            self.wall_ids = O.bodies.append([utils.wall(wl.position, axis=wl.axis, sense=wl.sense, material=wmat)
                                             for wl in scene.walls])
        if hertz:
            e = float(scene.restitution)
            self.law = w.Law2_ScGeom_MindlinPhys_Mindlin(calcEnergy=True)
            ig2 = [w.Ig2_Sphere_Sphere_ScGeom(), w.Ig2_Wall_Sphere_ScGeom()]
            ip2 = (w.Ip2_FrictMat_FrictMat_MindlinPhys(en=e, es=e) if e < 1 else w.Ip2_FrictMat_FrictMat_MindlinPhys())
        else:
            self.law = w.Law2_ScGeom6D_CohFrictPhys_CohesionMoment()
        # bonds may join spheres that do not touch (diagonals of a lattice, gaps of a random
        # packing): YADE keeps an interaction only while it is within the detection range
        i, j = scene.bonds.T if len(scene.bonds) else (np.zeros(0, int),) * 2
        reach = np.linalg.norm(scene.x[i] - scene.x[j], axis=1) / (scene.radius[i] + scene.radius[j])
        self.detection = max(1.0, 1.2 * float(reach.max())) if reach.size else 1.0
        setattr(__main__, _HOOK, self._hook)
        import yade.log
        yade.log.setLevel("NewtonIntegrator", yade.log.ERROR)
        O.engines = [
            w.NewtonIntegrator(damping=float(scene.local_damping)),
            w.ForceResetter(),
            w.InsertionSortCollider([w.Bo1_Sphere_Aabb(aabbEnlargeFactor=self.detection), w.Bo1_Wall_Aabb()]),
            w.InteractionLoop(ig2, [ip2], [self.law]) if hertz else
            w.InteractionLoop([w.Ig2_Sphere_Sphere_ScGeom6D(interactionDetectionFactor=self.detection)],
                              [w.Ip2_CohFrictMat_CohFrictMat_CohFrictPhys(setCohesionNow=False,
                                                                          setCohesionOnNewContacts=False)],
                              [self.law]),
            w.PyRunner(command=f"{_HOOK}()", iterPeriod=1, initRun=True),
        ]
        for (i, j), kn, ks, fb in zip(scene.bonds, scene.kn, scene.ks, scene.bond_strength):
            I = utils.createInteraction(int(i), int(j))
            ph = I.phys
            ph.kn, ph.ks = float(kn), float(ks)
            ph.cohesionBroken = False
            breakable = np.isfinite(fb)
            ph.normalAdhesion = float(fb) if breakable else _UNBREAKABLE
            ph.shearAdhesion = _UNBREAKABLE
            ph.fragile = bool(breakable)  # brittle: the bond is gone once its normal force exceeds fb
            ph.unp = I.geom.penetrationDepth  # the initial configuration is stress free
        self.prescribed = np.zeros(0, int)
        # cached (attribute lookups dominate bulk access); particles only, walls come after them
        self._states = [b.state for b in O.bodies][: scene.n]

    def critical_dt(self) -> float:
        return self.scene.critical_dt()

    def set_dt(self, dt: float) -> None:
        self.O.dt = self._dt = float(dt)

    # -- stepping ----------------------------------------------------------------------------
    def _hook(self) -> None:
        """The coupling hook, from YADE's PyRunner. What it raises is kept and raised again
        once the step is over (advance): through the PyRunner it became a RuntimeError("PyRunner
        error") with the traceback printed on the terminal. (Ctrl-C and SIGTERM wait for the
        step's end: _interrupts_after_the_step.)"""
        if self._between is not None:
            try:
                self._between()
            except BaseException as exc:
                self._hook_error = exc

    def start(self, between: Callable[[], None] | None = None) -> None:
        dt, self.O.dt = self.O.dt, 0.0  # a step of zero length: forces at x_0, then the hook
        self._starting = True  # its hook reads forces at x_0 with YADE's iter still 0
        try:
            self.advance(between)
        finally:
            self._starting = False
            self.O.dt = dt

    def advance(self, between: Callable[[], None] | None = None, steps: int = 1) -> None:
        self._between = between
        if callable(signal.getsignal(signal.SIGINT)) or callable(signal.getsignal(signal.SIGTERM)):
            with _interrupts_after_the_step():  # (delivered at the end of these steps: at most a sample's)
                self._steps(steps)
        else:  # nothing in Python would run on them (an engine's worker, step by step): as they come
            self._steps(steps)

    def _steps(self, steps: int) -> None:
        for _ in range(steps):
            self.O.step()
            if self._hook_error is not None:
                exc, self._hook_error = self._hook_error, None
                raise exc

    # -- interface data ----------------------------------------------------------------------
    def prescribe(self, ids: np.ndarray, dofs: str = "xyz") -> None:
        """Slave the translations ``dofs`` of particles ``ids`` (all three and the rotations by
        default); their other degrees of freedom stay dynamic."""
        ids = np.asarray(ids, int)
        if dofs == "xyz":  # fully slaved: their motion (and kinetic energy) belongs to the driver
            self.prescribed = np.union1d(self.prescribed, ids)
            # slaved particles must not touch each other: the body they follow (the FEM)
            # already carries those forces; YADE skips pairs sharing avoidSelfInteractionMask
            for i in ids.tolist():
                self.O.bodies[i].groupMask = 3
            self.O.engines[2].avoidSelfInteractionMask = 2
        self._partial = getattr(self, "_partial", {})
        blocked = dofs + ("XYZ" if dofs == "xyz" else ("zXY" if self.scene.plane else ""))
        for i in ids.tolist():  # a particle's prescriptions add up (a symmetry plane and a support)
            both = self._states[i].blockedDOFs + blocked
            self._states[i].blockedDOFs = "".join(sorted(set(both), key=both.index))
            if dofs == "xyz":
                self._partial.pop(i, None)
            elif i not in self.prescribed:
                self._partial[i] = sorted(set(self._partial.get(i, [])) | {"xyz".index(c) for c in dofs})
            if dofs != "xyz":  # kept past a full prescription: what a release leaves held
                self._planes = getattr(self, "_planes", {})
                self._planes[i] = set(self._planes.get(i, ())) | {"xyz".index(c) for c in dofs}

    def release(self, ids: np.ndarray) -> None:
        """Particles ``ids`` no longer slaved: they move with their forces and touch the others
        again (a symmetry plane's partial prescription stays)."""
        ids = np.asarray(ids, int)
        self.prescribed = np.setdiff1d(self.prescribed, ids)
        planes = getattr(self, "_planes", {})
        for i in ids.tolist():
            self.O.bodies[i].groupMask = 1
            held = "".join("xyz"[k] for k in planes.get(i, ())) + ("zXY" if self.scene.plane else "")
            self._states[i].blockedDOFs = held
            if i in planes:
                self._partial[i] = sorted(planes[i])

    def set_all_velocities(self, v: np.ndarray) -> None:
        """Every particle's velocity (n, 3) m/s as ``velocities()`` reports it, written whole:
        a model continued on this engine starts from it."""
        V3 = self.yade.Vector3
        for s, vi in zip(self._states, np.asarray(v, float).tolist()):
            s.vel = V3(*vi)

    def set_velocities(self, ids: np.ndarray, v: np.ndarray) -> None:
        V3, states, partial = self.yade.Vector3, self._states, getattr(self, "_partial", {})
        for i, vi in zip(ids.tolist() if hasattr(ids, "tolist") else ids, np.asarray(v, float).tolist()):
            if i in partial:  # keep the dynamic components
                cur = states[i].vel
                vi = [vi[k] if k in partial[i] else cur[k] for k in range(3)]
            states[i].vel = V3(vi[0], vi[1], vi[2])

    def bond_count(self) -> int:
        """Bonds still intact (brittle bonds are erased by YADE when they break)."""
        return sum(1 for I in self.O.interactions if I.isReal and not getattr(I.phys, "cohesionBroken", True))

    def bond_state(self) -> dict:
        """{intact, broken, broken_list}: broken_list rows (i, j, t s, x, y, z m) of every bond
        found broken since build, with the time and mid-point of the call that found it
        (call at output steps: the time resolution is the caller's)."""
        if not hasattr(self, "_broken"):
            self._broken: list[tuple] = []
        alive = {(min(I.id1, I.id2), max(I.id1, I.id2)) for I in self.O.interactions
                 if I.isReal and not getattr(I.phys, "cohesionBroken", True)}
        known = {(i, j) for i, j, *_ in self._broken}
        x = None
        for i, j in map(tuple, np.sort(self.scene.bonds, axis=1).tolist()):
            if (i, j) not in alive and (i, j) not in known:
                x = self.positions() if x is None else x
                mid = 0.5 * (x[i] + x[j])
                self._broken.append((i, j, float(self.O.time), *mid.tolist()))
        return {"intact": len(alive), "broken": len(self._broken), "broken_list": list(self._broken)}

    def forces(self, ids: np.ndarray) -> np.ndarray:
        f = self.O.forces.f
        return _rows(map(f, np.asarray(ids, int).tolist()))

    def forces_into(self, ids: np.ndarray, out: np.ndarray) -> None:
        out[:] = self.forces(ids)  # YADE reads one body at a time: no bulk path to spare

    def add_forces(self, ids: np.ndarray, F: np.ndarray) -> None:
        """Forces (k, 3) N added to particles ``ids`` for the next move (call from the hook).
        YADE has no bulk write: one addF per particle, a list converted by boost (0.38 us per
        particle, against 1.32 us through a Vector3: benchmarks/coupled_step.py --yade-transfer)."""
        add = self.O.forces.addF
        for i, row in zip(np.asarray(ids, int).tolist(), np.asarray(F, float).tolist()):
            add(i, row)

    def positions_of(self, ids: np.ndarray) -> np.ndarray:
        return self.positions()[np.asarray(ids, int)]

    def read_positions(self, ids: np.ndarray, out: np.ndarray) -> None:
        """out (k, 3) m <- the positions of particles ``ids``: YADE's one bulk read is of every
        sphere, one coordinate at a time (coordsAndDisplacements: 0.40 us per particle, against
        1.21 us reading each body's state)."""
        np.take(self.positions(), ids, axis=0, out=out)

    positions_into = read_positions  # (the penalty tie's read of its particles, each step)

    def positions(self) -> np.ndarray:
        coords = self.yade._utils.coordsAndDisplacements
        x = np.column_stack([np.asarray(coords(k)[0], float) for k in range(3)])
        return x[: self.scene.n]  # every body in id order: the particles, then the walls

    def velocities(self) -> np.ndarray:
        return _rows(s.vel for s in self._states)

    def energies(self) -> dict[str, float]:
        """Kinetic energy of the free particles (prescribed ones belong to the FEM side) and
        elastic bond energy, J, both at the time level of the last force evaluation: YADE's
        leapfrog velocities lag half a step, so v_k = v_{k-1/2} + dt/2 F_k / m, also in the
        start's hook (a zero step), where a zone grown mid-run carries v_{k-1/2} and forces."""
        m = self.scene.mass.copy()
        v = self.velocities()
        evaluated = self.O.iter > 0 or self._starting
        if evaluated:
            dt = getattr(self, "_dt", self.O.dt)
            v += 0.5 * dt * self.forces(np.arange(self.scene.n)) / m[:, None]
        m[self.prescribed] = 0.0
        for i, comps in getattr(self, "_partial", {}).items():
            v[i, comps] = 0.0  # the driven components of partly prescribed particles
        I = self.scene.inertia.copy()
        I[self.prescribed] = 0.0
        w = _rows(s.angVel for s in self._states)
        # the law's energy functions crash YADE before its first force evaluation (bonds are
        # built stress free); its shear energy divides by ks: bonds with ks = 0 are left out
        elastic, dissipated = 0.0, 0.0
        if evaluated and self.scene.contact == "hertz_mindlin":
            law = self.law
            elastic = law.normElastEnergy() + law.shearEnergy
            dissipated = law.normDampDissip + law.shearDampDissip + law.frictionDissipation
        elif evaluated:
            elastic = self.law.normElastEnergy()
            if self.scene.ks.min() > 0:
                elastic += self.law.shearElastEnergy()
            elif self.scene.ks.max() > 0:
                elastic += sum(0.5 * i.phys.shearForce.squaredNorm() / i.phys.ks
                               for i in self.O.interactions if i.isReal and i.phys.ks > 0)
        kinetic = 0.5 * float(np.einsum("n,ni,ni->", m, v, v) + np.einsum("n,ni,ni->", I, w, w))
        return {"kinetic": kinetic, "elastic": float(elastic), "dissipated": float(dissipated)}

    # -- checkpoint ----------------------------------------------------------------------------
    restart_file = "dem.yade.bz2"  # YADE picks the format from the name: compressed binary
    supports_checkpoint = True

    def checkpoint(self, path) -> None:
        """Save the whole engine state (YADE's own format), atomically: a kill mid-write
        leaves the previous checkpoint intact. YADE's file holds no force container, which
        the next move needs (Newton runs first in a step), so every body's force and torque
        go beside it (``path``.forces.npy, (bodies, 6) N, N m): the engine's own and what the
        hook added (the coupling layer's laws, impactors, a penalty tie)."""
        path = str(path)
        tmp = path + ".tmp.yade.bz2"
        self.O.save(tmp)
        os.replace(tmp, path)
        f, t = self.O.forces.f, self.O.forces.t
        forces = np.array([[*f(i), *t(i)] for i in range(len(self.O.bodies))], float)
        # stamped with the iteration, so that a restore never pairs them with another state
        # (a kill between the two writes, where a caller reuses a path)
        np.save(path + ".forces.npy", np.vstack([forces, np.full((1, 6), float(self.O.iter))]))

    def restore(self, path) -> None:
        """Load a checkpoint and set the force container as it was saved (the next move's
        forces): the continuation is bit-identical. Without them (a checkpoint written before
        they were kept, or forces of another iteration) the forces are recomputed at its
        positions by a step of zero length, without the hook's: a coupled beam resumed so
        moved first without its impactor and law bonds, 4 % off in momentum. A file YADE
        cannot read, or one of another model (another body count), is a ValueError: a
        checkpoint that does not fit, not an engine failure."""
        bodies = len(self.O.bodies)
        try:
            self.O.load(str(path))
        except RuntimeError as exc:  # (YADE's boost archive and bzip2 errors)
            raise ValueError(f"YADE cannot load {path}: {exc}") from None
        if len(self.O.bodies) != bodies:
            raise ValueError(f"{path} holds {len(self.O.bodies)} bodies, this model {bodies}")
        self._states = [b.state for b in self.O.bodies][: self.scene.n]
        self.law = self.O.engines[3].lawDispatcher.functors[0]
        saved = Path(str(path) + ".forces.npy")
        rows = np.load(saved) if saved.exists() else None
        if rows is not None and rows[-1, 0] == self.O.iter and len(rows) == len(self.O.bodies) + 1:
            forces, V3 = self.O.forces, self.yade.Vector3
            forces.reset()
            for i, row in enumerate(rows[:-1].tolist()):
                forces.addF(i, V3(*row[:3]))
                forces.addT(i, V3(*row[3:]))
            return
        between, self._between = self._between, None
        dt, self.O.dt = self.O.dt, 0.0
        self.O.step()
        self.O.dt = dt
        self._between = between

    def finalize(self) -> None:
        import __main__

        self._between = None
        if hasattr(__main__, _HOOK):
            delattr(__main__, _HOOK)
        self.O.reset()
