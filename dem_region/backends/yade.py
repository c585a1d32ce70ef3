"""YADE adapter (in-process; the only module that imports yade).

Bonds become CohFrictPhys interactions created explicitly from the neutral bond list
(``utils.createInteraction``), with their stiffnesses set per bond and their rest gap taken
from the initial configuration (``unp``), so the engine integrates exactly the neutral
scene. The coupling hook is a PyRunner placed between the InteractionLoop and the
NewtonIntegrator: forces at x_n are known there and the particles have not moved yet, so
one ``O.step()`` is one monolithic central-difference step of the coupled system.
"""
from __future__ import annotations

import contextlib
import io
import sys
from typing import Callable

import numpy as np

from ..scene import DemScene

YADE_PY = "/usr/lib/x86_64-linux-gnu/yade-double/py"
_HOOK = "_femdem_between"
_UNBREAKABLE = 1e300


def _import_yade():
    if YADE_PY not in sys.path:
        sys.path.insert(1, YADE_PY)
    with contextlib.redirect_stdout(io.StringIO()):  # yade prints 'Using python version' on import
        import yade
        import yade.config
        from yade import wrapper
    return yade, wrapper


class YadeBackend:
    """DEM back-end on YADE's global scene ``O`` (one per process; ``build`` resets it)."""

    name = "yade"
    native_laws = ("elastic",)

    def __init__(self):
        self.yade, self.w = _import_yade()
        self.version = self.yade.config.version
        self.O = self.yade.O
        self._between: Callable[[], None] | None = None

    # -- set-up ----------------------------------------------------------------------------
    def build(self, scene: DemScene) -> None:
        import __main__

        O, w, utils = self.O, self.w, self.yade.utils
        O.reset()
        self.scene = scene
        mat = O.materials.append(w.CohFrictMat(
            young=scene.young, poisson=scene.poisson, density=float(scene.density.mean()),
            frictionAngle=np.radians(scene.friction_deg), isCohesive=True, momentRotationLaw=False,
            normalCohesion=_UNBREAKABLE, shearCohesion=_UNBREAKABLE))
        V3 = self.yade.Vector3
        self.ids = O.bodies.append([utils.sphere(V3(*x), float(r), material=mat)
                                    for x, r in zip(scene.x, scene.radius)])
        for b, rho in zip(O.bodies, scene.density):  # per-particle density
            b.state.mass = float(rho * 4.0 / 3.0 * np.pi * b.shape.radius**3)
            if scene.plane:
                b.state.blockedDOFs = "zXY"
        self.law = w.Law2_ScGeom6D_CohFrictPhys_CohesionMoment()
        setattr(__main__, _HOOK, self._hook)
        O.engines = [
            w.ForceResetter(),
            w.InsertionSortCollider([w.Bo1_Sphere_Aabb()]),
            w.InteractionLoop([w.Ig2_Sphere_Sphere_ScGeom6D()],
                              [w.Ip2_CohFrictMat_CohFrictMat_CohFrictPhys(setCohesionNow=False,
                                                                          setCohesionOnNewContacts=False)],
                              [self.law]),
            w.PyRunner(command=f"{_HOOK}()", iterPeriod=1, initRun=True),
            w.NewtonIntegrator(damping=0.0),
        ]
        for (i, j), kn, ks in zip(scene.bonds, scene.kn, scene.ks):
            I = utils.createInteraction(int(i), int(j))
            ph = I.phys
            ph.kn, ph.ks = float(kn), float(ks)
            ph.cohesionBroken = False
            ph.normalAdhesion = ph.shearAdhesion = _UNBREAKABLE
            ph.unp = I.geom.penetrationDepth  # the initial configuration is stress free
        self.prescribed = np.zeros(0, int)

    def critical_dt(self) -> float:
        return self.scene.critical_dt()

    def set_dt(self, dt: float) -> None:
        self.O.dt = float(dt)

    # -- stepping ----------------------------------------------------------------------------
    def _hook(self) -> None:
        if self._between is not None:
            self._between()

    def advance(self, between: Callable[[], None] | None = None) -> None:
        self._between = between
        self.O.step()

    # -- interface data ----------------------------------------------------------------------
    def prescribe(self, ids: np.ndarray) -> None:
        self.prescribed = np.asarray(ids, int)
        for i in self.prescribed:
            self.O.bodies[int(i)].state.blockedDOFs = "xyzXYZ"

    def set_velocities(self, ids: np.ndarray, v: np.ndarray) -> None:
        V3, bodies = self.yade.Vector3, self.O.bodies
        for i, vi in zip(ids, v):
            bodies[int(i)].state.vel = V3(*vi)

    def forces(self, ids: np.ndarray) -> np.ndarray:
        f = self.O.forces.f
        return np.array([tuple(f(int(i))) for i in ids]).reshape(-1, 3)

    def positions(self) -> np.ndarray:
        return np.array([tuple(b.state.pos) for b in self.O.bodies])

    def velocities(self) -> np.ndarray:
        return np.array([tuple(b.state.vel) for b in self.O.bodies])

    def energies(self) -> dict[str, float]:
        """Kinetic energy of the free particles (prescribed ones belong to the FEM side) and
        elastic bond energy, J, both at the time level of the last force evaluation: YADE's
        leapfrog velocities are half a step ahead, so v_n = v_{n+1/2} - dt/2 F_n / m."""
        m = self.scene.mass.copy()
        v = self.velocities()
        if self.O.iter > 0:
            v -= 0.5 * self.O.dt * self.forces(np.arange(self.scene.n)) / m[:, None]
        m[self.prescribed] = 0.0
        # the law's energy functions crash YADE before its first step; bonds are built stress free
        elastic = self.law.normElastEnergy() + self.law.shearElastEnergy() if self.O.iter > 0 else 0.0
        return {"kinetic": 0.5 * float(np.einsum("n,ni,ni->", m, v, v)), "elastic": float(elastic),
                "dissipated": 0.0}

    def finalize(self) -> None:
        import __main__

        self._between = None
        if hasattr(__main__, _HOOK):
            delattr(__main__, _HOOK)
        self.O.reset()
