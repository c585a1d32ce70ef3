"""A growing zone's particles seeded in advance and released (``zone.conversion = "release"``;
laminated beams, 2D and 3D).

Radioss's way (its particles are seeded from the start, slaved to their parent bricks, and
released when a brick fails): the engine holds, from t = 0, every particle a growing zone may
reach (the lattice out to zone.grow_to, the reserve). Those beyond the zone are slaved to the
FEM as the interface's are, by the elements' shape functions, but carry none of the model's
mass (the elements do) and no law bond reaches them. A conversion then rebuilds the FEM, the
interface and the law bonds as ``rebuild`` does, but not the engine: the converted particles
are released where the FEM carried them and take the velocities a rebuilt engine would start
from (study/growth.py).

What it trades (docs/benchmarks.md): no engine set-up at a conversion (LAMMPS starts a worker
process for each rebuild) against the reserve's particles in the engine and the interface at
every step.

The zone's lattice is a prefix of the reserve's (the lattice numbers its particles column by
column from x = 0), so the zone's law bonds, impactors and probes keep their particle ids. A
quarter's symmetry planes are held on the whole reserve from the start (a slaved particle's
velocity is written whole all the same), so a released particle on y = 0 stays held there.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from dem_region.scene import DemScene


def reserve_scenes(scene: DemScene, reserve: DemScene, d: float) -> tuple[DemScene, DemScene]:
    """(the coupled model's scene, the engine's) for a zone's ``scene`` (n particles, its last
    column tied) within the ``reserve`` (N >= n particles, the lattice out to the growth limit,
    built alike): the reserve's particles, the zone's first with the zone's masses (its tied
    column's half cells), the rest in group "dormant"; the engine's with each particle's mass
    as it will be once released (the reserve's)."""
    n = scene.n
    if reserve.n < n or not np.allclose(reserve.x[:n], scene.x, rtol=0.0, atol=1e-9 * d):
        raise RuntimeError("zone.conversion = release: the zone's lattice is not the first part of the reserve's")
    density = reserve.density.copy()
    density[:n] = scene.density
    groups = {"interface": np.asarray(scene.groups["interface"], int), "dormant": np.arange(n, reserve.n)}
    model = replace(reserve, density=density, groups=groups)
    return model, replace(model, density=reserve.density.copy())


class ZoneView:
    """The engine as the zone's probes, fields and plots see it: its first ``n`` particles (the
    zone's; the rest are the reserve's, slaved to the FEM)."""

    def __init__(self, engine, n: int):
        self.engine, self.n = engine, n

    def positions(self) -> np.ndarray:
        return self.engine.positions()[: self.n]

    def velocities(self) -> np.ndarray:
        return self.engine.velocities()[: self.n]

    def __getattr__(self, name):
        return getattr(self.engine, name)
