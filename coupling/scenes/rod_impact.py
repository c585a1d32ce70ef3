"""rod_impact: the seed paper's example 5.3, a two-layer circular composite plate struck by a
long steel rod: the numerical-stability study (3D, quarter model by symmetry).

Data (seed Table 3): plate E = 152.4 GPa (fibre direction), nu = 0.29, G = 4.226 GPa,
rho = 1550 kg/m^3, interlaminar strengths Z0 = R0 = 40 MPa; steel rod rho = 7860 kg/m^3;
the paper's settings: hourglass control off / on, penalties 2e10, 2e12, 2e14 with steps
1e-6 s and (for 2e14) 1e-7 s; the good setting runs to 0.4 ms. Not in the paper, chosen and
fixed here: plate radius 120 mm, clamped rim, two 12 mm layers at 0 and 90 degrees (E22 =
10.3 GPa, G23 = 3.7 GPa, nu23 = 0.4: typical carbon/epoxy), one element per layer through
the thickness and ~15 mm in the plane, so that the paper's 1e-6 s is just below the
elements' own stable step, as the paper's "initial stable time step" says; the rod rigid
(radius 20 mm, length 100 mm, 100 m/s; the paper's rod deforms: here only the plate and
the contact are studied); interface toughness GIc = 500, GIIc = 1000 J/m^2 (the law needs
Gc >= Z0^2 / (2 K): 400 J/m^2 at K = 2e12 Pa/m).

Penalties are read as stiffness per area (Pa/m): a node gets penalty x its tributary area.
This reading makes the paper's observations consistent: at 2e14 a surface node's contact
mode needs dt < ~4e-7 s (hence its 1e-7 s), at 2e10 the rod sinks metres into the plate.

Model: FEM plate (Hex8, Total Lagrangian, one-point integration with Flanagan-Belytschko
hourglass control or none, or selective), the two layers meshed separately and joined node
to node by HashinCohesiveLaw bonds (penalty interface.penalty, Hashin initiation, linear
softening, contact and friction after debonding) that the coupling layer evaluates on the
FEM nodes (dem_region/law_bonds.py, the same code as on particles); rigid rod in penalty
contact (contact.penalty) with the top surface.

Modes: fem (the above), and coupled: a particle zone, the square [0, zone.half_width]^2 under
the rod through both layers (3D ply lattice of spacing zone.particle_size, dem_region/
ply_block.py: each layer's E11, E22, G12, G23 on a cubic lattice, the layer interface as
Hashin bonds with K = E22 / d, the material they replace, and rotation-free slip along both
in-plane directions), the rod on the top particles (penalty contact.penalty x d^2, its edge
rounded by the particle radius so a particle beside it is pushed aside, not found deep under
the face), the FEM plate around it (an O-grid: the hole is the zone's square exactly, the
layers' node bonds as in fem mode), the zone's outer faces x = a, y = a kinematically tied to
it, its faces x = 0, y = 0 on the symmetry planes. The plies stay elastic (Table 3 has no ply
strengths), as in fem mode; zone.ply_failure = true lets them fail by Hoffman with the
carbon/epoxy strengths of 5.1 (at 100 m/s the layers then crack through under the rod).

How the program detects a bad setting: before the first step (exit 2) a step above the
stable limit of the elements, the contact penalty or the interface bonds is refused with
the limit named; while running (exit 3) the guards stop on energy created, hourglass energy
above 10 % of the strain energy, inverted elements, or the rod sinking more than half an
element into the plate (it passes through). benchmarks/rod_impact_stability.py runs the
paper's settings and writes the stability map.

qoi: rod velocity history and its final value, peak plate deflection (bottom centre), peak
layer separation (largest interface opening), debonded interface area, energy balance.
Checks: the energy balance; peak deflection against the spring-mass estimate v sqrt(M / k)
with the clamped circular plate's bending stiffness 16 pi D / R^2 (D of the two layers
about the mid-plane, mean of the two in-plane directions) in series with its transverse
shear stiffness 2 pi kappa G t / ln(R / r), M the rod's mass plus a fifth of the plate's,
within 35 % (an estimate: the contact is short, the plate orthotropic and indented).

Measured: peak deflection 10.95 mm (8 x 8 x 2 elements, 3 s) and 11.11 mm (16 x 16 x 4,
24 s) against the estimate 9.38 mm. The paper's good setting (one-point elements with
hourglass control) is stopped on this mesh by the hourglass guard: with one or two elements
per layer the hourglass modes hold 45-80 % of the strain energy, and the plate comes out
stiff (3.1 mm against 5.6 mm fully integrated at 50 m/s); so the good setting here is
full integration with the paper's 2e14 penalties and the step they need. A flat rigid rod
punches the element under its edge when no node ring lies on the edge (12 elements per
radius: inverted elements at 7 us); mesh.radial is a multiple of 8 so that one does.
"""
from __future__ import annotations

