"""The assembler: a study's resolved parameters -> the FEM participant, the DEM participant and
the coupled assembly of the requested mode.

Modes of one body: ``fem``, the whole body as FEM (no damage, the cheap bound); ``dem``, the
whole body as particles (the expensive reference); ``coupled``, particles inside the zone and
FEM outside, tied at the zone's faces. Geometry shapes: ``beam``, a plane-strain slice of a
laminated beam along x, y through the thickness, half model about x = 0; ``beam_3d``, a
quarter of the beam (symmetry planes x = 0 and y = 0, mid-width), free edges at y = W / 2,
the thickness along z; 0 plies have their fibres along x, 90 plies along y.

The particle zone is a ply lattice (dem_region.ply_lattice in 2D, ply_block in 3D): one
particle row per ``zone.plies_per_particle`` plies, the Hoffman intralaminar law on the bonds
within a ply and the laminate's interface law on the bonds across plies of different angle.
Particles on a symmetry plane, a free edge (3D) or the FEM's face stand for half a cell: half
the mass, and their bonds along that plane half the area.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from dem_region import ply_block, ply_lattice
from dem_region.particle_impactor import ParticleImpactor
from dem_region.scene import DemScene
from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from fem_region.node_to_face import NodeToFace, node_to_face
from physics.failure import HoffmanStrengths
from physics.impactor import RigidImpactor
from physics.law_bonds import LawBonds
from physics.laws import HashinCohesiveLaw

from ..params import CaseError
from ..participants.coupled import coupled_simulation
from ..participants.dem import dem_only, hold_symmetry_planes
from ..participants.fem import (cohesive_node_bonds, cohesive_penalty, energies_with, face_pair_mass, fem_only,
                                make_region, node_to_face_bonds)
from .schema import section
from .selectors import footprint, tie_particles, whole_spacings
from .seeded import ZoneView, reserve_scenes


@dataclass
class Laminate:
    """A laminate's runs of equal plies, bottom up, and its materials (Pa, kg/m^3, J/m^2)."""

    angles: list[float]  # degrees, one per run
    plies: list[int]  # plies per run
    ply_thickness: float  # m
    ply: dict  # the [materials.*] fields
    interface: dict  # the [interfaces.*] fields
    elastic: bool = False  # the plies do not fail (zone.ply_failure = false)

    @property
    def thickness(self) -> float:
        return sum(self.plies) * self.ply_thickness

    def stiffness(self, angle: float, dim: int) -> np.ndarray:
        """(6, 6) Pa of a ply at ``angle`` in the structure's axes: the ply normal along y (2D)
        or z (3D), the fibres turned about it from x (materials.ply_axes)."""
        m = self.ply
        C = materials.orthotropic(m["E11"], m["E22"], m["E22"], m["nu12"], m["nu12"], m["nu23"], m["G12"], m["G12"],
                                  m["G23"])
        return materials.rotate(C, materials.ply_axes(angle, dim))

    def by_run(self, of, run: np.ndarray) -> np.ndarray:
        """(k, ...) ``of(angle)`` (D or C) of each element's ply run ``run`` (k,): one per run,
        repeated (formed per element, a 2D beam's build spent 0.07 s on its 216 rotations)."""
        return np.array([of(a) for a in self.angles])[np.asarray(run, int)]

    def D(self, angle: float) -> np.ndarray:
        """(3, 3) plane-strain stiffness Pa of a ply at ``angle`` in the slice."""
        return materials.plane_strain(self.stiffness(angle, 2))

    def C(self, angle: float) -> np.ndarray:
        """(6, 6) Pa of a ply in the beam's axes (x span, y width, z thickness): fibres along x
        (0) or y (90)."""
        return self.stiffness(angle, 3)

    def strengths(self) -> HoffmanStrengths:
        """The ply's nine Hoffman strengths, transversely isotropic (Zt = Yt, Zc = Yc, S13 = S12);
        infinite when the plies are elastic."""
        if self.elastic:
            inf = np.inf
            return HoffmanStrengths(Xt=inf, Xc=inf, Yt=inf, Yc=inf, Zt=inf, Zc=inf, S23=inf, S13=inf, S12=inf)
        m = self.ply
        return HoffmanStrengths(Xt=m["Xt"], Xc=m["Xc"], Yt=m["Yt"], Yc=m["Yc"], Zt=m["Yt"], Zc=m["Yc"], S23=m["S23"],
                                S13=m["S12"], S12=m["S12"])

    def material(self, moduli=None) -> ply_lattice.PlyMaterial:
        """The lattice's ply: moduli, density, Hoffman strengths, fracture energies; ``moduli``:
        the 2D slice's in-plane moduli per angle."""
        m = self.ply
        return ply_lattice.PlyMaterial(m["E11"], m["E22"], m["G12"], m["G23"], m["rho"], self.strengths(),
                                       m["Gf_fibre"], m["Gf_matrix"], moduli=moduli)

    def bending_stiffness(self) -> float:
        """D (N m) per unit width, plane strain: sum E_x,b z^2 dz about the mid-plane."""
        tp, H = self.ply_thickness, self.thickness
        z = np.cumsum([0] + self.plies) * tp - H / 2
        return sum(ply_lattice.slice_moduli(self.D(a))[0] * (z1**3 - z0**3) / 3
                   for a, z0, z1 in zip(self.angles, z[:-1], z[1:]))

    def transverse_modulus(self) -> float:
        """The smallest through-thickness slice modulus E_y of its plies (Pa)."""
        return min(ply_lattice.slice_moduli(self.D(a))[1] for a in self.angles)


def laminate(p: dict, name: str) -> Laminate:
    """The [laminates.name] of the resolved parameters, its layup grouped in runs."""
    lam = section(p, f"laminates.{name}")
    angles = materials.parse_layup(lam["layup"])
    if any(a not in (0.0, 90.0) for a in angles):
        raise CaseError(f"laminates.{name}.layup = {lam['layup']!r}: a beam slice takes 0 and 90 plies only")
    runs_a, runs_n = [], []
    for a in angles:
        if runs_a and runs_a[-1] == a:
            runs_n[-1] += 1
        else:
            runs_a.append(a)
            runs_n.append(1)
    return Laminate(runs_a, runs_n, lam["ply_thickness"], section(p, f"materials.{lam['material']}"),
                    section(p, f"interfaces.{lam['interface']}"))


