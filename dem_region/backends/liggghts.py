"""LIGGGHTS-PUBLIC 3.8 adapter (in-process through libliggghts' C API; the only module that
loads it).

The neutral scene becomes a data file (atom style hybrid granular molecular) with harmonic
bonds, one bond type per (stiffness, rest length) pair, K = kn / 2 because LAMMPS' harmonic
energy is K (r - r0)^2. All bonded particles share one molecule and granular contacts inside
a molecule are excluded (special_bonds does not reach the granular neighbour list), so a
bond is the only interaction of its pair, as in the YADE adapter. Unbonded particles touch
through the Hertz model with the scene's restitution. Arrays are zero-copy numpy views of
LIGGGHTS' x, v, f, omega (atoms keep their order: map array, sort off, one process).

Stepping (velocity Verlet, ``run 1 pre no post no``) leaves on-step velocities; the contract's
``velocities`` returns the leapfrog half-step ones (v - dt/2 f/m) so both engines feed the
coupled clock the same time level. Prescribed particles: ``fix store/force`` (their force
from the rest of the scene) then ``fix setforce 0 0 0`` and a written velocity.

Added forces (penalty ties, bond laws and impactors the coupling layer evaluates): the hook
runs after the step's force evaluation and final half kick, so an added force f goes into
LIGGGHTS' force array (the next step's first half kick uses it) and its missing final half
kick dt/2 f/m into the velocity: exactly velocity Verlet with f included, no fix needed. On
held particles (setforce) the added force is only reported by ``forces`` (their motion is
prescribed). Partial prescriptions (a symmetry plane): ``fix setforce`` on those components.

Brittle bonds and Cundall damping, which this build lacks, are evaluated on the same arrays
(lammps_family). Bonded particles share one molecule, so fragments of a bonded
zone do not touch through the granular model (YADE's do); law bonds keep their compressive
contact.
"""
from __future__ import annotations

import ctypes
import os
import shutil
import sys
from contextlib import contextmanager
from typing import Callable

import numpy as np
from ..scene import DemScene
from .base import scratch_dir
from .lammps_family import VerletArrays

LIB = "libliggghts.so.3"