import numpy as np
import skfem

from dem_region import ply_block
from physics.law_bonds import LawBonds
from physics.laws import HashinCohesiveLaw
from dem_region.particle_impactor import ParticleImpactor
from dem_region.ply_lattice import PlyMaterial
from physics.failure import HoffmanStrengths
from fem_region import materials, mesh
from fem_region.elements import ELEMENTS
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from physics.impactor import RigidImpactor
from fem_region.region import FemRegion

from ..checks import check, energy_balance
from ..params import CaseError, Param, density, modulus, positive
from ..participants.dem import hold_symmetry_planes
from ..participants.fem import FemNodes, fem_only
from ..participants.coupled import COUPLING, coupled_simulation
from .ply_fracture import PLY

NAME = "rod_impact"
DESCRIPTION = "seed 5.3: two-layer circular plate, long-rod impact; stability under hourglass / penalty settings"
MODES = ("fem", "coupled")

PARAMETERS = {
    "plate.E11": modulus(152.4e9, "modulus along the fibres (Table 3)"),
    "plate.E22": modulus(10.3e9, "transverse modulus (not in the paper)"),
    "plate.nu12": Param(0.29, "Poisson ratio (Table 3)", low=0.0, high=0.49),
    "plate.nu23": Param(0.4, "transverse Poisson ratio (not in the paper)", low=0.0, high=0.49),
    "plate.G12": modulus(4.226e9, "shear modulus (Table 3)"),
    "plate.G23": modulus(3.7e9, "transverse shear modulus (not in the paper)"),
    "plate.rho": density(1550.0, "plate density (Table 3)"),
    "geometry.radius": positive(0.12, "plate radius (clamped rim)", "m"),
    "geometry.layer_thickness": positive(12e-3, "thickness of each of the two layers", "m"),
    "mesh.radial": Param(8, "elements along the radius (a multiple of 8: a node ring on the rod's edge;  (quarter model: radial x radial per layer)", kind="int",
                         low=2, high=64),
    "mesh.per_layer": Param(1, "elements through each layer", kind="int", low=1, high=8),
    "fem.integration": Param("full", "full (2 x 2 x 2 points) or reduced (one point, the paper's, with "
                             "fem.hourglass)", kind="str", choices=("full", "selective", "reduced")),
    "fem.hourglass": Param("stiffness", "hourglass control with reduced integration", kind="str",
                           choices=("stiffness", "viscous", "none")),
    "fem.hourglass_kappa": Param(0.1, "hourglass coefficient", low=0.0, high=1.0),
    "interface.penalty": positive(2e14, "layer-to-layer penalty (Pa/m, per tributary area)", "Pa/m"),
    "interface.Z0": positive(40e6, "interlaminar normal strength (Table 3)", "Pa"),
    "interface.R0": positive(40e6, "interlaminar shear strength (Table 3)", "Pa"),
    "interface.GIc": positive(500.0, "mode I toughness (not in the paper)", "J/m^2"),
    "interface.GIIc": positive(1000.0, "mode II toughness (not in the paper)", "J/m^2"),
    "interface.friction": Param(0.3, "friction of debonded layers", low=0.0, high=2.0),
    "contact.penalty": positive(2e14, "rod-to-plate penalty (Pa/m, per tributary area of a surface node)", "Pa/m"),
    "rod.radius": positive(20e-3, "rod radius", "m"),
    "rod.length": positive(0.1, "rod length (its mass: steel)", "m"),
    "rod.rho": density(7860.0, "rod density (Table 3)"),
    "rod.velocity": positive(100.0, "impact speed", "m/s"),
    # coupled mode: the particle zone under the rod (ply strengths and energies: carbon/epoxy, as 5.1)
    **{k: v for k, v in PLY.items() if k.startswith(("strength.", "fracture."))},
    "zone.ply_failure": Param(False, "intralaminar failure (Hoffman, strength.* and fracture.*) in the particle "
                             "zone; off: elastic layers as in the paper (Table 3 has interface strengths only)",
                             kind="bool"),
    "zone.half_width": positive(30e-3, "half side of the square particle zone under the rod (coupled)", "m"),
    "zone.particle_size": positive(3e-3, "particle spacing d (divides the layer thickness and zone.half_width)", "m"),
    **COUPLING,
}
T_END = 0.4e-3