@dataclass
class Built:
    """What the assembler made, for probes, checks and plots. Lengths m; ``width_factor``
    turns a force on the modelled slice into one on the whole structure."""

    p: dict
    mode: str
    lam: Laminate | None  # None: a bonded beam
    half_span: float
    t: float  # particle size, m (and the 2D slice's thickness out of plane)
    width_factor: float
    dim: int = 2
    column: np.ndarray | None = None  # (n,) each particle's column index along x (0 on x = 0)
    lattice: ply_lattice.PlyLattice | None = None
    intra: LawBonds | None = None
    inter: LawBonds | None = None
    backend: object = None
    dyn: ExplicitDynamics | None = None
    clock: object = None  # a coupled run's CoupledClock
    fem_elements: int = 0
    end_held: bool = False  # the zone's last column is tied to the FEM or clamped
    impactors: dict = field(default_factory=dict)  # name -> ParticleImpactor (particles) or RigidImpactor (FEM)
    # a bonded beam's (study/bonded.py): its data, the sheet's bonds, each particle's width index
    # (3D), the beam's length per adhesive bond (m, whole beam), the loads' probes, the body's
    # stiffness row of sigma_xx (all-FEM), and whether the zone's edge damage counts body bonds
    bonded: object = None
    sheet: LawBonds | None = None
    width_index: np.ndarray | None = None
    bond_whole: np.ndarray | None = None
    load_probes: dict = field(default_factory=dict)
    particle_loads: list = field(default_factory=list)  # ParticleLoads the models apply (a block's pressure)
    models: tuple = ()  # the zone's models in the order the simulation runs them (a grown zone's carry over)
    fibre_stiffness: np.ndarray | None = None
    edge_intra: bool = False
    mesh_groups: dict = field(default_factory=dict)  # a mesh file's physical groups: name -> node coordinates
    node_bonds: LawBonds | None = None  # a cohesive far field's node-pair bonds
    fem_pairs: np.ndarray | None = None  # (k, 2) the FEM's doubled nodes, lower / upper
    fem_pair_area: np.ndarray | None = None  # (k,) m^2 (per m of slice in 2D) each pair stands for
    fem_face: NodeToFace | None = None  # runs meshed apart (a mesh file): the pairs node to face, (node, point)
    particles: int = 0  # particles outside a lattice (a panel's windows)
    panel: object = None  # a panel's parts the probes read (study/panel.py)


def body_of(p: dict, mode: str) -> Built:
    """The body's laminate and particle size, before its participants exist."""
    lam = laminate(p, p["geometry.laminate"])
    lam.elastic = not p["zone.ply_failure"]
    if p["geometry.shape"] == "disc":
        return Built(p, mode, lam, 0.5 * p["geometry.span"], p["zone.particle_size"], 4.0, dim=3)  # a quarter
    k = p["zone.plies_per_particle"]
    if any(n % k for n in lam.plies):
        raise CaseError(f"zone.plies_per_particle = {k}: must divide every ply run of the laminate ({lam.plies})")
    t = k * lam.ply_thickness
    if p["geometry.shape"] in ("beam_3d", "plate"):
        return Built(p, mode, lam, 0.5 * p["geometry.span"], t, 4.0, dim=3)  # a quarter
    return Built(p, mode, lam, 0.5 * p["geometry.span"], t, 2 * p["geometry.width"] / t)  # whole width, both halves


def _columns_across(p: dict, d: float) -> int:
    """Particle columns across the modelled half width (3D): half the width in whole spacings."""
    m = 0.5 * p["geometry.width"] / d
    if abs(m - round(m)) > 1e-6 or round(m) < 1:
        raise CaseError(f"geometry.width = {p['geometry.width']:g}: half of it must be a whole number of particle "
                        f"spacings ({d:g} m); allowed e.g. {2 * max(1, round(m)) * d:g} m")
    return int(round(m)) + 1


def particle_zone(p: dict, x_end: float, tied: bool, clamped: bool):
    """(lattice, engine scene, intralaminar LawBonds, interlaminar LawBonds) of a study's beam on
    [0, x_end] (benchmarks and kernel tests take the law families from here)."""
    built = body_of(p, "dem")
    return (_particle_block if built.dim == 3 else _particle_zone)(built, x_end, tied, clamped)


def beam(study, p: dict, mode: str, dem: str, start=None):
    """(Simulation, Built) of a laminated beam (slice or quarter) under its impactors and supports;
    start: the state a coupled run continues from (coupled_simulation's)."""
    built = body_of(p, mode)
    t, L, dim = built.t, built.half_span, built.dim
    if dim == 3:
        _columns_across(p, t)
    t_end = study.t_end
    if mode == "fem":
        return _fem_beam(study, p, built, t_end), built
    w = L if mode == "dem" else p["zone.half_width"]
    if mode == "coupled" and not 2 * t < w < 0.8 * L:
        raise CaseError(f"zone.half_width = {w:g}: allowed more than two particle sizes ({2 * t:g} m) and less "
                        f"than 0.8 x half the span ({0.8 * L:g} m)")
    if mode == "coupled" and p.get("zone.grow"):
        xg = grow_limit(p, built)
        check_growth(p, t, w, xg, xg < 0.8 * L, f"below 0.8 x half the span ({0.8 * L:g} m)")
        if p.get("mesh.file"):
            raise CaseError("zone.grow = true: not with a mesh file (mesh.file), whose line at the zone's edge fixes "
                            "the zone; allowed: zone.grow = false")
    for name in study.layout.names["impactors"]:  # a punch's face stays on the particles
        hw = p.get(f"impactors.{name}.half_width", 0.0)
        if mode == "coupled" and hw > w - 2 * t:
            raise CaseError(f"impactors.{name}.half_width = {hw:g}: the face must stay on the DEM zone; allowed <= "
                            f"zone.half_width - 2 particle sizes = {w - 2 * t:g} m")
    clamp = _support(study, p) == "clamped"
    zone = _particle_block if dim == 3 else _particle_zone
    lat, scene, intra, inter = zone(built, w, tied=(mode == "coupled"), clamped=(mode == "dem" and clamp))
    engine_scene = None
    seeded = mode == "coupled" and p.get("zone.grow") and p.get("zone.conversion") == "release"
    planes = lat  # the lattice whose symmetry planes the engine holds
    if seeded:  # the reserve's particles in the engine from the start (study/seeded.py)
        planes, reserve, _, _ = zone(built, grow_limit(p, built), tied=True, clamped=False)
        scene, engine_scene = reserve_scenes(scene, reserve, t)
    built.lattice, built.intra, built.inter = lat, intra, inter
    built.column = lat.index[:, 0] if dim == 3 else lat.column
    built.end_held = mode == "coupled" or clamp
    built.impactors = {name: _particle_impactor(p, name, built) for name in study.layout.names["impactors"]}
    models = built.models = (intra, inter, *built.impactors.values())

    def hold(backend) -> None:  # the symmetry planes
        if dim == 3:  # (seeded: the reserve's, the slaved particles too, held on them once released)
            held = np.concatenate([[] if seeded else scene.groups.get("interface", []),
                                   scene.groups.get("fixed", [])]).astype(int)
            hold_symmetry_planes(backend, planes.index[:, 0], planes.index[:, 1], held)
        else:
            axis = np.flatnonzero(lat.column == 0)
            backend.prescribe(axis, "x")
            backend.set_velocities(axis, np.zeros((len(axis), 3)))

    if mode == "dem":
        sim, backend, _ = dem_only(p, scene, dem, t_end, models=models)
        if not clamp:  # simply supported: the bottom particles of the last column
            last = np.flatnonzero(built.column == built.column.max())
            bottom = last[lat.x[last, dim - 1] <= lat.x[last, dim - 1].min() + 1e-9 * t]
            backend.prescribe(bottom, "yz"[dim - 2])
            backend.set_velocities(bottom, np.zeros((len(bottom), 3)))
        hold(backend)
    else:
        def make(extra_mass):
            x0 = lat.x[:, 0].max()
            grow = p.get("zone.grow", False)
            region = _fem_block(p, built, x0, grow) if dim == 3 else _fem_region(p, built, x0, reserve=grow)
            dyn = ExplicitDynamics(region, supports=_fem_supports(study, p, region, L, dim, symmetry_x=False,
                                                                  groups=built.mesh_groups), extra_mass=extra_mass)
            built.node_bonds = _far_field_bonds(p, built, dyn)
            return dyn
        sim, clock = coupled_simulation(p, make, scene, dem, t_end, models=models, start=start, hold=hold,
                                        engine=getattr(start, "engine", None), engine_scene=engine_scene)
        backend, built.dyn, built.clock = clock.dem, clock.fem, clock
        if seeded:
            backend = ZoneView(backend, lat.n)
        built.fem_elements = clock.fem.region.n_elements
        _with_far_field(sim, built)
    built.backend = backend
    sim.counts.update({"law_bonds": len(intra.pairs) + len(inter.pairs)})
    return sim, built