class LiggghtsBackend(VerletArrays):
    """DEM back-end on one LIGGGHTS instance (several may live in one process)."""

    name = "liggghts"
    native_laws = ("elastic",)

    def __init__(self):
        self.lib = ctypes.CDLL(LIB, ctypes.RTLD_GLOBAL)
        self.lib.lammps_command.restype = ctypes.c_char_p
        self.lib.lammps_extract_atom.restype = ctypes.c_void_p
        self.lib.lammps_extract_fix.restype = ctypes.c_void_p
        self.version = "3.8.0"
        self.h = None

    # -- set-up ----------------------------------------------------------------------------
    def _cmd(self, text: str) -> None:
        for line in text.strip().splitlines():
            self.lib.lammps_command(self.h, line.strip().encode())

    def build(self, scene: DemScene) -> None:
        missing = self._unsupported(scene)
        if missing:
            raise NotImplementedError(f"liggghts adapter: {missing} is not available on this engine yet")
        self.scene = scene
        self.tmp = scratch_dir("liggghts")
        # LIGGGHTS ends the process on an input error: its log (in the scene's temp dir, or on
        # screen with FEMDEM_LIGGGHTS_SCREEN=1) is where the reason is
        argv = [b"liggghts", b"-log", str(self.tmp / "log.liggghts").encode()]
        if not os.environ.get("FEMDEM_LIGGGHTS_SCREEN"):  # (a -screen file name would be a file)
            argv += [b"-screen", b"none"]
        args = (ctypes.c_char_p * len(argv))(*argv)
        self.h = ctypes.c_void_p()
        if os.environ.get("FEMDEM_LIGGGHTS_SCREEN"):
            self.lib.lammps_open_no_mpi(len(argv), args, ctypes.byref(self.h))
        else:  # a second instance in one process warns of its style tables' "collisions" (harmless)
            with _std_streams_to(self.tmp / "streams.liggghts"):
                self.lib.lammps_open_no_mpi(len(argv), args, ctypes.byref(self.h))
        n = scene.n
        types, btype = self._bond_types(scene)
        lo, hi = scene.x.min(axis=0) - 10 * scene.radius.max(), scene.x.max(axis=0) + 10 * scene.radius.max()
        mats, atype = np.unique(np.column_stack([scene.young, scene.poisson]), axis=0, return_inverse=True)
        if scene.walls:  # the walls' material is one more atom type (no atom has it)
            mats = np.vstack([mats, self.wall_material()])
        lines = ["LIGGGHTS data (femdem)", "", f"{n} atoms", f"{len(scene.bonds)} bonds", f"{len(mats)} atom types",
                 f"{max(1, len(types))} bond types",
                 *(f"{a:.17g} {b:.17g} {c}lo {c}hi" for a, b, c in zip(lo, hi, "xyz")), "", "Atoms", ""]
        mol = 1 if len(scene.bonds) else None
        lines += [f"{k + 1} {t + 1} {x:.17g} {y:.17g} {z:.17g} {2 * r:.17g} {rho:.17g} {mol or k + 1}"
                  for k, ((x, y, z), r, rho, t) in enumerate(zip(scene.x, scene.radius, scene.density, atype))]
        if len(scene.bonds):
            lines += ["", "Bonds", ""] + [f"{k + 1} {t + 1} {a + 1} {b + 1}"
                                          for k, (t, (a, b)) in enumerate(zip(btype, scene.bonds))]
        (self.tmp / "scene.data").write_text("\n".join(lines) + "\n")
        nt = len(mats)
        Es = " ".join(f"{E:.17g}" for E in mats[:, 0])
        nus = " ".join(f"{nu:.17g}" for nu in mats[:, 1])
        e = " ".join([f"{max(float(scene.restitution), 1e-3):.17g}"] * nt * nt)
        mu = " ".join([f"{np.tan(np.radians(scene.friction_deg)):.17g}"] * nt * nt)
        self._cmd(f"""
            units si
            hard_particles yes
            atom_style hybrid granular molecular
            atom_modify map array sort 0 0
            boundary m m m
            newton off
            communicate single vel yes
            read_data {self.tmp / 'scene.data'}
            neighbor {0.2 * scene.radius.min():.17g} bin
            neigh_modify delay 0
            fix m1 all property/global youngsModulus peratomtype {Es}
            fix m2 all property/global poissonsRatio peratomtype {nus}
            fix m3 all property/global coefficientRestitution peratomtypepair {nt} {e}
            fix m4 all property/global coefficientFriction peratomtypepair {nt} {mu}
            pair_style gran model hertz tangential history
            pair_coeff * *
        """)
        # each step is a ``run 1``, whose thermo lines went to the log: 313 bytes and a kinetic
        # energy and volume computed per step. The step alone: about 24 -> 17 us (168 atoms)
        self._cmd("thermo_style custom step")
        if len(scene.bonds):
            self._cmd("bond_style harmonic\nneigh_modify exclude molecule all")
            for t, (kn, length) in enumerate(types):
                self._cmd(f"bond_coeff {t + 1} {kn / 2:.17g} {length:.17g}")
        for k, w in enumerate(scene.walls):  # primitive planes (both sides touch)
            self._cmd(f"fix wall{k} all wall/gran model hertz tangential history primitive type {nt} "
                      f"{'xyz'[w.axis]}plane {w.position:.17g}")
        self._cmd("fix integ all nve/sphere")
        # every particle's force before any setforce (held and partly held ones report it)
        self._cmd("fix sf all store/force")
        if scene.plane:
            self._cmd("fix plane all setforce NULL NULL 0.0")  # quasi-2D: no out-of-plane motion
        self.X, self.V, self.F = (self._array(k, 3) for k in ("x", "v", "f"))
        self.W = self._array("omega", 3)
        self.T = self._array("torque", 3)
        self.ids_order = np.ctypeslib.as_array(ctypes.cast(self.lib.lammps_extract_atom(self.h, b"id"),
                                                           ctypes.POINTER(ctypes.c_int)), shape=(n,))
        if not np.array_equal(self.ids_order, np.arange(1, n + 1)):
            raise RuntimeError("liggghts adapter: atoms are not in id order")
        self.V[:] = scene.velocity
        self.mass = scene.mass
        self._bond_K = types[btype, 0] / 2 if len(scene.bonds) else np.zeros(0)
        self._bond_r0 = types[btype, 1] if len(scene.bonds) else np.zeros(0)
        self.prescribed = np.zeros(0, int)
        self._driven = np.zeros((n, 3), bool)  # components a symmetry plane's setforce holds
        self._n_partial = 0
        self._added = np.zeros((n, 3))  # forces added to held particles since the last step (reported only)
        self._store = None
        fixed = scene.groups.get("fixed", np.zeros(0, int))
        if len(fixed):
            self._group("fixed", fixed)
            self._cmd("fix fixed fixed setforce 0 0 0")
            self.V[fixed] = 0.0
        self._init_extras(scene)

    def _array(self, name: str, cols: int) -> np.ndarray:
        p = ctypes.cast(self.lib.lammps_extract_atom(self.h, name.encode()), ctypes.POINTER(ctypes.POINTER(ctypes.c_double)))
        return np.ctypeslib.as_array(p[0], shape=(self.scene.n, cols))

    # -- stepping ----------------------------------------------------------------------------
    def start(self, between: Callable[[], None] | None = None) -> None:
        self._cmd("run 0")
        self._refresh_store()
        self._setup_needed = False  # (the fixes added before it are set up)
        self._hook_phase(between)

    def advance(self, between: Callable[[], None] | None = None, steps: int = 1) -> None:
        for _ in range(steps):
            self._advance_one(between)

    def _advance_one(self, between: Callable[[], None] | None) -> None:
        if getattr(self, "_setup_needed", False):  # fixes added since the last run need a setup
            self._setup_keeping_added()
        x_old = self._step_begin()
        self.lib.lammps_command(self.h, b"run 1 pre no post no")
        self._step_end(x_old)
        self._hook_phase(between)

    def _state(self) -> dict[str, np.ndarray]:
        return {"x": self.X, "v": self.V, "f": self.F, "omega": self.W, "torque": self.T}

    def _omega(self) -> np.ndarray:
        return self.W

    def _after_setup(self) -> None:
        self._refresh_store()

    # -- interface data ----------------------------------------------------------------------
    def _refresh_store(self) -> None:
        """View of the store/force fix's per-atom array (allocated by the first run)."""
        p = ctypes.cast(self.lib.lammps_extract_fix(self.h, b"sf", 1, 2, 0, 0),
                        ctypes.POINTER(ctypes.POINTER(ctypes.c_double)))
        self._store = np.ctypeslib.as_array(p[0], shape=(self.scene.n, 3))

    def finalize(self) -> None:
        if self.h is not None:
            self.lib.lammps_close(self.h)
            self.h = None
        if getattr(self, "tmp", None):
            shutil.rmtree(self.tmp, ignore_errors=True)


@contextmanager
def _std_streams_to(path):
    """The process's stdout and stderr (file descriptors 1, 2) appended to ``path`` meanwhile:
    a second LIGGGHTS instance in one process prints its static style tables' "collision"
    warnings there at its creation, whatever -screen says (harmless: the styles are the
    same)."""
    libc = ctypes.CDLL(None)
    sys.stdout.flush()
    sys.stderr.flush()
    libc.fflush(None)
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(path, "ab") as f:
            os.dup2(f.fileno(), 1)
            os.dup2(f.fileno(), 2)
        yield
    finally:
        libc.fflush(None)  # (C's buffers, filled while the descriptors were the file, go there)
        for fd, was in zip((1, 2), saved):
            os.dup2(was, fd)
            os.close(was)