def layer_C(p: dict, angle: float) -> np.ndarray:
    E11, E22, G12, G23 = p["plate.E11"], p["plate.E22"], p["plate.G12"], p["plate.G23"]
    C = materials.orthotropic(E11, E22, E22, p["plate.nu12"], p["plate.nu12"], p["plate.nu23"], G12, G12, G23)
    return materials.rotate(C, materials.ply_axes(angle, 3))


def core_cells(p: dict) -> int:
    """Grid cells along each side of the square hole the DEM zone fills (coupled mode)."""
    return max(1, int(round(p["mesh.radial"] * p["zone.half_width"] / p["geometry.radius"])))


def _map(u: np.ndarray, v: np.ndarray, p: dict, core: bool) -> tuple[np.ndarray, np.ndarray]:
    """The square grid [0, 1]^2 onto the quarter disc. Without a core:
    (u sqrt(1 - v^2 / 2), v sqrt(1 - u^2 / 2)). With one (an O-grid): the grid square
    [0, s]^2 (s = core_cells / radial) onto the DEM zone's square [0, a]^2 exactly, and each
    ray from it blended linearly from the square's side to the rim."""
    R = p["geometry.radius"]
    if not core:
        return R * u * np.sqrt(1 - v**2 / 2), R * v * np.sqrt(1 - u**2 / 2)
    a, s = p["zone.half_width"], core_cells(p) / p["mesh.radial"]
    rho = np.maximum(u, v)
    w = np.clip((rho - s) / (1 - s), 0.0, 1.0)[None]
    uv = np.array([u, v])
    with np.errstate(invalid="ignore", divide="ignore"):
        square = np.nan_to_num(a * uv / rho)
        circle = np.nan_to_num(R * uv / np.hypot(u, v))
    out = np.where(rho >= s, (1 - w) * square + w * circle, a * uv / s)
    return out[0], out[1]


def plate_mesh(p: dict, core: bool = False) -> tuple[skfem.MeshHex1, np.ndarray, np.ndarray, np.ndarray]:
    """Quarter disc of two layers (Hex8), the interface nodes doubled: (mesh, layer of each
    element (nel,), interface pairs (k, 2) lower / upper node, grid key (n_nodes,) of each
    node on the structured (radial + 1)^2 grid). core: leave the DEM zone's square
    [0, zone.half_width]^2 out (coupled mode)."""
    n, m, h = p["mesh.radial"], p["mesh.per_layer"], p["geometry.layer_thickness"]
    g = np.linspace(0.0, 1.0, n + 1)
    box = mesh.box(g, g, np.linspace(0.0, 2 * h, 2 * m + 1), "hex8")
    P, T = box.p.copy(), box.t.copy()
    tol = 1e-9 * h
    on = np.flatnonzero(np.abs(P[2] - h) < tol)
    twin = np.arange(P.shape[1])
    twin[on] = P.shape[1] + np.arange(on.size)
    P = np.hstack([P, P[:, on]])
    upper = P[2, T].mean(axis=0) > h
    T[:, upper] = twin[T[:, upper]]
    pairs = np.column_stack([on, twin[on]])
    u, v = P[0].copy(), P[1].copy()
    P[0], P[1] = _map(u, v, p, core)
    key = np.round(v * n) * (n + 1) + np.round(u * n)
    if core:  # drop the hole's elements, then the nodes no element uses
        s = core_cells(p) / n
        keep = np.maximum(u[T].mean(axis=0), v[T].mean(axis=0)) > s
        T, upper = T[:, keep], upper[keep]
        used = np.unique(T)
        renumber = np.full(P.shape[1], -1)
        renumber[used] = np.arange(used.size)
        P, T, key = P[:, used], renumber[T], key[used]
        pairs = renumber[pairs]
        pairs = pairs[(pairs >= 0).all(axis=1)]
    return skfem.MeshHex1(np.ascontiguousarray(P), np.ascontiguousarray(T)), upper.astype(int), pairs, key.astype(int)


