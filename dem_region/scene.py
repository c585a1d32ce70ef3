"""The engine-neutral damage-zone description that every DEM back-end builds from.

Particles are spheres; bonds join neighbours and carry a law family (inside a ply, between
plies, between two materials). Arrays are SI: positions (n, 3) m, radii (n,) m, densities
(n,) kg/m^3, bond stiffnesses (nb,) N/m.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np



# Peak memory per particle of a bonded lattice in a run (the orchestrator's arrays, the law
# kernels' buffers and an engine's atoms, bonds and neighbour lists; ~13 bonds per particle).
BYTES_PER_PARTICLE = 4096


class TooLarge(MemoryError):
    """A model that cannot fit in this machine's memory (bad input: the message has the count
    and the estimate)."""


def check_fits(n: float, what: str) -> None:
    """Refuse ``n`` particles before any array of them exists, when BYTES_PER_PARTICLE x n
    exceeds the memory available now (MemAvailable of /proc/meminfo; the same rule as
    fem_region.mesh.check_fits, which this package may not import)."""
    need, avail = float(n) * BYTES_PER_PARTICLE, _available()
    if avail is not None and need > avail:
        raise TooLarge(f"{what}: {n:.3g} particles need about {need / 2**30:.3g} GiB, {avail / 2**30:.3g} GiB "
                       "available; allowed: a coarser particle spacing or a smaller zone")


def _available() -> float | None:
    try:
        with open("/proc/meminfo") as f:
            return next(float(line.split()[1]) * 1024 for line in f if line.startswith("MemAvailable:"))
    except (OSError, StopIteration):
        return None


@dataclass
class ElasticBond:
    """Linear elastic bond: normal force kn * (gap change), shear ks (no failure)."""

    name: str = "elastic"


@dataclass(frozen=True)
class Wall:
    """A fixed rigid plane normal to global ``axis`` (0, 1, 2) at ``position`` (m), acting on
    the side ``sense`` (+1: particles above it, -1: below, 0: both). Rigid impactors and
    clamps are particles: an impactor is a large sphere with its own mass and velocity, a
    clamp is a group of prescribed particles."""

    axis: int
    position: float
    sense: int = 0


@dataclass
class DemScene:
    """Particles, bonds and named groups of a damage zone.

    x: (n, 3) m; radius: (n,) m; density: (n,) kg/m^3; part: (n,) int (ply / part id);
    bonds: (nb, 2) particle index pairs; kn, ks: (nb,) N/m; bond_family: (nb,) int index into
    ``laws``; groups: name -> particle indices ("interface", "clamped", ...);
    plane: True for quasi-2D scenes (motion out of the x-y plane and rotations about x, y blocked);
    velocity: (n, 3) m/s initial velocities (zero if not given);
    young, poisson: (n,) or scalar, elastic constants of the particle material (Pa, -), used by
    the contact law of particles that touch without a bond; contact: "linear" (linear spring,
    the bonded scenes) or "hertz_mindlin" (Hertz normal, Mindlin tangential, with a normal and
    tangential coefficient of restitution ``restitution``); the group "fixed" holds particles
    that do not move (rigid supports, e.g. a very large sphere standing in for a plane).
    """

    x: np.ndarray
    radius: np.ndarray
    density: np.ndarray
    bonds: np.ndarray
    kn: np.ndarray
    ks: np.ndarray
    part: np.ndarray | None = None
    bond_family: np.ndarray | None = None
    laws: list = field(default_factory=lambda: [ElasticBond()])
    groups: dict[str, np.ndarray] = field(default_factory=dict)
    plane: bool = False
    young: np.ndarray | float = 1e9
    poisson: np.ndarray | float = 0.3
    friction_deg: float = 0.0
    contact: str = "linear"
    restitution: float = 1.0
    bond_strength: np.ndarray | float = np.inf  # (nb,) N, normal force at which a bond breaks (brittle)
    walls: list = field(default_factory=list)  # rigid planes: Wall(axis, position, sense)
    local_damping: float = 0.0  # Cundall's non-viscous damping, only for quasi-static virtual tests
    # True when the bonds only keep the engine from adding contact between law pairs (the
    # coupling layer's laws carry the forces): a tie must not remove them
    placeholder_bonds: bool = False
    velocity: np.ndarray | None = None

    def __post_init__(self):
        n = len(self.x)
        self.velocity = np.zeros((n, 3)) if self.velocity is None else np.asarray(self.velocity, float).reshape(n, 3)
        self.young = np.broadcast_to(np.asarray(self.young, float), (n,)).copy()
        self.poisson = np.broadcast_to(np.asarray(self.poisson, float), (n,)).copy()
        if self.contact not in ("linear", "hertz_mindlin"):
            raise ValueError(f"contact {self.contact!r}: allowed linear, hertz_mindlin")
        if self.contact == "hertz_mindlin" and len(self.bonds):
            raise ValueError("bonded scenes use the linear contact law")
        if self.walls and self.contact != "hertz_mindlin":
            raise ValueError("walls are available with the hertz_mindlin contact family")
        self.x = np.asarray(self.x, float).reshape(n, 3)
        self.radius = np.broadcast_to(np.asarray(self.radius, float), (n,)).copy()
        self.density = np.broadcast_to(np.asarray(self.density, float), (n,)).copy()
        self.bonds = np.asarray(self.bonds, int).reshape(-1, 2)
        nb = len(self.bonds)
        self.kn = np.broadcast_to(np.asarray(self.kn, float), (nb,)).copy()
        self.ks = np.broadcast_to(np.asarray(self.ks, float), (nb,)).copy()
        self.part = np.zeros(n, int) if self.part is None else np.asarray(self.part, int)
        self.bond_family = np.zeros(nb, int) if self.bond_family is None else np.asarray(self.bond_family, int)
        self.bond_strength = np.broadcast_to(np.asarray(self.bond_strength, float), (nb,)).copy()
        for name, ids in self.groups.items():
            ids = np.asarray(ids, int)
            if ids.size and (ids.min() < 0 or ids.max() >= n):
                raise ValueError(f"group {name!r} refers to particles outside 0..{n - 1}")
            self.groups[name] = ids

    @property
    def n(self) -> int:
        return len(self.x)

    def without_bonds_within(self, ids: np.ndarray) -> "DemScene":
        """A copy without the bonds whose two ends are both in ``ids`` (bonds inside an
        interface band that the FEM already represents would count its stiffness twice)."""
        inside = np.zeros(self.n, bool)
        inside[ids] = True
        keep = ~(inside[self.bonds[:, 0]] & inside[self.bonds[:, 1]])
        kw = {k: v for k, v in self.__dict__.items()}
        kw.update(bonds=self.bonds[keep], kn=self.kn[keep], ks=self.ks[keep], bond_family=self.bond_family[keep],
                  bond_strength=self.bond_strength[keep], groups=dict(self.groups))
        return DemScene(**kw)

    def to_wire(self) -> dict:
        """Plain-Python form (arrays as dtype, shape, bytes) for another process, which may run
        a different numpy (the LAMMPS worker venv)."""
        out = {}
        for k, v in self.__dict__.items():
            if isinstance(v, np.ndarray):
                out[k] = ("ndarray", v.dtype.str, v.shape, v.tobytes())
            elif k == "groups":
                out[k] = {g: ("ndarray", a.dtype.str, a.shape, a.tobytes()) for g, a in v.items()}
            elif k == "laws":
                out[k] = [type(law).__name__ for law in v]
            elif k == "walls":
                out[k] = [(w.axis, w.position, w.sense) for w in v]
            else:
                out[k] = v
        return out

    @classmethod
    def from_wire(cls, d: dict) -> "DemScene":
        arr = lambda t: np.frombuffer(t[3], dtype=np.dtype(t[1])).reshape(t[2]).copy()
        kw = {k: (arr(v) if isinstance(v, tuple) and v and v[0] == "ndarray" else v) for k, v in d.items()}
        kw["groups"] = {g: arr(t) for g, t in d["groups"].items()}
        kw["laws"] = [ElasticBond() for _ in d["laws"]]
        kw["walls"] = [Wall(*w) for w in d.get("walls", [])]
        return cls(**kw)

    @property
    def mass(self) -> np.ndarray:
        """(n,) kg of solid spheres."""
        return self.density * 4.0 / 3.0 * np.pi * self.radius**3

    @property
    def inertia(self) -> np.ndarray:
        """(n,) kg m^2, moment of inertia of solid spheres."""
        return 0.4 * self.mass * self.radius**2

    def critical_dt(self, free: np.ndarray | None = None) -> float:
        """Central-difference stable step (s) of the bonded network, by Gershgorin's bound.

        omega_max^2 <= max_i sum_j k_ij (1/m_i + 1/sqrt(m_i m_j)) over bonds with k = max(kn, ks).
        """
        m = self.mass
        if not len(self.bonds):  # granular: the Rayleigh wave step of the smallest particle
            G = self.young / (2 * (1 + self.poisson))
            return float(np.min(np.pi * self.radius * np.sqrt(self.density / G) / (0.1631 * self.poisson + 0.8766)))
        return gershgorin_dt(m, self.bonds, np.maximum(self.kn, self.ks))


def gershgorin_dt(m: np.ndarray, pairs: np.ndarray, k: np.ndarray, ground: np.ndarray | None = None) -> float:
    """Central-difference stable step (s) of springs k (nb,) N/m on pairs (nb, 2) between
    masses m (n,) kg, and springs ``ground`` (n,) N/m from each mass to a rigid body (an
    impactor's penalty): omega_max^2 <= max_i [sum_j k_ij (1/m_i + 1/sqrt(m_i m_j)) + g_i / m_i]."""
    n = len(m)
    i, j = np.asarray(pairs, int).reshape(-1, 2).T
    cross = k / np.sqrt(m[i] * m[j])
    row = np.bincount(i, k / m[i] + cross, n) + np.bincount(j, k / m[j] + cross, n)
    if ground is not None:
        row = row + ground / m
    return 2.0 / np.sqrt(row.max()) if row.size and row.max() > 0 else np.inf