def _support(study, p: dict) -> str:
    """The condition of the one [supports.NAME] table (clamped or simply_supported)."""
    names = list(study.layout.names["supports"])
    if len(names) != 1:
        raise CaseError(f"supports: a beam takes one [supports.NAME] table at its ends; given {len(names)}")
    return p[f"supports.{names[0]}.condition"]


def _fem_supports(study, p: dict, region, L: float, dim: int, symmetry_x: bool,
                  groups: dict | None = None) -> list[PrescribedMotion]:
    """The supports at x = span / 2 (clamped: every DOF of the end face; simply supported: the
    vertical DOF of its bottom edge; or, when the mesh file has a physical group named as the
    support, its nodes), the symmetry plane y = 0 (3D) and, when the FEM reaches it, x = 0."""
    X = region.X
    (name,) = study.layout.names["supports"]
    clamped = _support(study, p) == "clamped"
    if groups and name in groups:  # the mesh file names the support's nodes
        dist = np.linalg.norm(X[:, None, :] - groups[name][None, :, :dim], axis=2)
        held = np.flatnonzero(dist.min(axis=1) < 1e-9 * L)
    else:
        held = np.flatnonzero(np.abs(X[:, 0] - L) < 1e-9 * L)
        if not clamped:
            held = held[X[held, dim - 1] < 1e-9 * L]
    if clamped:
        out = [PrescribedMotion(np.concatenate([dim * held + c for c in range(dim)]))]
    else:
        out = [PrescribedMotion(dim * held + dim - 1)]
    if dim == 3:
        out.append(PrescribedMotion(3 * np.flatnonzero(np.abs(X[:, 1]) < 1e-9 * L) + 1))
    if symmetry_x:
        out.append(PrescribedMotion(dim * np.flatnonzero(np.abs(X[:, 0]) < 1e-9 * L)))
    return out