def tributary_area(p: dict, core: bool = False) -> np.ndarray:
    """((radial + 1)^2,) m^2 by grid key: a quarter of each adjoining quad of the mapped
    surface grid (none from the DEM zone's hole)."""
    n = p["mesh.radial"]
    g = np.linspace(0.0, 1.0, n + 1)
    U, V = np.meshgrid(g, g)  # row = v, column = u: key = row (n + 1) + column
    xy = np.stack(_map(U, V, p, core), axis=-1)
    a = xy[1:, 1:] - xy[:-1, :-1]
    b = xy[:-1, 1:] - xy[1:, :-1]
    quad = 0.5 * np.abs(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])
    if core:
        c = core_cells(p)
        quad[:c, :c] = 0.0
    area = np.zeros((n + 1, n + 1))
    for di in (0, 1):
        for dj in (0, 1):
            area[di:n + di, dj:n + dj] += quad / 4
    return area.ravel()


def plate_region(p: dict, core: bool) -> tuple[FemRegion, np.ndarray, np.ndarray]:
    """(FEM plate, interface node pairs (k, 2), grid key (n_nodes,))."""
    m, layer, pairs, key = plate_mesh(p, core)
    if p["fem.integration"] == "selective":
        raise CaseError("fem.integration = 'selective': the 90 layer couples normal and shear terms in 3D; "
                        "allowed full or reduced")
    C = np.array([layer_C(p, 0.0), layer_C(p, 90.0)])[layer]
    region = FemRegion(m, ELEMENTS["hex8"], C, p["plate.rho"], 1.0, p["fem.integration"], "total_lagrangian",
                       hourglass=p["fem.hourglass"], hourglass_kappa=p["fem.hourglass_kappa"])
    return region, pairs, key


def supports(region: FemRegion, p: dict) -> list[PrescribedMotion]:
    """Clamped rim, symmetry planes x = 0 and y = 0."""
    X, R = region.X, p["geometry.radius"]
    rim = np.flatnonzero(np.hypot(X[:, 0], X[:, 1]) > R * (1 - 1e-9))
    sym_x, sym_y = np.flatnonzero(X[:, 0] < 1e-9 * R), np.flatnonzero(X[:, 1] < 1e-9 * R)
    return [PrescribedMotion(np.concatenate([3 * rim + k for k in range(3)])),
            PrescribedMotion(3 * sym_x), PrescribedMotion(3 * sym_y + 1)]


def interface_bonds(p: dict, dyn: ExplicitDynamics, pairs: np.ndarray, area: np.ndarray) -> LawBonds:
    """The layers' node-to-node Hashin bonds, evaluated on the FEM nodes each force
    evaluation; sets the stable step they allow."""
    try:
        law = HashinCohesiveLaw(K=p["interface.penalty"], Z0=p["interface.Z0"], R0=p["interface.R0"],
                                GIc=p["interface.GIc"], GIIc=p["interface.GIIc"])
    except ValueError as exc:
        raise CaseError(f"interface.penalty = {p['interface.penalty']:g}: {exc}") from None
    # coincident nodes: the bond normal is the plate normal (+z from the lower layer)
    bonds = LawBonds(pairs, dyn.region.X, np.tile([0.0, 0.0, 1.0], (len(pairs), 1)), area, law,
                     friction=p["interface.friction"], label="interlaminar")
    dyn.node_forces = [FemNodes(dyn).model(bonds, dyn)]
    # stable step of the interface springs on the lighter of the two nodes (Gershgorin: 2 k)
    k_bond = law.K * area
    m_pair = np.minimum(dyn.m[pairs[:, 0]], dyn.m[pairs[:, 1]])
    dyn.critical_dt_extra = float(np.min(2.0 / np.sqrt(2 * 2 * k_bond / np.maximum(m_pair, 1e-300))))
    return bonds


