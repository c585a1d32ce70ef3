"""The FEM participant: an explicit FEM far field (fem_region.ExplicitDynamics) with the
case's FEM options, its output frames, its run-time guards, law bonds on its nodes, and a run
of it alone (``--mode fem``)."""
from __future__ import annotations

import numpy as np

from fem_region import mesh
from fem_region.elements import ELEMENTS
from fem_region.explicit import ExplicitDynamics
from fem_region.kernels import face_forces, face_points, nodes_as_particles
from fem_region.region import FORMULATIONS, INTEGRATIONS, FemRegion
from fem_region.stable_step import pair_springs, spring_stiffness

from ..params import CaseError, Param
from ..simulation import FieldFrame, Simulation, Stage
from ..timestep import n_steps, time_step


FEM_OPTIONS: dict[str, Param] = {
    "mesh.element": Param("quad4", "2D element", kind="str", choices=("quad4", "tri3")),
    "fem.integration": Param("selective", "full, or selective (shear at the centroid: no shear locking)",
                             kind="str", choices=INTEGRATIONS),
    "fem.formulation": Param("linear", "small-strain linear or Total Lagrangian", kind="str", choices=FORMULATIONS),
    "fem.hypothesis": Param("plane_stress", "2D hypothesis", kind="str", choices=("plane_stress", "plane_strain")),
}


def make_region(m, p: dict, D: np.ndarray, rho, thickness: float) -> FemRegion:
    """FemRegion on mesh m with the case's fem.* options; D (nel, ns, ns) or (ns, ns) Pa. The
    hourglass control's form and coefficient where the case declares them (they were read by
    the disc only: a beam's reduced integration ran the stiffness form whatever fem.hourglass said)."""
    hg = {k: p[f"fem.{k}"] for k in ("hourglass", "hourglass_kappa") if f"fem.{k}" in p}
    try:
        return FemRegion(m, ELEMENTS[mesh.element_name(m)], D, rho, thickness,
                         p["fem.integration"], p["fem.formulation"], **hg)
    except ValueError as exc:
        raise CaseError(f"fem.integration = {p['fem.integration']!r}: {exc}") from None


def fem_fields(dyn: ExplicitDynamics):
    """XDMF frame of the FEM mesh with displacement and velocity."""
    mesh = dyn.region.mesh
    cell_type = {"quad4": "quad", "tri3": "triangle", "hex8": "hexahedron", "tet4": "tetra"}[dyn.region.etype.name]
    pts = np.zeros((dyn.region.n_nodes, 3))
    pts[:, : dyn.region.dim] = dyn.region.X

    def frame() -> FieldFrame:
        pad = lambda a: np.pad(a, ((0, 0), (0, 3 - a.shape[1])))
        _, stress = dyn.region.centroid_strain_stress(dyn.state.u)  # small-strain, Voigt, Pa
        return FieldFrame(pts, {cell_type: mesh.t.T}, {"displacement": pad(dyn.state.u), "velocity": pad(dyn.state.v)},
                          {"stress": [stress]})

    return frame


def fem_guards(dyn: ExplicitDynamics, hourglass_limit: float = 0.1, penetration_limit: float = 0.5) -> list:
    """Run-time checks of a FEM participant: inverted elements, hourglass energy above
    ``hourglass_limit`` of the strain energy, impactor penetration above
    ``penetration_limit`` element sizes."""
    region = dyn.region

    def inverted():
        bad = region.inverted_elements(dyn.state.u)
        if bad.size:
            x = region.X[region.mesh.t[:, bad[0]]].mean(axis=0)
            return (f"FEM: {bad.size} inverted element(s), first {bad[0]} at {np.round(x, 6).tolist()} m "
                    "(excessive distortion: impactor penetration, hourglassing or a step too large)")
        return None

    def hourglass():
        # from the 50th step on, like the energy guard: over the first steps of an impact the
        # few loaded elements deform mostly in hourglass patterns and the ratio means little
        if region.hg is None or dyn.state.step < 50:
            return None
        ue = dyn.state.u[region.mesh.t.T]
        e_hg = region.hg.energy(ue) if region.hg.form == "stiffness" else region.hg.indicator(ue)
        e = region.strain_energy(dyn.state.u)
        if e > 0 and e_hg > hourglass_limit * e:
            what = ("hourglass energy" if region.hg.form == "stiffness" else
                    f"hourglass deformation (uncontrolled, form {region.hg.form!r}: the energy a stiffness "
                    "control would store)")
            return (f"FEM: {what} {e_hg:.3g} J is {e_hg / e:.0%} of the strain energy "
                    f"(> {hourglass_limit:.0%}): hourglassing; use fem.integration = 'full' or 'selective', "
                    "or a finer mesh under the load")
        return None

    size = float(np.ptp(region.X[region.mesh.t], axis=0).max(axis=1).min())  # smallest element extent

    def penetration():
        for k, imp in enumerate(dyn.impactors):
            pen, _ = imp.gap(region.X[dyn._surface] + dyn.state.u[dyn._surface])
            if pen.max() > penetration_limit * size:
                m = dyn.m[dyn._surface].min()
                dt_need = 2.0 / np.sqrt(imp.penalty * (1 / m + 1 / imp.mass))
                return (f"FEM: impactor {k} penetrates {pen.max():.3g} m (> {penetration_limit:g} of the element "
                        f"size {size:.3g} m): normal penalty {imp.penalty:.3g} N/m is too soft for "
                        f"{np.linalg.norm(imp.velocity):.3g} m/s; a stiffer penalty needs a smaller step "
                        f"(k = 100 x this needs dt below {dt_need / 10:.3g} s)")
        return None

    return [inverted, hourglass, penetration]


