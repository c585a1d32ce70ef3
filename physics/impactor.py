"""Rigid impactors in penalty contact with the FEM surface nodes, with Coulomb friction.

Shapes: "sphere" (3D) / "cylinder" (2D: a disc, the section of a cylinder; 3D with ``axis``:
a cylinder along it), "flat_punch"
and "rod" (a flat circular or strip face of half-width ``radius`` whose normal into the
target is -axis). Normal force per node k_n * penetration along the surface normal of the
impactor; friction mu |f_n| opposite to the tangential slip velocity, regularised over
``slip_velocity`` so the force is continuous. The impactor translates (no rotation); its
contact force is minus the sum of the nodal forces, so momentum is conserved exactly.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .kernels import ball_contact

SHAPES = ("sphere", "cylinder", "flat_punch", "rod")
FLAT = ("flat_punch", "rod")  # a face, not a ball


@dataclass
class RigidImpactor:
    """shape: one of SHAPES; center: (dim,) m (ball centre, or centre of the flat face);
    radius: m; mass: kg; velocity: (dim,) m/s; axis: (dim,) from the face into the impactor
    (flat shapes); penalty: N/m per contact node; friction: Coulomb coefficient;
    depth: m, how far behind a flat face a node still counts as in contact; rounding: m, for
    particle centres: the flat shape grown by the particle radius."""

    shape: str
    center: np.ndarray
    radius: float
    mass: float
    velocity: np.ndarray
    penalty: float
    friction: float = 0.0
    axis: np.ndarray | None = None
    depth: float | None = None
    rounding: float = 0.0  # m, flat shapes: edges rounded by this (a particle radius), see gap
    # flat shapes on FEM nodes: (n_nodes,) N/m, each node's consistent share of the face's penalty
    # (penalty per area x the integral of its shape function over the face); None: ``penalty`` on
    # every node within ``radius``, which on a coarse mesh loads only the nodes that happen to lie
    # under the face
    footprint: np.ndarray | None = None
    slip_velocity: float = 1e-3
    x: np.ndarray = field(init=False)
    v: np.ndarray = field(init=False)
    a: np.ndarray = field(init=False)
    x_at_forces: np.ndarray = field(init=False)  # position at the last force evaluation (work ledger)

    def __post_init__(self):
        if self.shape not in SHAPES:
            raise ValueError(f"impactor shape {self.shape!r}: allowed {SHAPES}")
        self.x = np.array(self.center, float)
        self.v = np.array(self.velocity, float)
        self.a = np.zeros_like(self.x)
        self.x_at_forces = self.x.copy()
        # the compiled contacts' axis (kernels.particle_gap): a cylinder's or a flat face's, zeros
        # for a ball (a sphere, a disc)
        self.contact_axis = np.zeros_like(self.x)
        if self.shape == "cylinder" and self.axis is not None:
            self.axis = np.asarray(self.axis, float) / np.linalg.norm(self.axis)
            self.contact_axis = self.axis.copy()
        if self.shape in FLAT:
            ax = np.asarray(self.axis if self.axis is not None else -self.v, float)
            self.axis = ax / np.linalg.norm(ax)
            self.depth = self.depth or self.radius
            self.contact_axis = self.axis.copy()
        self._k = None  # the footprint on the contact nodes, in the order forces() receives them

    @property
    def ball(self) -> bool:
        """A sphere or a cylinder (a disc in 2D; in 3D along ``axis``, a ball in its cross-section):
        the compiled contact (kernels.ball_contact)."""
        return self.shape in ("sphere", "cylinder")

    @property
    def on_nodes_compiled(self) -> bool:
        """FEM nodes take the compiled contact (kernels.impactor_on_nodes): a ball, a cylinder, or a
        flat face not grown by a rounding (a particle's: that one is ParticleImpactor's)."""
        return self.ball or (self.shape in FLAT and self.rounding == 0)

    def restrict(self, nodes: np.ndarray) -> None:
        """The contact nodes' indices (m,) in the order ``forces`` receives them (the footprint's
        share of each)."""
        if self.footprint is not None:
            self._k = np.asarray(self.footprint, float)[nodes]

    def gap(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """x: (m, dim) node positions -> (penetration (m,) m >= 0, normal (m, dim) pointing at the node)."""
        d = x - self.x
        if self.shape in ("sphere", "cylinder"):
            if self.shape == "cylinder" and self.axis is not None:  # 3D: a cylinder along axis
                d = d - np.outer(d @ self.axis, self.axis)
            r = np.linalg.norm(d, axis=1)
            n = d / np.maximum(r, 1e-300)[:, None]
            return np.maximum(self.radius - r, 0.0), n
        s = d @ self.axis  # depth behind the face
        lat = d - s[:, None] * self.axis
        lateral = np.linalg.norm(lat, axis=1)
        if self.rounding > 0:
            return self._rounded_gap(s, lat, lateral)
        inside = (s > 0) & (s < self.depth) & ((lateral <= self.radius) if self._k is None else (self._k > 0))
        return np.where(inside, s, 0.0), np.broadcast_to(-self.axis, x.shape)

    def _rounded_gap(self, s, lat, lateral):
        """The flat shape grown by a ball of radius ``rounding`` (the set of sphere centres that
        touch it): flat under the face, a torus round the edge, a cylinder beside the side, so
        a centre never finds itself deep inside when it moves across the edge."""
        r, e = self.rounding, self.radius
        e_r = lat / np.maximum(lateral, 1e-300)[:, None]
        out = lateral - e  # > 0 beyond the edge
        under = out <= 0
        dist = np.where(s <= 0, np.hypot(np.maximum(out, 0.0), s), out)  # from the edge or the side
        n_edge = np.where((s <= 0)[:, None], np.maximum(out, 0.0)[:, None] * e_r + s[:, None] * self.axis,
                          e_r * np.maximum(dist, 0.0)[:, None]) / np.maximum(dist, 1e-300)[:, None]
        pen = np.where(under, s + r, r - dist)
        pen = np.where((pen > 0) & (s < self.depth), pen, 0.0)
        n = np.where(under[:, None], -self.axis, n_edge)
        return pen, n

    def forces(self, x: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, float]:
        """Nodal contact forces (m, dim) N for positions x and velocities v (m, dim); and the
        stored penalty energy (J)."""
        if self.ball:  # compiled
            f = np.empty((len(x), x.shape[1]))
            pen2 = ball_contact(np.ascontiguousarray(x, float), np.ascontiguousarray(v, float), self.x,
                                self.contact_axis, self.v, float(self.radius), float(self.penalty),
                                float(self.friction), float(self.slip_velocity**2), f)
            return f, 0.5 * self.penalty * pen2
        pen, n = self.gap(x)
        k = self.penalty if self._k is None else self._k
        fn = k * pen
        f = fn[:, None] * n
        if self.friction > 0:
            vr = v - self.v
            vt = vr - np.einsum("mi,mi->m", vr, n)[:, None] * n
            speed = np.sqrt(np.einsum("mi,mi->m", vt, vt) + self.slip_velocity**2)
            f -= (self.friction * fn / speed)[:, None] * vt
        return f, 0.5 * (self.penalty * float(pen @ pen) if self._k is None else float(fn @ pen))

    def critical_dt(self, node_mass: np.ndarray) -> float:
        """Stable step of the penalty spring between any surface node (m,) kg and the impactor."""
        if self._k is not None:
            w2 = float(np.max(self._k / node_mass)) + float(self._k.max()) / self.mass
        else:
            w2 = self.penalty * (1.0 / node_mass.min() + 1.0 / self.mass)
        return 2.0 / np.sqrt(w2)

    def momentum(self) -> np.ndarray:
        return self.mass * self.v

    def kinetic_energy(self) -> float:
        return 0.5 * self.mass * float(self.v @ self.v)