def rod_mass(p: dict) -> float:
    """kg, the quarter model's share of the rod."""
    return 0.25 * p["rod.rho"] * np.pi * p["rod.radius"] ** 2 * p["rod.length"]


def build(p: dict, mode: str, dem: str):
    if mode == "coupled":
        return _build_coupled(p, dem)
    region, pairs, key = plate_region(p, core=False)
    X, n, h, R = region.X, p["mesh.radial"], p["geometry.layer_thickness"], p["geometry.radius"]
    area_by_key = tributary_area(p)
    top = np.flatnonzero(np.abs(X[:, 2] - 2 * h) < 1e-9 * h)
    k_contact = p["contact.penalty"] * float(np.median(area_by_key[key[top]]))
    rod = RigidImpactor("rod", np.array([0.0, 0.0, 2 * h + 1e-9]), p["rod.radius"], rod_mass(p),
                        np.array([0.0, 0.0, -p["rod.velocity"]]), k_contact, axis=np.array([0.0, 0.0, 1.0]))
    dyn = ExplicitDynamics(region, supports=supports(region, p), impactors=[rod])
    area = area_by_key[key[pairs[:, 0]]]
    bonds = interface_bonds(p, dyn, pairs, area)
    centre = np.flatnonzero((np.hypot(X[:, 0], X[:, 1]) < 1e-9 * R) & (X[:, 2] < 1e-9 * h))[0]
    probes = {"rod_velocity": lambda: float(-rod.v[2]),
              "rod_displacement": lambda: float(-(rod.x[2] - 2 * h)),
              "plate_deflection": lambda: float(-dyn.state.u[centre, 2]),
              "layer_separation": lambda: _separation(bonds),
              "debonded_area": lambda: float(4 * area @ bonds.failed()),
              "damaged_area": lambda: float(4 * area @ (bonds.damage > 0))}
    sim = fem_only(dyn, p, T_END, probes)
    sim.energies = _with_bonds(sim.energies, [bonds])
    sim.counts.update({"interface_bonds": len(pairs)})
    return sim


def _separation(*families: LawBonds) -> float:
    """m, the largest interface opening."""
    return float(max(max(np.einsum("bi,bi->b", b.delta, b.normal).max(initial=0.0), 0.0) for b in families))


def _with_bonds(energies, families):
    """An energy ledger that adds the coupling layer's bonds evaluated on FEM nodes."""
    def total():
        e = dict(energies())
        for b in families:
            eb = b.energies()
            e["internal"] += eb["internal"]
            e["dissipated"] += eb["dissipated"]
        return e
    return total


# -- coupled: a particle zone under the rod ------------------------------------------------------
def plate_material(p: dict) -> PlyMaterial:
    """The layers' material on the lattice: elastic unless zone.ply_failure (Table 3 gives no
    ply strengths: the paper's plies stay elastic, only the interface fails)."""
    Yt, Yc, S23 = p["strength.Yt"], p["strength.Yc"], p["strength.S23"]
    if not p["zone.ply_failure"]:
        inf = np.inf
        k = HoffmanStrengths(Xt=inf, Xc=inf, Yt=inf, Yc=inf, Zt=inf, Zc=inf, S23=inf, S13=inf, S12=inf)
        return PlyMaterial(p["plate.E11"], p["plate.E22"], p["plate.G12"], p["plate.G23"], p["plate.rho"], k,
                           p["fracture.Gf_fibre"], p["fracture.Gf_matrix"])
    k = HoffmanStrengths(Xt=p["strength.Xt"], Xc=p["strength.Xc"], Yt=Yt, Yc=Yc, Zt=Yt, Zc=Yc, S23=S23,
                         S13=p["strength.S12"], S12=p["strength.S12"])
    return PlyMaterial(p["plate.E11"], p["plate.E22"], p["plate.G12"], p["plate.G23"], p["plate.rho"], k,
                       p["fracture.Gf_fibre"], p["fracture.Gf_matrix"])