def fem_only(dyn: ExplicitDynamics, p: dict, t_end_default: float, probes: dict, hourglass_limit: float = 0.1,
             **kw) -> Simulation:
    """A Simulation that steps one explicit FEM participant alone."""
    dt_stable = dyn.critical_dt()
    n, dt = n_steps(p, t_end_default, time_step(p, dt_stable))
    dyn.start()
    every = p["output.history_every"] or max(1, n // 1000)
    return Simulation(
        stages=[Stage("fem.kick_drift", "fem", lambda: dyn.kick_drift(dt)),
                Stage("fem.forces", "fem", dyn.compute_forces),
                Stage("fem.kick", "fem", lambda: dyn.kick(dt))],
        dt=dt, n_steps=n, history_every=every, probes=probes, energies=dyn.energies,
        counts={"fem_nodes": dyn.region.n_nodes, "fem_elements": dyn.region.n_elements,
                "particles": 0, "bonds": 0, "interface_particles": 0},
        clock_info={"dt_fem": dt, "dt_dem": 0.0, "dt_stable_fem": dt_stable, "substeps": 0},
        fields=fem_fields(dyn), field_frames=p["output.field_frames"],
        energy_growth_tol=p["guards.energy_growth"], guards=fem_guards(dyn, hourglass_limit),
        checkpoint=lambda: (dyn.checkpoint_state(), None), restore=lambda d, _: dyn.restore_state(d), **kw)


class FemNodes:
    """The FEM's nodes seen the way LawBonds sees an engine's particles: positions x (n, 3) m
    (2D meshes padded with z = 0, refreshed before each evaluation) and forces f (n, 3) N,
    accumulated until the FEM's force evaluation takes them (``ExplicitDynamics.node_forces``);
    a node's row is its number."""

    def __init__(self, dyn: ExplicitDynamics):
        self.dyn = dyn
        self.x = np.zeros((dyn.region.n_nodes, 3))
        self.f = np.zeros((dyn.region.n_nodes, 3))

    def refresh(self) -> None:
        """Positions from the FEM's state, forces cleared: before each evaluation."""
        nodes_as_particles(self.x, self.f, self.dyn.region.X, self.dyn.state.u)

    def rows_of(self, ids):
        return ids

    def collect(self) -> np.ndarray:
        """(n, 3) N: the forces the bonds left on the nodes."""
        return self.f

    def model(self, bonds, dyn: ExplicitDynamics) -> "NodeBondForces":
        """A node-force model for ExplicitDynamics.node_forces that evaluates ``bonds``."""
        return NodeBondForces(self, bonds, dyn)


class FaceNodes(FemNodes):
    """FemNodes and, after the n nodes, the k node-to-face points of ``face``
    (fem_region.node_to_face): rows n + q of x (n + k, 3) m follow their faces' nodes, and the
    bonds' forces on them (rows of f) go back to those nodes by the same weights."""

    def __init__(self, dyn: ExplicitDynamics, face):
        n = dyn.region.n_nodes
        self.dyn, self.n = dyn, n
        self.nodes, self.weights = np.ascontiguousarray(face.nodes, np.int64), np.ascontiguousarray(face.weights)
        self.x = np.zeros((n + len(self.nodes), 3))
        self.f = np.zeros((n + len(self.nodes), 3))

    def refresh(self) -> None:
        self.f[:] = 0.0
        np.add(self.dyn.region.X, self.dyn.state.u, out=self.x[: self.n, : self.dyn.region.dim])
        face_points(self.x, self.nodes, self.weights, self.n)

    def collect(self) -> np.ndarray:
        face_forces(self.f, self.nodes, self.weights, self.n)
        return self.f[: self.n]


class NodeBondForces:
    """Law bonds on FEM nodes as an ExplicitDynamics node-force model: called at each force
    evaluation, returns (n, 3) N; its state (damage, separations, work) goes into the FEM's
    checkpoint."""

    def __init__(self, nodes: FemNodes, bonds, dyn: ExplicitDynamics):
        self.nodes, self.bonds, self.dyn = nodes, bonds, dyn
        self.last = 0.0  # s, time of the last evaluation

    def __call__(self) -> np.ndarray:
        self.nodes.refresh()
        self.bonds.apply(self.nodes, self.dyn.state.t - self.last)
        self.last = self.dyn.state.t
        return self.nodes.collect()

    def checkpoint_state(self) -> dict:
        return {"bonds": self.bonds.checkpoint_state(), "last": self.last}

    def restore_state(self, d: dict) -> None:
        self.bonds.restore_state(d["bonds"])
        self.last = float(d["last"])


# The dampers of the FEM's pairs (pair_damping). A pair that has softened is a bilinear spring,
# K in compression, (1 - d) K in opening; under central differences such a spring rings inside
# the linear stable step (a single pair of masses grows a millionfold in resonance tongues from
# omega_p dt = 0.44, omega_p^2 = K A / mu its own mode; docs/status.md, session 42), and the seed
# beam's softened lower interface chattered at the zone's edge. A damper of 10 % of the pair's
# critical damping on the opening's rate, acting only on softened pairs at contact (where the
# stiffness switches), holds the single pair decaying up to omega_p dt = 1.54 (a scan of
# softenings and starts: benchmarks/pair_ringing.py), and leaves intact and opening pairs
# undamped (a damper on every pair's whole separation rate moved the seed beam's delamination to
# the other interface). The FEM's step keeps every pair below PAIR_RING_LIMIT (pair_step_limit).
PAIR_DAMPING = 0.1
PAIR_RING_LIMIT = 1.5


def pair_damping(K: float, area: np.ndarray, mu: np.ndarray, xi: float = PAIR_DAMPING) -> np.ndarray:
    """(k,) Pa s/m per area: dampers of ratio xi on each pair's own mode, a spring K area (N/m)
    between masses of reduced mass mu (k,) kg: c = 2 xi sqrt(K A mu) N s/m."""
    area = np.asarray(area, float)
    return 2.0 * xi * np.sqrt(K * np.asarray(mu, float) / area)


def pair_step_limit(K: float, area: np.ndarray, mu: np.ndarray) -> float:
    """s, the step below which every damped pair decays (omega_p dt <= PAIR_RING_LIMIT). It binds
    only where a pair's own mode is near the model's highest (the seed beam's and the DCB's
    pairs, their penalty capped by cohesive_penalty, leave their steps as they were)."""
    return float(PAIR_RING_LIMIT / np.sqrt(np.max(K * np.asarray(area, float) / np.asarray(mu, float))))


def cohesive_node_bonds(dyn: ExplicitDynamics, pairs: np.ndarray, area: np.ndarray, law, friction: float):
    """LawBonds joining coincident FEM nodes across a ply interface (a cohesive far field):
    pairs (k, 2) lower / upper node, area (k,) m^2 each pair stands for; evaluated on the nodes
    at each force evaluation, each with its damper (pair_damping). The FEM's stable step becomes
    that of elements and pairs together (within the dampers' own limit, pair_step_limit),
    each pair a spring of its penalty along every axis (fem_region.stable_step; the elements' own
    step alone, or the pairs' alone, is not a bound: a DCB with pairs at the elements' limit blew
    up in 220 steps)."""
    from physics.law_bonds import LawBonds
    # coincident nodes: the bond normal is the laminate's (+y in a 2D slice, +z in 3D, from the
    # lower ply); positions padded to 3D as FemNodes gives them
    dim = dyn.region.dim
    normal = np.zeros((len(pairs), 3))
    normal[:, dim - 1] = 1.0
    m1, m2 = dyn.m[pairs[:, 0]], dyn.m[pairs[:, 1]]
    mu = m1 * m2 / (m1 + m2)
    bonds = LawBonds(pairs, np.pad(dyn.region.X, ((0, 0), (0, 3 - dim))), normal, area, law, friction=friction,
                     label="interlaminar", damping=pair_damping(law.K, area, mu))
    dyn.node_forces = [FemNodes(dyn).model(bonds, dyn)]
    dyn.add_springs(pair_springs(dyn.region.n_nodes, dim, pairs, law.K * np.asarray(area, float)),
                    limit=pair_step_limit(law.K, area, mu))
    return bonds


def node_to_face_bonds(dyn: ExplicitDynamics, face, area: np.ndarray, law, friction: float):
    """LawBonds joining a ply interface meshed independently on its two sides (``face``:
    fem_region.node_to_face.NodeToFace; area (k,) m^2 each slave stands for: face.area, times
    the slice's thickness in 2D): each slave node to its point on the other side's face,
    evaluated on FaceNodes at each force evaluation, damped as cohesive_node_bonds. Each bond
    runs from its slave to its point (pairs[:, 0] is a node on the plane), its normal along the
    laminate's (y in 2D, z in 3D) pointing there: the opening is the two sides' separation either
    way. The stable step is that of elements and bonds together, as cohesive_node_bonds: a bond
    is a spring k on its slave less its point, u_s - sum_a w_a u_a."""
    from physics.law_bonds import LawBonds
    n, dim, k = dyn.region.n_nodes, dyn.region.dim, len(face.slave)
    X = np.pad(dyn.region.X, ((0, 0), (0, 3 - dim)))
    X = np.vstack([X, face.points(X)])
    point = n + np.arange(k)
    pairs = np.column_stack([face.slave, point])
    normal = np.zeros((k, 3))
    normal[:, dim - 1] = np.where(face.slave_above, -1.0, 1.0)
    mu = 0.5 * face_pair_mass(dyn, face)  # (the damper's reduced mass: the bond's lightest node at both ends)
    bonds = LawBonds(pairs, X, normal, area, law, friction=friction, label="interlaminar",
                     damping=pair_damping(law.K, area, mu))
    dyn.node_forces = [FaceNodes(dyn, face).model(bonds, dyn)]
    dyn.add_springs(spring_stiffness(n, dim, np.column_stack([face.slave, face.nodes]),
                                     np.column_stack([np.ones(k), -face.weights]), law.K * bonds.area),
                    limit=pair_step_limit(law.K, bonds.area, mu))
    return bonds


def face_pair_mass(dyn: ExplicitDynamics, face) -> np.ndarray:
    """(k,) kg, the lightest node of each node-to-face bond (its slave and the face nodes it
    loads): the mass cohesive_penalty limits the stiffness by."""
    m_face = np.where(face.weights > 0, dyn.m[face.nodes], np.inf).min(axis=1)
    return np.minimum(dyn.m[face.slave], m_face)


def cohesive_penalty(dyn: ExplicitDynamics, pairs: np.ndarray, area: np.ndarray, K: float,
                     m_pair: np.ndarray | None = None) -> float:
    """Pa/m, the stiffness per area K, or at most m / (A dt_el^2) (the lighter node's mass m, the
    pair's area A): the pairs then lower the elements' stable step to dt_el / sqrt(2) at most
    (cohesive_node_bonds). Softer costs accuracy, not only time: at a quarter of it the seed
    beam's cohesive plies bent 2.5 % more than tied ones (a half: 1.35 %; the limit: under 1 %),
    since a pair at the limit is already about as compliant as two element rows."""
    dt_el = dyn.region.critical_dt(dyn.density_scale)
    if m_pair is None:  # (node-to-face bonds: face_pair_mass)
        m_pair = np.minimum(dyn.m[pairs[:, 0]], dyn.m[pairs[:, 1]])
    return float(min(K, np.min(m_pair / area) / dt_el**2))


def energies_with(energies, families):
    """An energy ledger that adds law bonds evaluated on FEM nodes (stored and dissipated)."""
    def total():
        e = dict(energies())
        for b in families:
            eb = b.energies()
            e["internal"] += eb["internal"]
            e["dissipated"] += eb["dissipated"]
        return e
    return total