def _through(p: dict, lam: Laminate) -> np.ndarray:
    """The element rows' heights through the laminate, bottom up (m): one row per particle row,
    or mesh.elements_per_run rows through each run of equal plies (a coarser far field: a
    larger stable step)."""
    n_run = p["mesh.elements_per_run"]
    if not n_run:
        return np.linspace(0.0, lam.thickness, sum(lam.plies) // p["zone.plies_per_particle"] + 1)
    tops = np.cumsum([0] + lam.plies) * lam.ply_thickness
    return np.unique(np.concatenate([np.linspace(a, b, n_run + 1) for a, b in zip(tops[:-1], tops[1:])]))


def check_growth(p: dict, d: float, w: float, xg: float, fits: bool, limit: str) -> None:
    """A growing zone's keys: a kinematic tie (a grown zone rebuilds one), and its limit xg (m,
    zone.grow_to or the shape's default) whole particle spacings d from the zone's half width w
    (a grown zone may reach the limit itself); ``fits``: the shape's bound on xg holds, said by
    ``limit``. CaseError (one line) otherwise."""
    if p["coupling.tie"] != "kinematic":
        raise CaseError(f"coupling.tie = {p['coupling.tie']!r}: a growing zone rebuilds a kinematic tie (its "
                        "particles' momentum in the FEM's nodes); allowed with zone.grow = true: kinematic")
    if not w <= xg * (1 + 1e-9) or not fits or abs(xg / d - round(xg / d)) > 1e-6:
        raise CaseError(f"zone.grow_to = {p['zone.grow_to']:g}: allowed whole particle spacings ({d:g} m) from "
                        f"the zone's half width ({w:g} m) to {limit}")


def grow_limit(p: dict, built: Built) -> float:
    """The farthest a grown zone may reach (m): zone.grow_to, or the last whole particle spacing
    below 0.8 x half the span (a zone's limit)."""
    d, L = built.t, built.half_span
    if p["zone.grow_to"]:
        return p["zone.grow_to"]
    return (np.ceil(0.8 * L / d - 1e-9) - 1) * d


def _along(p: dict, built: Built, x0: float, reserve: bool) -> np.ndarray:
    """The far field's element edges along x from x0 (m): graded from x0 to the support in the
    most of mesh.elements_along whose first element is no shorter than the particle spacing;
    with ``reserve`` (a zone that may grow) one element per particle spacing out to grow_limit
    first, so any grown zone's edge is a mesh line and the remaining far field the same mesh,
    less the columns that became particles."""
    n, L, d = p["mesh.elements_along"], built.half_span, built.t
    start = grow_limit(p, built) if reserve else x0
    cols = np.arange(int(round(x0 / d)), int(round(start / d))) * d
    # an element shorter than the particles beside it resolves nothing they do not, and it
    # would set the shared step below the lattice's (2 plies per particle on the seed beam:
    # 0.15 mm elements beside 0.3 mm particles held the step at 0.58 of the lattice's)
    for k in range(n, 0, -1):
        rest = mesh.graded(start, L, k, p["mesh.element_ratio"] ** (1.0 / max(k - 1, 1)), start)
        if rest[1] - rest[0] >= d * (1 - 1e-9) or k == 1:
            break
    return np.concatenate([cols, rest])


def _fem_region(p: dict, built: Built, x0: float, reserve: bool = False):
    """FEM laminate on [x0, span / 2] x [0, H], one element row per particle row (or
    mesh.elements_per_run per ply run), graded from x0 (or the mesh.file's part right of x0);
    ``reserve``: uniform at the particle spacing out to the growth limit first (_along)."""
    if p["mesh.file"]:
        return _file_region(p, built, x0)
    lam = built.lam
    xs = _along(p, built, x0, reserve)
    ys = _through(p, lam)
    m = mesh.rectangle(xs, ys, p["mesh.element"])
    cy = m.p[1, m.t].mean(axis=0)
    run = np.searchsorted(np.cumsum(lam.plies) * lam.ply_thickness, cy)
    m = _split(p, built, m, run)
    D = lam.by_run(lam.D, run)
    return make_region(m, p, D, lam.ply["rho"], built.t)


def _file_region(p: dict, built: Built, x0: float):
    """The FEM laminate from a Gmsh file: the elements of its physical group named after the
    laminate that lie right of x0 (the file needs a mesh line, in 3D a plane, there), each in one
    ply run (the file needs lines or planes at the runs' interfaces; the runs may be meshed
    apart there, _split); its physical groups' nodes kept for the supports. A beam slice takes
    quadrangles or triangles on [x0, L] x [0, H], a 3D beam hexahedra or tetrahedra on
    [x0, L] x [0, W / 2] x [0, H]."""
    lam, L, dim = built.lam, built.half_span, built.dim
    try:
        m, built.mesh_groups = mesh.read_gmsh(p["mesh.file"], p["geometry.laminate"])
    except (OSError, ValueError) as exc:
        raise CaseError(f"mesh.file = {p['mesh.file']!r}: {exc}") from None
    tol = 1e-6 * min(lam.ply_thickness, built.t)
    X, where = m.p, f"mesh.file = {p['mesh.file']!r}"
    if m.dim() != dim:
        raise CaseError(f"{where}: a {'beam slice' if dim == 2 else '3D beam'} takes a {dim}D mesh; this one is "
                        f"{m.dim()}D")
    x = X[0, m.t]
    if x0 > 0:
        left, right = x.max(axis=0) <= x0 + tol, x.min(axis=0) >= x0 - tol
        if not (left | right).all():
            raise CaseError(f"{where}: elements cross x = {x0:g} m, the zone's edge; allowed: a mesh with a "
                            f"{'line' if dim == 2 else 'plane'} there (zone.half_width rounded to whole particle "
                            "spacings)")
        m = m.remove_elements(np.flatnonzero(left))
        X = m.p
    want = [(x0, L)] + ([(0.0, 0.5 * p["geometry.width"])] if dim == 3 else []) + [(0.0, lam.thickness)]
    span = list(zip(X.min(axis=1), X.max(axis=1)))
    if any(abs(a - c) > tol or abs(b - e) > tol for (a, b), (c, e) in zip(span, want)):
        show = lambda box: ", ".join(f"{'xyz'[i]} {a:g}..{b:g}" for i, (a, b) in enumerate(box))
        raise CaseError(f"{where}: spans {show(span)} m; allowed: the {'half' if dim == 2 else 'quarter'} beam "
                        f"{show(want)} m (x from the zone's edge in coupled mode)")
    levels = np.cumsum(lam.plies) * lam.ply_thickness
    z = X[dim - 1, m.t]
    run = np.searchsorted(levels, z.mean(axis=0))
    bottom = np.concatenate([[0.0], levels])[run]
    bad = (z.min(axis=0) < bottom - tol) | (z.max(axis=0) > levels[run] + tol)
    if bad.any():
        raise CaseError(f"{where}: {int(bad.sum())} elements cross a ply run's interface ({'xyz'[dim - 1]} = "
                        f"{', '.join(f'{v:g}' for v in levels[:-1])} m); allowed: a mesh with "
                        f"{'lines' if dim == 2 else 'planes'} there")
    m = _split(p, built, m, run)
    if dim == 2:
        return make_region(m, p, lam.by_run(lam.D, run), lam.ply["rho"], built.t)
    return make_region(m, p, lam.by_run(lam.C, run), lam.ply["rho"], 1.0)


def _split(p: dict, built: Built, m, run: np.ndarray):
    """The mesh with its ply runs' interfaces doubled when the far field is cohesive (the pairs
    in built.fem_pairs, the interface area each stands for in built.fem_pair_area: a share of
    the faces of the elements below it, per unit slice thickness in 2D), else as it is. A mesh
    file whose runs are meshed apart at an interface (no node shared there) is joined there node
    to face (built.fem_face, with the doubled pairs of the other interfaces among its bonds)."""
    lam, key = built.lam, f"laminates.{p['geometry.laminate']}.far_field_interfaces"
    axis, tol = m.dim() - 1, 1e-9 * lam.ply_thickness
    levels = np.cumsum(lam.plies)[:-1] * lam.ply_thickness
    apart = _meshed_apart(m, run, levels, axis, tol)
    built.fem_pairs, built.fem_face = None, None
    if p[key] != "cohesive":
        if apart.any():
            raise CaseError(f"{key} = {p[key]!r}: the mesh's ply runs are meshed apart at "
                            f"{'xyz'[axis]} = {', '.join(f'{v:g}' for v in levels[apart])} m (no shared node); "
                            "allowed: 'cohesive' (joined node to face), or a mesh whose runs share their nodes there")
        return m
    joined = np.flatnonzero(~apart)
    below = np.searchsorted(joined, run)  # the doubled interfaces under each element
    P, T, pairs = mesh.split_interfaces(m.p, m.t, below, levels[joined], axis, tol)
    area = mesh.interface_areas(P, T, below, levels[joined], axis, tol)[pairs[:, 0]]
    if apart.any():
        faces = [node_to_face(P, T, np.flatnonzero(run <= k), np.flatnonzero(run > k), axis, levels[k], tol)
                 for k in np.flatnonzero(apart)]
        built.fem_face = NodeToFace.concat([NodeToFace.coincident(pairs, area, faces[0].nodes.shape[1]), *faces])
        pairs, area = np.column_stack([built.fem_face.slave, P.shape[1] + np.arange(len(built.fem_face.slave))]), \
            built.fem_face.area  # (the second of each pair: its point, after the nodes)
    built.fem_pairs, built.fem_pair_area = pairs, area
    return type(m)(np.ascontiguousarray(P), np.ascontiguousarray(T))


def _meshed_apart(m, run: np.ndarray, levels: np.ndarray, axis: int, tol: float) -> np.ndarray:
    """(len(levels),) bool: the ply runs below and above each interface plane share no node on
    it (a mesh file may mesh each run apart); CaseError if they share only some."""
    apart = np.zeros(len(levels), bool)
    for k, level in enumerate(levels):
        on = [np.unique(m.t[:, side][np.abs(m.p[axis, m.t[:, side]] - level) < tol])
              for side in (run <= k, run > k)]
        shared = np.intersect1d(*on).size
        if shared and (shared < len(on[0]) or shared < len(on[1])):
            raise CaseError(f"mesh.file: the ply runs share {shared} of their {len(on[0])} / {len(on[1])} nodes on "
                            f"the interface {'xyz'[axis]} = {level:g} m; allowed: all of them, or none (meshed apart, "
                            "joined node to face by a cohesive far field)")
        apart[k] = shared == 0
    return apart


def _fem_block(p: dict, built: Built, x0: float, reserve: bool = False):
    """Hex8 laminate on [x0, span / 2] x [0, W / 2] x [0, H], one element layer per particle row
    (or mesh.elements_per_run per ply run; or the mesh.file's part right of x0); ``reserve``:
    as _fem_region's."""
    if p["mesh.file"]:
        return _file_region(p, built, x0)
    lam = built.lam
    m = mesh.box(_along(p, built, x0, reserve),
                 np.linspace(0.0, 0.5 * p["geometry.width"], p["mesh.elements_width"] + 1), _through(p, lam), "hex8")
    run = np.searchsorted(np.cumsum(lam.plies) * lam.ply_thickness, m.p[2, m.t].mean(axis=0))
    C = lam.by_run(lam.C, run)
    return make_region(_split(p, built, m, run), p, C, lam.ply["rho"], 1.0)


def _fem_beam(study, p: dict, built: Built, t_end: float):
    """All-FEM: the impactors on the top face nodes, the symmetry planes held."""
    dim = built.dim
    region = (_fem_block if dim == 3 else _fem_region)(p, built, 0.0)
    X, L, H, d = region.X, built.half_span, built.lam.thickness, built.t
    top = X[:, dim - 1] > H - 1e-9 * H
    # the particles' penalty per particle, times a node's share of the surface in particles
    share_x = max(1.0, np.diff(np.unique(X[top, 0])).min() / d)
    share_y = 1.0
    if dim == 3:  # (a mesh file's: its smallest spacing across the top)
        tol = 1e-6 * d  # (a mesh file's coordinates carry round-off)
        wide = np.diff(np.unique(np.round(X[top, 1] / tol)) * tol).min() if p["mesh.file"] else \
            0.5 * p["geometry.width"] / p["mesh.elements_width"]
        share_y = max(1.0, wide / d)
    imps = {}
    for name in study.layout.names["impactors"]:
        q = section(p, f"impactors.{name}")
        if dim == 3:
            imps[name] = RigidImpactor("cylinder", np.array([0.0, 0.0, H + q["radius"] + 1e-9]), q["radius"],
                                       0.25 * q["mass_per_width"] * p["geometry.width"],
                                       np.array([0.0, 0.0, -q["velocity"]]),
                                       (q["penalty"] or built.lam.ply["E22"] * d) * share_x * share_y,
                                       friction=q["friction"],
                                       axis=np.array([0.0, 1.0, 0.0]))
        elif study.layout.names["impactors"][name] == "flat_punch":  # its face just above the top face
            k_pen = (q["penalty"] or built.lam.transverse_modulus() * d) * share_x
            imps[name] = RigidImpactor("flat_punch", np.array([0.0, H + 1e-9]), q["half_width"],
                                       0.5 * q["mass_per_width"] * d, np.array([0.0, -q["velocity"]]), k_pen,
                                       friction=q["friction"], axis=np.array([0.0, 1.0]))
        else:
            k_pen = (q["penalty"] or built.lam.transverse_modulus() * d) * share_x
            imps[name] = RigidImpactor("cylinder", np.array([0.0, H + q["radius"] + 1e-9]), q["radius"],
                                       0.5 * q["mass_per_width"] * d, np.array([0.0, -q["velocity"]]), k_pen,
                                       friction=q["friction"])
    dyn = ExplicitDynamics(region, supports=_fem_supports(study, p, region, L, dim, symmetry_x=True,
                                                          groups=built.mesh_groups), impactors=list(imps.values()))
    built.dyn, built.impactors, built.fem_elements = dyn, imps, region.n_elements
    built.node_bonds = _far_field_bonds(p, built, dyn)
    return _with_far_field(fem_only(dyn, p, t_end, {}), built)


def _with_far_field(sim, built: Built):
    """The simulation with the far field's node pairs in its energy ledger (when it has any)."""
    if built.node_bonds is not None:
        sim.energies = energies_with(sim.energies, [built.node_bonds])
    return sim


def _far_field_bonds(p: dict, built: Built, dyn: ExplicitDynamics) -> LawBonds | None:
    """A cohesive far field (laminates' far_field_interfaces = "cohesive"): the node
    pairs the mesh doubled at the ply runs' interfaces, joined by the laminate's interface law
    with its penalty (0: 50 x the plies' smallest transverse modulus over the particle size,
    stiff against an element row as Turon et al. 2007 advise, or the elements' own limit if
    lower: participants.fem.cohesive_penalty), each pair
    standing for its share of the interface (times the slice's thickness in 2D); None with
    tied plies."""
    pairs, face = built.fem_pairs, built.fem_face
    if pairs is None or len(pairs) == 0:
        return None
    lam, name = built.lam, p[f"laminates.{p['geometry.laminate']}.interface"]
    itf = lam.interface
    area = built.fem_pair_area * (built.t if dyn.region.dim == 2 else 1.0)  # a 2D slice is t thick
    # as stiff as 50 E_y / d, or the elements' limit (the step of both together: dt_el / sqrt 2 at most)
    m_pair = None if face is None else face_pair_mass(dyn, face)
    K = itf["penalty"] or cohesive_penalty(dyn, pairs, area, 50 * lam.transverse_modulus() / built.t, m_pair)
    try:
        law = HashinCohesiveLaw(K=K, Z0=itf["Z0"], R0=itf["R0"], GIc=itf["GIc"], GIIc=itf["GIIc"])
    except ValueError as exc:
        raise CaseError(f"interfaces.{name}.penalty = {itf['penalty']:g}: {exc}") from None
    if face is not None:  # runs meshed apart somewhere: every interface's bonds node to face
        return node_to_face_bonds(dyn, face, area, law, itf["friction"])
    return cohesive_node_bonds(dyn, pairs, area, law, itf["friction"])


def interlaminar_law(p: dict, lam, K: float, d: float) -> HashinCohesiveLaw:
    """The particles' interface law of laminate ``lam`` at the lattice's penalty K = E_transverse
    / d (Pa/m, d the particle size in m); a toughness below the elastic energy at initiation,
    tau^2 / (2 K), is refused naming its keys (linear softening cannot start there)."""
    itf = lam.interface
    name = p[f"laminates.{p['geometry.laminate']}.interface"]
    for tau, gc in (("Z0", "GIc"), ("R0", "GIIc")):
        need = itf[tau] ** 2 / (2 * K)
        if itf[gc] < need:
            raise CaseError(f"interfaces.{name}.{gc} = {itf[gc]:g}: below the elastic energy at initiation "
                            f"{tau}^2 / (2 K) = {need:.4g} J/m^2 of the particles (K = {K:.4g} Pa/m, the transverse "
                            f"modulus over the particle size {d:g} m); allowed: {gc} >= that, a lower {tau}, "
                            "a stiffer ply or smaller particles")
    return HashinCohesiveLaw(K=K, Z0=itf["Z0"], R0=itf["R0"], GIc=itf["GIc"], GIIc=itf["GIIc"])


def _particle_zone(built: Built, x_end: float, tied: bool, clamped: bool):
    """(lattice, engine scene, intralaminar LawBonds, interlaminar LawBonds) on [0, x_end] x
    [0, H]: column 0 on the symmetry plane; the last on the FEM's face (``tied``), or the
    beam's end, held by a clamp if ``clamped``."""
    lam, d = built.lam, built.t
    k = round(d / lam.ply_thickness)
    mat = lam.material(moduli={a: ply_lattice.slice_moduli(lam.D(a)) for a in set(lam.angles)})
    try:
        lat = ply_lattice.build(0.0, int(round(x_end / d)) + 1, 0.0, [n // k for n in lam.plies], lam.angles, d, mat)
    except ValueError as exc:  # a shear modulus the square lattice cannot carry
        material = built.p[f"laminates.{built.p['geometry.laminate']}.material"]
        raise CaseError(f"materials.{material}.G12 = {lam.ply['G12']:g}: {exc}") from None
    last = lat.column == lat.column.max()
    on_plane = (lat.column == 0) | (last & tied)  # half cells
    l = lat.x[lat.intra_pairs[:, 1]] - lat.x[lat.intra_pairs[:, 0]]
    intra = LawBonds(lat.intra_pairs, lat.x, l, np.where(on_plane[lat.intra_pairs].all(axis=1), 0.5, 1.0) * d * d,
                     lat.intra_law, volume=lat.cell_volume() * np.where(on_plane, 0.5, 1.0), label="intralaminar")
    law = interlaminar_law(built.p, lam, lat.inter_K, d)
    inter = LawBonds(lat.inter_pairs, lat.x, np.tile([0.0, 1.0, 0.0], (len(lat.inter_pairs), 1)),
                     np.where(on_plane[lat.inter_pairs].all(axis=1), 0.5, 1.0) * d * d, law,
                     friction=lam.interface["friction"], label="interlaminar", along=lat.inter_along)
    lat.density = lat.density * np.where(on_plane, 0.5, 1.0)
    groups = {"interface": np.flatnonzero(last)} if tied else {"fixed": np.flatnonzero(last)} if clamped else {}
    pairs = np.vstack([lat.intra_pairs, lat.inter_pairs])
    k_hold = 1e-9 * float(np.max(lat.intra_law.K)) * d**2  # placeholder bonds: the laws act through LawBonds
    scene = DemScene(lat.x, lat.radius, lat.density, pairs, kn=k_hold, ks=0.0, plane=True,
                     young=float(np.max(lat.intra_law.K)) * d, placeholder_bonds=True, groups=groups)
    return lat, scene, intra, inter


def _particle_block(built: Built, x_end: float, tied: bool, clamped: bool):
    """(block, engine scene, intralaminar LawBonds, interlaminar LawBonds) on [0, x_end] x
    [0, W / 2] x [0, H]; half cells on the symmetry planes, the free edge and (``tied``) the
    FEM's face; the last column held by a clamp if ``clamped``."""
    d, p = built.t, built.p
    M, N = _columns_across(p, d), int(round(x_end / d)) + 1
    block, intra, inter = _block_with_laws(built, (N, M), [(0, 0), (1, 0), (1, M - 1)] + ([(0, N - 1)] if tied else []))
    last = np.flatnonzero(block.index[:, 0] == N - 1)
    groups = {"interface": last} if tied else {"fixed": last} if clamped else {}
    return block, ply_block.engine_scene(block, groups=groups), intra, inter


def _block_with_laws(built: Built, columns: tuple[int, int], half: list, cells: np.ndarray | None = None):
    """(3D ply block of ``columns`` (nx, ny) particle columns with cells halved on ``half``, or
    carved to the selected ``cells`` (ply_block.carve), its intralaminar and interlaminar
    LawBonds)."""
    lam, d, p = built.lam, built.t, built.p
    k = round(d / lam.ply_thickness)
    try:
        block = ply_block.build((0.0, 0.0, 0.0), columns, [n // k for n in lam.plies], lam.angles, d, lam.material(),
                                half_planes=half)
    except ValueError as exc:
        material = p[f"laminates.{p['geometry.laminate']}.material"]
        raise CaseError(f"materials.{material}.G12 = {lam.ply['G12']:g}: {exc}") from None
    if cells is not None:
        block, _ = ply_block.carve(block, cells)
    l = block.x[block.intra_pairs[:, 1]] - block.x[block.intra_pairs[:, 0]]
    intra = LawBonds(block.intra_pairs, block.x, l, block.intra_area, block.intra_law, volume=block.volume,
                     label="intralaminar")
    itf = lam.interface
    law = interlaminar_law(p, lam, block.inter_K, d)
    inter = LawBonds(block.inter_pairs, block.x, np.tile([0.0, 0.0, 1.0], (len(block.inter_pairs), 1)),
                     block.inter_area, law, friction=itf["friction"], along=block.inter_along, label="interlaminar")
    return block, intra, inter


def _particle_impactor(p: dict, name: str, built: Built) -> ParticleImpactor:
    """The part of the cylinder (or, 2D, the flat punch) the symmetry planes leave (a half in 2D,
    a quarter in 3D) on the top rows, moving only vertically."""
    q, lat, d = section(p, f"impactors.{name}"), built.lattice, built.t
    if built.dim == 3:
        H, R, r = built.lam.thickness, q["radius"], lat.radius
        top = np.flatnonzero(lat.index[:, 2] >= lat.index[:, 2].max() - 1)
        cyl = RigidImpactor("cylinder", np.array([0.0, 0.0, H - d / 2 + R + r + 1e-9]), R + r,
                            0.25 * q["mass_per_width"] * p["geometry.width"], np.array([0.0, 0.0, -q["velocity"]]),
                            q["penalty"] or built.lam.ply["E22"] * d, friction=q["friction"],
                            axis=np.array([0.0, 1.0, 0.0]))
        return ParticleImpactor(cyl, top, fixed=(True, True, False))
    r, H = lat.radius, built.lam.thickness
    k_pen = q["penalty"] or built.lam.transverse_modulus() * d
    top = np.flatnonzero(lat.row >= lat.row.max() - 1)
    if "half_width" in q:  # a flat punch: its face grown by the particle radius meets the top centres
        punch = RigidImpactor("flat_punch", np.array([0.0, H + 1e-9, 0.0]), q["half_width"],
                              0.5 * q["mass_per_width"] * d, np.array([0.0, -q["velocity"], 0.0]), k_pen,
                              friction=q["friction"], axis=np.array([0.0, 1.0, 0.0]), rounding=r)
        return ParticleImpactor(punch, top, fixed=(True, False, True))
    R = q["radius"]
    imp = RigidImpactor("sphere", np.array([0.0, H - d / 2 + R + r + 1e-9, 0.0]), R + r, 0.5 * q["mass_per_width"] * d,
                        np.array([0.0, -q["velocity"], 0.0]), k_pen, friction=q["friction"])
    return ParticleImpactor(imp, top, fixed=(True, False, True))


# -- a plate ------------------------------------------------------------------------------------
def plate(study, p: dict, mode: str, dem: str, start=None):
    """(Simulation, Built) of a quarter of a rectangular laminated plate (symmetry planes x = 0
    and y = 0, the thickness along z) under an impactor (a sphere or a flat-faced rod) or a
    pressure history on a disc (study/pressure.py) at its centre, supported at its edges; the
    zone a column through the thickness whose footprint zone.shape selects (study/selectors.py);
    start: the state a coupled run continues from (a grown zone's, coupled_simulation's)."""
    built = body_of(p, mode)
    d, t_end = built.t, study.t_end
    a2, b2 = 0.5 * p["geometry.span"], 0.5 * p["geometry.width"]
    whole_spacings(p, d)
    from .bonded import load_curve
    from .pressure import fem_pressure, particle_pressure  # (they import the disc, which imports this)
    grow = mode == "coupled" and p.get("zone.grow", False)
    fp = footprint(study, p, built, cell_wise=grow)
    if grow:
        _check_plate_growth(p, built, fp)
    clamp = _support(study, p) == "clamped"
    names, loads = list(study.layout.names["impactors"]), list(study.layout.names["loads"])
    curve = load_curve(p, loads[0]) if loads else None
    H = built.lam.thickness
    if mode == "fem":
        region = _fem_plate(p, built, fp, hole=False)
        imps = {name: _fem_striker(study, p, name, built, region) for name in names}
        dyn = ExplicitDynamics(region, supports=_plate_supports(region, built, clamp, symmetry=True),
                               impactors=list(imps.values()), loads=fem_pressure(p, loads, region, H, curve))
        built.dyn, built.impactors, built.fem_elements = dyn, imps, region.n_elements
        built.node_bonds = _far_field_bonds(p, built, dyn)
        if loads:
            built.load_probes = {loads[0]: lambda: float(curve(dyn.state.t))}
        return _with_far_field(fem_only(dyn, p, t_end, {}), built), built
    tied = mode == "coupled"
    if tied:
        nx = ny = int(round(fp.w / d)) + 1
        cells = fp.cells(d)
        block, intra, inter = _block_with_laws(built, (nx, ny), [], cells=cells)
        i, j = block.index[:, 0], block.index[:, 1]
        edge = np.flatnonzero(tie_particles(cells, i, j))
        grid = np.ones((nx, ny), bool)  # particle columns, False on the tied edge (distances from it)
        grid[i[edge], j[edge]] = False
        to_edge = ndimage.distance_transform_cdt(grid, metric="chessboard")[i, j]
    else:
        nx, ny = int(round(a2 / d)) + 1, int(round(b2 / d)) + 1
        block, intra, inter = _block_with_laws(built, (nx, ny), [(0, 0), (1, 0)])
        i, j = block.index[:, 0], block.index[:, 1]
        to_edge = np.minimum(nx - 1 - i, ny - 1 - j)  # columns to the plate's edge
        edge = np.flatnonzero(to_edge == 0)
    groups = {"interface": edge} if tied else {"fixed": edge} if clamp else {}
    scene = ply_block.engine_scene(block, groups=groups)
    built.lattice, built.intra, built.inter = block, intra, inter
    built.column = to_edge.max() - to_edge  # the largest on the edge, as a beam's last column
    built.end_held = tied or clamp
    built.impactors = {name: _particle_striker(study, p, name, built) for name in names}
    models = (intra, inter, *built.impactors.values())
    if loads:
        load = particle_pressure(p, loads[0], block, cells if tied else None, (a2, b2), curve)
        models += (load,)
        built.particle_loads = [load]
        built.load_probes = {loads[0]: lambda: float(curve(load.time))}
    held = np.concatenate([scene.groups.get("interface", []), scene.groups.get("fixed", [])]).astype(int)

    def hold(backend) -> None:  # the symmetry planes
        hold_symmetry_planes(backend, i, j, held)

    if mode == "dem":
        sim, backend, _ = dem_only(p, scene, dem, t_end, models=models)
        if not clamp:  # simply supported: the bottom particles of the edges, vertically
            bottom = edge[block.index[edge, 2] == 0]
            backend.prescribe(bottom, "z")
            backend.set_velocities(bottom, np.zeros((len(bottom), 3)))
        hold(backend)
    else:
        def make(extra_mass):
            region = _fem_plate(p, built, fp, hole=True, reserve=plate_grow_limit(p, built) if grow else 0.0)
            dyn = ExplicitDynamics(region, supports=_plate_supports(region, built, clamp, symmetry=True),
                                   extra_mass=extra_mass, loads=fem_pressure(p, loads, region, H, curve))
            built.node_bonds = _far_field_bonds(p, built, dyn)
            return dyn
        sim, clock = coupled_simulation(p, make, scene, dem, t_end, models=models, start=start, hold=hold)
        backend, built.dyn, built.fem_elements = clock.dem, clock.fem, clock.fem.region.n_elements
        built.clock = clock
        _with_far_field(sim, built)
    built.models = models
    built.backend = backend
    sim.counts.update({"law_bonds": len(intra.pairs) + len(inter.pairs)})
    return sim, built


def _plate_axis(w: float, half: float, n_zone: int, n: int, ratio: float) -> np.ndarray:
    """Node coordinates on [0, half]: n_zone equal elements over the zone's [0, w], then n graded
    from w (smallest there) to the edge."""
    return np.concatenate([np.linspace(0.0, w, n_zone + 1)[:-1], mesh.graded(w, half, n, ratio, w)])


def spacing_below(x: float, d: float) -> float:
    """m, the last whole particle spacing d strictly below x (a growing zone's default limit)."""
    return (np.ceil(x / d - 1e-9) - 1) * d


def plate_grow_limit(p: dict, built: Built) -> float:
    """The farthest a plate's grown zone may reach (m): zone.grow_to, or the last whole particle
    spacing below 0.8 x the smaller half side (a zone's limit)."""
    d, half = built.t, 0.5 * min(p["geometry.span"], p["geometry.width"])
    return p["zone.grow_to"] or spacing_below(0.8 * half, d)


def _check_plate_growth(p: dict, built: Built, fp) -> None:
    """A plate's growing zone: a box footprint (its edge a mesh line at any width), a kinematic
    tie, grow_to whole spacings from the zone's half width to below 0.8 x the smaller half side;
    CaseError otherwise."""
    d, half = built.t, 0.5 * min(p["geometry.span"], p["geometry.width"])
    if p["zone.shape"] != "box":
        raise CaseError(f"zone.shape = {p['zone.shape']!r}: a plate's zone grows as a box (zone.grow = true); "
                        "allowed: box")
    xg = plate_grow_limit(p, built)
    check_growth(p, d, fp.w, xg, xg < 0.8 * half, f"below 0.8 x the smaller half side ({0.8 * half:g} m)")


def _reserved_axis(xg: float, half: float, d: float, n: int, ratio: float) -> np.ndarray:
    """Node coordinates on [0, half] for a zone that may grow to xg: elements of one particle
    spacing d out to xg (any grown zone's edge a mesh line), then graded to the edge from elements
    no shorter than d (the stable step stays the particle-sized elements'), the most of n that
    allows it."""
    for k in range(n, 0, -1):
        rest = mesh.graded(xg, half, k, ratio ** (1.0 / max(k - 1, 1)), xg)
        if rest[1] - rest[0] >= d * (1 - 1e-9) or k == 1:
            break
    return np.concatenate([np.arange(int(round(xg / d))) * d, rest])


def _fem_plate(p: dict, built: Built, fp, hole: bool, reserve: float = 0.0):
    """Hex8 laminate on the quarter plate, one element layer per particle row, mesh.elements_width
    equal elements over the zone's square; with ``hole`` the zone's elements (those whose centre
    its footprint holds) left out (the FEM around the particles); ``reserve`` (m, a zone that may
    grow to there): elements of one particle cell out to it (_reserved_axis)."""
    lam, k, w = built.lam, p["zone.plies_per_particle"], fp.w
    n, nz = p["mesh.elements_along"], fp.n
    ratio = p["mesh.element_ratio"] ** (1.0 / max(n - 1, 1))
    if reserve:
        axes = [_reserved_axis(reserve, 0.5 * p[key], built.t, n, p["mesh.element_ratio"])
                for key in ("geometry.span", "geometry.width")]
    else:
        axes = [_plate_axis(w, 0.5 * p[key], nz, n, ratio) for key in ("geometry.span", "geometry.width")]
    m = mesh.box(*axes, np.linspace(0.0, lam.thickness, sum(lam.plies) // k + 1), "hex8")
    centre = m.p[:, m.t].mean(axis=1)
    if hole:
        m = m.remove_elements(np.flatnonzero(fp.inside(centre[0], centre[1])))
        centre = m.p[:, m.t].mean(axis=1)
    run = np.searchsorted(np.cumsum(lam.plies) * lam.ply_thickness, centre[2])
    return make_region(_split(p, built, m, run), p, lam.by_run(lam.C, run), lam.ply["rho"],
                       1.0)


def _plate_supports(region, built: Built, clamp: bool, symmetry: bool) -> list[PrescribedMotion]:
    """Clamped edges (every DOF at x = span / 2 and y = width / 2) or simply supported ones
    (their bottom edges, vertically); the symmetry planes x = 0 and y = 0."""
    X, p = region.X, built.p
    a2, b2 = 0.5 * p["geometry.span"], 0.5 * p["geometry.width"]
    tol = 1e-9 * max(a2, b2)
    edge = np.flatnonzero((np.abs(X[:, 0] - a2) < tol) | (np.abs(X[:, 1] - b2) < tol))
    if clamp:
        out = [PrescribedMotion(np.concatenate([3 * edge + c for c in range(3)]))]
    else:
        out = [PrescribedMotion(3 * edge[X[edge, 2] < tol] + 2)]
    if symmetry:
        out += [PrescribedMotion(3 * np.flatnonzero(np.abs(X[:, 0]) < tol)),
                PrescribedMotion(3 * np.flatnonzero(np.abs(X[:, 1]) < tol) + 1)]
    return out


def _particle_striker(study, p: dict, name: str, built: Built) -> ParticleImpactor:
    """A quarter of the sphere or rod (two symmetry planes cut it) on the top rows, moving only
    along z; a rod's face grown by the particle radius meets the particle centres (a rounded
    edge), its penalty per area times d^2 per particle."""
    q, block, d = section(p, f"impactors.{name}"), built.lattice, built.t
    H, r = built.lam.thickness, block.radius
    top = np.flatnonzero(block.index[:, 2] >= block.index[:, 2].max() - 1)
    if study.layout.names["impactors"][name] == "rod":
        from .disc import rod
        return ParticleImpactor(rod(p, name, H, q["penalty"] * d**2, rounding=r), top,
                                fixed=(True, True, False))
    R = q["radius"]
    ball = RigidImpactor("sphere", np.array([0.0, 0.0, H - d / 2 + R + r + 1e-9]), R + r, 0.25 * q["mass"],
                         np.array([0.0, 0.0, -q["velocity"]]), q["penalty"] or built.lam.ply["E22"] * d,
                         friction=q["friction"])
    return ParticleImpactor(ball, top, fixed=(True, True, False))


def _fem_striker(study, p: dict, name: str, built: Built, region) -> RigidImpactor:
    """A quarter of the sphere or rod on the FEM's top nodes. A sphere: the particles' penalty
    times a node's share of the surface in particles. A rod: each node's consistent share of
    its face (penalty per area x the integral of the node's shape function over the face)."""
    q, d, H, X = section(p, f"impactors.{name}"), built.t, built.lam.thickness, region.X
    top = X[:, 2] > H - 1e-9 * H
    if study.layout.names["impactors"][name] == "rod":
        from .disc import face_shares, rod
        share = face_shares(region, H, q["radius"])
        striker = rod(p, name, H, q["penalty"] * float(share.max()))
        striker.footprint = q["penalty"] * share
        return striker
    share = max(1.0, np.diff(np.unique(X[top, 0])).min() / d) * max(1.0, np.diff(np.unique(X[top, 1])).min() / d)
    return RigidImpactor("sphere", np.array([0.0, 0.0, H + q["radius"] + 1e-9]), q["radius"], 0.25 * q["mass"],
                         np.array([0.0, 0.0, -q["velocity"]]), (q["penalty"] or built.lam.ply["E22"] * d) * share,
                         friction=q["friction"])