def particle_zone(p: dict):
    """(block, scene, intralaminar LawBonds, interlaminar LawBonds, rod on the particles):
    the square [0, a]^2 through both layers; columns on x = 0, y = 0 (symmetry) and on
    x = a, y = a (tied to the FEM) carry half cells."""
    a, d, h = p["zone.half_width"], p["zone.particle_size"], p["geometry.layer_thickness"]
    for key, length in (("geometry.layer_thickness", h), ("zone.half_width", a)):
        if abs(length / d - round(length / d)) > 1e-6:
            raise CaseError(f"zone.particle_size = {d:g}: must divide {key} = {length:g} m")
    top = min(2 * p["rod.radius"], 0.5 * p["geometry.radius"])
    if not top >= a > p["rod.radius"] + 2 * d:
        raise CaseError(f"zone.half_width = {a:g}: allowed above the rod radius + 2 particles "
                        f"({p['rod.radius'] + 2 * d:g} m) and up to twice the rod radius or half the plate "
                        f"radius ({top:g} m)")
    N, rows = int(round(a / d)) + 1, int(round(h / d))
    try:
        block = ply_block.build((0.0, 0.0, 0.0), (N, N), [rows, rows], [0.0, 90.0], d, plate_material(p),
                                half_planes=[(0, 0), (1, 0), (0, N - 1), (1, N - 1)])
    except ValueError as exc:
        raise CaseError(f"plate.G12 = {p['plate.G12']:g}: {exc}") from None
    l = block.x[block.intra_pairs[:, 1]] - block.x[block.intra_pairs[:, 0]]
    intra = LawBonds(block.intra_pairs, block.x, l, block.intra_area, block.intra_law, volume=block.volume,
                     label="intralaminar")
    try:
        law = ply_block.interlaminar_law(block, p["interface.Z0"], p["interface.R0"], p["interface.GIc"],
                                         p["interface.GIIc"])
    except ValueError as exc:
        raise CaseError(f"interface.GIc = {p['interface.GIc']:g}: on the particle lattice (K = E22 / d = "
                        f"{block.inter_K:.3g} Pa/m) {exc}") from None
    inter = LawBonds(block.inter_pairs, block.x, np.tile([0.0, 0.0, 1.0], (len(block.inter_pairs), 1)),
                     block.inter_area, law, friction=p["interface.friction"], along=block.inter_along,
                     label="interlaminar")
    i, j, k = block.index.T
    tied = np.flatnonzero((i == N - 1) | (j == N - 1))
    scene = ply_block.engine_scene(block, groups={"interface": tied})
    # the rod grown by the particle radius meets the particle centres (rounded edge: a particle
    # beside the rod is pushed aside, not found deep under the face)
    rod = RigidImpactor("rod", np.array([0.0, 0.0, 2 * h + 1e-9]), p["rod.radius"], rod_mass(p),
                        np.array([0.0, 0.0, -p["rod.velocity"]]), p["contact.penalty"] * d**2,
                        axis=np.array([0.0, 0.0, 1.0]), rounding=block.radius)
    impactor = ParticleImpactor(rod, np.flatnonzero(k >= k.max() - 1), fixed=(True, True, False))
    return block, scene, intra, inter, impactor


def _build_coupled(p: dict, dem: str):
    block, scene, intra, inter, impactor = particle_zone(p)
    h = p["geometry.layer_thickness"]
    area_by_key = tributary_area(p, core=True)
    fem_bonds = []

    def make(extra_mass):
        region, pairs, key = plate_region(p, core=True)
        dyn = ExplicitDynamics(region, supports=supports(region, p), extra_mass=extra_mass)
        fem_bonds.append(interface_bonds(p, dyn, pairs, area_by_key[key[pairs[:, 0]]]))
        return dyn

    sim, clock = coupled_simulation(p, make, scene, dem, T_END, models=(intra, inter, impactor))
    backend, bonds = clock.dem, fem_bonds[-1]
    fem_area = bonds.area
    i, j, k = block.index.T
    hold_symmetry_planes(backend, i, j, held=scene.groups["interface"])
    centre = np.flatnonzero((i == 0) & (j == 0) & (k == 0))[0]
    z0 = block.x[centre, 2]
    rod = impactor.imp
    sim.probes.update({
        "rod_velocity": lambda: float(-rod.v[2]),
        "rod_displacement": lambda: float(-(rod.x[2] - 2 * h)),
        "plate_deflection": lambda: float(-(backend.positions_of(np.array([centre]))[0, 2] - z0)),
        "layer_separation": lambda: _separation(bonds, inter),
        "debonded_area": lambda: float(4 * (fem_area @ bonds.failed() + inter.area @ inter.failed())),
        "damaged_area": lambda: float(4 * (fem_area @ (bonds.damage > 0) + inter.area @ (inter.damage > 0))),
        "failed_intralaminar": lambda: float(np.sum(intra.failed())),
    })
    sim.energies = _with_bonds(sim.energies, [bonds])
    sim.counts.update({"interface_bonds": len(bonds.pairs) + len(inter.pairs), "law_bonds": len(intra.pairs)})
    return sim


def spring_mass_estimate(p: dict) -> float:
    """Peak deflection (m): v sqrt(M / k), 1 / k = R^2 / (16 pi D) + ln(R / r) / (2 pi kappa G t)
    (clamped plate, bending and transverse shear, load on the rod's disc)."""
    h = p["geometry.layer_thickness"]
    D = 0.0
    for angle, (z0, z1) in ((0.0, (-h, 0.0)), (90.0, (0.0, h))):
        Q = materials.plane_stress(layer_C(p, angle))
        D += 0.5 * (Q[0, 0] + Q[1, 1]) * (z1**3 - z0**3) / 3
    R = p["geometry.radius"]
    k_bending = 16 * np.pi * D / R**2
    # a thick plate (R / thickness = 5): transverse shear adds w = P ln(R / r) / (2 pi kappa G t)
    # (Mindlin, load on a disc of radius r), kappa = 5/6, G the mean transverse shear modulus
    G = 0.5 * (p["plate.G12"] + p["plate.G23"])
    k_shear = 2 * np.pi * 5 / 6 * G * 2 * h / np.log(R / p["rod.radius"])
    M = p["rod.rho"] * np.pi * p["rod.radius"] ** 2 * p["rod.length"] + 0.2 * p["plate.rho"] * 2 * h * np.pi * R**2
    return p["rod.velocity"] * np.sqrt(M * (1 / k_bending + 1 / k_shear))


def evaluate(p: dict, h: dict, mode: str):
    w = np.asarray(h["plate_deflection"])
    qoi = {"peak_plate_deflection": float(w.max()), "time_of_peak_deflection": float(h["time"][int(np.argmax(w))]),
           "final_rod_velocity": float(h["rod_velocity"][-1]), "peak_layer_separation": float(np.max(h["layer_separation"])),
           "debonded_area": float(h["debonded_area"][-1]), "damaged_area": float(h["damaged_area"][-1]),
           "spring_mass_estimate": spring_mass_estimate(p)}
    checks = {
        "peak_plate_deflection": check(qoi["peak_plate_deflection"], qoi["spring_mass_estimate"], 0.35,
                                       "spring-mass estimate v sqrt(M / k), plate bending and shear in series (an estimate)"),
        "energy_balance": energy_balance(h),
    }
    return qoi, checks


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    t = 1e3 * np.asarray(h["time"])
    fig, ax = plt.subplots(1, 4, figsize=(16, 3.6))
    ax[0].plot(t, h["rod_velocity"])
    ax[0].set(xlabel="time (ms)", ylabel="rod velocity (m/s, into the plate)")
    ax[1].plot(t, 1e3 * np.asarray(h["plate_deflection"]), label="plate (bottom centre)")
    ax[1].plot(t, 1e3 * np.asarray(h["rod_displacement"]), "--", label="rod face")
    ax[1].axhline(1e3 * qoi["spring_mass_estimate"], color="k", ls=":", label="spring-mass estimate")
    ax[1].set(xlabel="time (ms)", ylabel="mm")
    ax[1].legend()
    ax[2].plot(t, 1e6 * np.asarray(h["layer_separation"]))
    ax[2].set(xlabel="time (ms)", ylabel="largest layer separation (um)")
    for key in ("kinetic", "internal", "dissipated", "external_work"):
        ax[3].plot(t, h[key], label=key)
    ax[3].set(xlabel="time (ms)", ylabel="J (quarter model)")
    ax[3].legend()
    fig.tight_layout()
    fig.savefig(plots_dir / "histories.png", dpi=120)
    plt.close(fig)
