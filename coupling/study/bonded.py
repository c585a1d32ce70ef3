"""The assembler of a bonded beam: a beam of one quasi-brittle isotropic material (concrete)
with a fibre sheet (CFRP) bonded to its bottom face, on two supports inside its length,
under a load history on a patch of its top face (the seed paper's example 5.4).

Shapes: ``bonded_beam``, a plane-stress slice one particle size thick, half model about
x = 0; ``bonded_beam_3d``, a quarter (symmetry planes x = 0 and mid-width y = 0, free side
faces, the depth along z). Modes as every study: ``coupled`` (particles for |x| <=
zone.half_width over the whole depth, FEM outside, tied at the zone's face), ``fem`` (no
fracture: the cheap bound and the reference of the cracking checks) and ``dem`` (the whole
beam as particles).

Particles: the body as an isotropic lattice (2D: ply_lattice with the plane-stress slice
moduli; 3D: ply_block, E and G = E / (2 (1 + nu)) exact) with PlyBondLaw (Hoffman with ft,
fc and the isotropic shear strength sqrt(ft fc / 3) (Hoffman 1967), Gf-regularised
softening, strengths scattered by 1 +- strength_scatter); a sheet particle under each bottom
column (2D: axial bonds along the fibres; 3D: a membrane lattice, axial bonds along x and y
and two diagonals per cell for G12), its Hoffman ply law; Hashin bonds between each sheet
particle and the body particle above it (the half cells of both in series), friction after
debonding. The sheet's spheres get the lattice's radius and the sheet's mass: engines size
their contact search by the bond reach over the radii (YADE: 9 x slower with t_s / 2).

FEM: element rows of d (one per particle row), the first holding the sheet and the bottom d of
the body smeared (its axial stiffness and mass exact, its lever arm half a particle off: 0.7 %
of the bending stiffness of the seed beam); columns of d up to the zone's edge, growing by
mesh.growth to mesh.max_size towards the support, a node line at the support, then equal
columns to the end. The support is a line (a node in 2D) under the sheet at x = span / 2,
held vertically (in all-DEM, the support column's sheet and bottom body particles).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dem_region import ply_block, ply_lattice
from dem_region.particle_load import ParticleLoad
from dem_region.scatter import strength_scale
from dem_region.scene import DemScene
from fem_region import loads as fem_loads, materials, mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from physics.failure import HoffmanStrengths
from physics.law_bonds import LawBonds
from physics.laws import HashinCohesiveLaw, PlyBondLaw

from ..params import CaseError
from ..participants.coupled import coupled_simulation
from ..participants.dem import dem_only, hold_symmetry_planes
from ..participants.fem import fem_only, make_region
from .assemble import Built, check_growth
from .schema import section


@dataclass
class Particles:
    """The zone's particles: x (n, 3) m at rest, their part (0 body, 1 sheet), radius m."""

    x: np.ndarray
    part: np.ndarray
    radius: float

    @property
    def n(self) -> int:
        return len(self.x)

    @property
    def ply(self) -> np.ndarray:  # fields.xdmf's "ply" column: the part
        return self.part


@dataclass
class BondedBeam:
    """A bonded beam's data, SI: the body's and the sheet's [materials.*] fields, the
    adhesive's [interfaces.*] fields, the sheet's thickness, the particle size d and rows."""

    body: dict
    sheet: dict
    adhesive: dict
    ts: float
    depth: float
    d: float
    rows: int
    length: float
    span: float

    def body_C(self) -> np.ndarray:
        return materials.isotropic(self.body["E"], self.body["nu"])

    def sheet_C(self) -> np.ndarray:
        """(6, 6) Pa of the sheet, fibres along x."""
        m = self.sheet
        return materials.orthotropic(m["E11"], m["E22"], m["E22"], m["nu12"], m["nu12"], m["nu23"], m["G12"],
                                     m["G12"], m["G23"])

    def body_strengths(self) -> HoffmanStrengths:
        ft, fc = self.body["ft"], self.body["fc"]
        S = np.sqrt(ft * fc / 3)  # Hoffman's criterion for an isotropic material (Hoffman 1967)
        return HoffmanStrengths(Xt=ft, Xc=fc, Yt=ft, Yc=fc, Zt=ft, Zc=fc, S23=S, S13=S, S12=S)

    def sheet_strengths(self) -> HoffmanStrengths:
        m = self.sheet
        return HoffmanStrengths(Xt=m["Xt"], Xc=m["Xc"], Yt=m["Yt"], Yc=m["Yc"], Zt=m["Yt"], Zc=m["Yc"],
                                S23=m["S23"], S13=m["S12"], S12=m["S12"])

    def adhesive_law(self, K: float) -> HashinCohesiveLaw:
        a = self.adhesive
        return HashinCohesiveLaw(K=K, Z0=a["Z0"], R0=a["R0"], GIc=a["GIc"], GIIc=a["GIIc"])


def bonded_of(study, p: dict) -> BondedBeam:
    """The beam's data from the resolved parameters; CaseError if its particles do not fit."""
    (name,) = study.layout.names["sheets"]
    sh = section(p, f"sheets.{name}")
    supports = study.layout.names["supports"]
    if len(supports) != 1 or p[f"supports.{next(iter(supports))}.condition"] != "simply_supported":
        raise CaseError("supports: a bonded beam takes one [supports.NAME] at its ends, condition = "
                        "'simply_supported' (a line under the sheet at x = +-span / 2)")
    d, H, span = p["zone.particle_size"], p["geometry.depth"], p["geometry.span"]
    length = p["geometry.length"] or span
    n = int(round(H / d)) if d > 0 else 0
    if n < 4 or abs(n * d - H) > 1e-6 * H:
        raise CaseError(f"zone.particle_size = {d:g}: the depth {H:g} m must hold a whole number (>= 4) of rows")
    if not 2 * H < span <= length:
        raise CaseError(f"geometry.span = {span:g}: allowed between two depths ({2 * H:g} m) and the length "
                        f"{length:g} m")
    return BondedBeam(section(p, f"materials.{p['geometry.material']}"), section(p, f"materials.{sh['material']}"),
                      section(p, f"interfaces.{sh['interface']}"), sh["thickness"], H, d, n, length, span)


def load_curve(p: dict, name: str):
    """t (s) -> the whole load (N) of [loads.name]: its curve (or file) scaled to SI, zero
    outside, times its scale."""
    q = section(p, f"loads.{name}")
    if q["file"]:
        try:
            f = fem_loads.tabulated(q["file"], q["time_scale"], q["value_scale"])
        except (OSError, ValueError) as exc:
            raise CaseError(f"loads.{name}.file = {q['file']!r}: {exc}") from None
        t, F = f.t, f.value
    else:
        t, F = np.array(q["curve"]).T * [[q["time_scale"]], [q["value_scale"]]]
    return fem_loads.Table(t, F, q["scale"])


# -- the assembly --------------------------------------------------------------------------------
def bonded_beam(study, p: dict, mode: str, dem: str, start=None):
    """(Simulation, Built) of a bonded beam (slice or quarter) in ``mode``; start: the state a
    coupled run continues from (a grown zone's, coupled_simulation's)."""
    bb = bonded_of(study, p)
    dim = 3 if p["geometry.shape"] == "bonded_beam_3d" else 2
    d, W = bb.d, p["geometry.width"]
    if dim == 3:
        m = 0.5 * W / d
        if abs(m - round(m)) > 1e-6 or round(m) < 1:
            raise CaseError(f"zone.particle_size = {d:g}: half the width {W:g} m must hold a whole number of "
                            "particle spacings")
    (load_name,) = study.layout.names["loads"]
    if p[f"loads.{load_name}.width"] / 2 >= bb.span / 2:
        raise CaseError(f"loads.{load_name}.width = {p[f'loads.{load_name}.width']:g}: must be narrower than the span")
    curve = load_curve(p, load_name)
    width_share = d / W  # a 2D slice's share of the whole width
    built = Built(p, mode, None, 0.5 * bb.span, d, 4.0 if dim == 3 else 2 / width_share, dim=dim)
    built.bonded = bb
    if mode == "fem":
        return _fem_beam(study, p, bb, built, curve, load_name), built
    L, s = bb.length / 2, bb.span / 2
    w = L if mode == "dem" else p["zone.half_width"]
    given, w = w, d * round(w / d)
    # (the zone as built, whole spacings, within the limits with their round-off: grow_limit's
    # d floor(s / d - 4) may read an ulp past s - 4 d, and a zone grown to it was refused mid-run)
    if mode == "coupled" and not 4 * d * (1 - 1e-9) <= w <= (s - 4 * d) * (1 + 1e-9):
        raise CaseError(f"zone.half_width = {given:g}: allowed from four particle sizes ({4 * d:g} m) to four short "
                        f"of the support ({s - 4 * d:g} m), in whole particle sizes")
    tied = mode == "coupled"
    grow = tied and p.get("zone.grow", False)
    if grow:
        _check_growth(p, bb, w)
    zone = (_Zone3 if dim == 3 else _Zone2)(bb, p, w, tied)
    load = zone.load(p[f"loads.{load_name}.width"] / 2, curve, width_share)
    models = zone.models + (load,)
    up = dim - 1
    if mode == "dem":
        sim, backend, _ = dem_only(p, zone.scene, dem, study.t_end, models=models)
        # the support holds the column through the adhesive (the sheet's particle and the body's
        # bottom one): held on the sheet alone, the reaction tore the adhesive there
        c = zone.column[zone.sheet_ids[np.argmin(np.abs(zone.x[zone.sheet_ids, 0] - s))]]
        support = np.flatnonzero((zone.column == c) & (zone.x[:, up] < d))
        backend.prescribe(support, "yz"[up - 1])
        backend.set_velocities(support, np.zeros((len(support), 3)))
        _hold(backend, zone, support, dim)
    else:
        def make(extra_mass):
            region = _fem_region(p, bb, w, dim, grow_limit(p, bb) if grow else 0.0)
            return ExplicitDynamics(region, supports=_supports(region, bb, dim, symmetry_x=False),
                                    extra_mass=extra_mass)
        sim, clock = coupled_simulation(p, make, zone.scene, dem, study.t_end, models=models, start=start,
                                        hold=lambda backend: _hold(backend, zone, zone.scene.groups["interface"], dim))
        backend, built.dyn, built.fem_elements = clock.dem, clock.fem, clock.fem.region.n_elements
        built.clock = clock
    built.backend, built.column = backend, zone.column
    built.lattice = Particles(zone.x, zone.part, d / 2)
    built.intra, built.inter, built.sheet = zone.body, zone.bond, zone.sheet
    built.models = models
    built.width_index = zone.width_index
    built.bond_whole = zone.bond_whole
    built.end_held, built.edge_intra = tied, True
    whole = (lambda: float(-4 * load.force()[2])) if dim == 3 else \
        (lambda: float(-2 * load.force()[1] / width_share))
    built.load_probes = {load_name: whole}
    sim.counts.update({"law_bonds": sum(len(b.pairs) for b in zone.models)})
    return sim, built


def _hold(backend, zone, held: np.ndarray, dim: int) -> None:
    """The symmetry planes (x = 0; in 3D also mid-width y = 0), but for the particles ``held``
    already (tie, support)."""
    if dim == 3:
        hold_symmetry_planes(backend, zone.column, zone.width_index, held)
    else:
        axis = np.flatnonzero(zone.column == 0)
        backend.prescribe(axis, "x")
        backend.set_velocities(axis, np.zeros((len(axis), 3)))


def _fem_beam(study, p: dict, bb: BondedBeam, built: Built, curve, load_name: str):
    """All-FEM: the load as a traction on the top face under the patch, exact in total."""
    dim = built.dim
    region = _fem_region(p, bb, 0.0, dim)
    H = bb.depth
    a = p[f"loads.{load_name}.width"] / 2
    if dim == 3:
        load = fem_loads.surface_traction(region, lambda x: (x[2] > H * (1 - 1e-9)) & (x[0] < a), [0.0, 0.0, -1.0],
                                          curve)
        load.amplitude = load.amplitude * (0.25 / -np.sum(load.amplitude))  # a quarter of the load, exactly
        supports = _supports(region, bb, dim, symmetry_x=True)
    else:
        width_share = bb.d / built.p["geometry.width"]
        pressure = 1.0 / (p[f"loads.{load_name}.width"] * p["geometry.width"])  # Pa per N of load
        load = fem_loads.surface_traction(region, lambda x: (x[1] > H * (1 - 1e-9)) & (x[0] < a), [0.0, -pressure],
                                          curve)
        # the facets under the patch end on a mesh line, not at its edge: scale to the exact total
        load.amplitude = load.amplitude * (0.5 * width_share / -np.sum(load.amplitude))
        supports = _supports(region, bb, dim, symmetry_x=True)
    dyn = ExplicitDynamics(region, supports=supports, loads=[load])
    built.dyn, built.fem_elements = dyn, region.n_elements
    built.load_probes = {load_name: lambda: float(curve(dyn.state.t))}
    built.fibre_stiffness = (bb.body_C() if dim == 3 else materials.plane_stress(bb.body_C()))[0]
    return fem_only(dyn, p, study.t_end, {})


def _lines(x0: float, x1: float, h0: float, growth: float, h_max: float) -> list[float]:
    xs, h = [x0], h0
    while xs[-1] + 1.5 * h < x1:
        xs.append(xs[-1] + h)
        h = min(h * growth, h_max)
    return xs + [x1]


def grow_limit(p: dict, bb: BondedBeam) -> float:
    """The farthest a grown zone may reach (m): zone.grow_to, or the last whole particle spacing
    four spacings short of the support (the zone's own limit)."""
    return p["zone.grow_to"] or bb.d * np.floor(bb.span / 2 / bb.d - 4 + 1e-9)


def _check_growth(p: dict, bb: BondedBeam, w: float) -> None:
    """A growing zone's keys (as the beams', assemble.beam): a kinematic tie, grow_to whole spacings
    from the zone's half width to four spacings short of the support; CaseError otherwise."""
    d, s = bb.d, bb.span / 2
    xg = grow_limit(p, bb)
    check_growth(p, d, w, xg, xg <= (s - 4 * d) * (1 + 1e-9), f"four short of the support ({s - 4 * d:g} m)")


def _fem_region(p: dict, bb: BondedBeam, x0: float, dim: int, reserve: float = 0.0):
    """The FEM half (2D) or quarter (3D) beam on [x0, length / 2] over [-t_sheet, depth];
    ``reserve`` (m, a zone that may grow to there): columns of d out to it first, so that any
    grown zone's edge is a mesh line and its far field the same mesh less the converted columns."""
    n, d, ts = bb.rows, bb.d, bb.ts
    L, s = bb.length / 2, bb.span / 2
    cols = list(d * np.arange(int(round(x0 / d)), int(round(reserve / d)))) if reserve > x0 else []
    xs = cols + _lines(cols[-1] + d if cols else x0, s, d, p["mesh.growth"], p["mesh.max_size"])
    if L - s > 1e-9 * L:  # the overhang beyond the support (none when the span is the length)
        xs += list(np.linspace(s, L, max(2, int(np.ceil((L - s) / p["mesh.max_size"]))) + 1)[1:])
    depth = np.concatenate([[-ts], d * np.arange(1, n + 1)])
    if dim == 3:
        m = mesh.box(np.array(xs), np.linspace(0.0, 0.5 * p["geometry.width"], p["mesh.elements_width"] + 1), depth,
                     "hex8")
        Cc, Cs = bb.body_C(), bb.sheet_C()
    else:
        m = mesh.rectangle(np.array(xs), depth, "quad4")
        Cc, Cs = materials.plane_stress(bb.body_C()), materials.plane_stress(bb.sheet_C())
    bottom = m.p[dim - 1, m.t].mean(axis=0) < d / 2
    C = np.where(bottom[:, None, None], (d * Cc + ts * Cs) / (d + ts), Cc)
    rho_c, rho_s = bb.body["rho"], bb.sheet["rho"]
    rho = np.where(bottom, (d * rho_c + ts * rho_s) / (d + ts), rho_c)
    return make_region(m, p, C, rho, 1.0 if dim == 3 else d)


def _supports(region, bb: BondedBeam, dim: int, symmetry_x: bool) -> list[PrescribedMotion]:
    """The support under the sheet at x = span / 2, held vertically; in 3D the mid-width
    symmetry plane; the mid-span plane when the FEM reaches it."""
    X, s = region.X, bb.span / 2
    if dim == 2:
        node = np.argmin(np.abs(X[:, 0] - s) + np.abs(X[:, 1] - X[:, 1].min()))
        out = [PrescribedMotion(np.array([2 * node + 1]))]
        if symmetry_x:
            out.append(PrescribedMotion(2 * np.flatnonzero(X[:, 0] < 1e-9)))
        return out
    xs = np.unique(X[:, 0])
    line = np.flatnonzero((np.abs(X[:, 0] - xs[np.argmin(np.abs(xs - s))]) < 1e-12) & (X[:, 2] < X[:, 2].min() + 1e-12))
    out = [PrescribedMotion(3 * line + 2), PrescribedMotion(3 * np.flatnonzero(X[:, 1] < 1e-12) + 1)]
    if symmetry_x:
        out.append(PrescribedMotion(3 * np.flatnonzero(X[:, 0] < 1e-12)))
    return out


# -- the particle zones --------------------------------------------------------------------------
class _Zone2:
    """The zone on [0, x_end] of the slice: the body's lattice (rows above y = 0), a sheet
    particle at y = -t_sheet / 2 under each column, their laws, the engine scene. Column 0 lies
    on the symmetry plane and (``tied``) the last on the FEM's face: half their cells are in the
    zone (half mass, vertical bonds half area)."""

    def __init__(self, bb: BondedBeam, p: dict, x_end: float, tied: bool):
        d, ts, t = bb.d, bb.ts, bb.d  # t: the slice's thickness
        Ex, Ey, G = ply_lattice.slice_moduli(materials.plane_stress(bb.body_C()))
        c = bb.body
        mat = ply_lattice.PlyMaterial(Ex, Ey, G, G, c["rho"], bb.body_strengths(), c["Gf"], c["Gf"],
                                      moduli={0.0: (Ex, Ey, G)})
        n_col = int(round(x_end / d)) + 1
        lat = ply_lattice.build(0.0, n_col, 0.0, [bb.rows], [0.0], d, mat)
        lat.intra_law.strength_scale[:] = strength_scale(lat.x, lat.intra_pairs, d, c["seed"], c["strength_scatter"])
        nc = lat.n
        half = (lat.column == 0) | ((lat.column == n_col - 1) & tied)
        both = half[lat.intra_pairs].all(axis=1)
        l = lat.x[lat.intra_pairs[:, 1]] - lat.x[lat.intra_pairs[:, 0]]
        vol_c = d**2 * t * np.where(half, 0.5, 1.0)
        col = np.arange(n_col)  # sheet particle c under column c
        xs = np.column_stack([col * d, np.full(n_col, -ts / 2), np.zeros(n_col)])
        half_s = (col == 0) | ((col == n_col - 1) & tied)
        vol_s = ts * d * t * np.where(half_s, 0.5, 1.0)
        x = np.vstack([lat.x, xs])
        volume = np.concatenate([vol_c, vol_s])
        self.body = LawBonds(lat.intra_pairs, x, l, np.where(both, 0.5, 1.0) * d * t, lat.intra_law,
                             volume=volume, label="concrete")
        sheet_pairs = nc + np.column_stack([col[:-1], col[1:]])
        m = bb.sheet
        sheet_law = PlyBondLaw(np.full(n_col - 1, m["E11"] / d), (m["Gf_fibre"], m["Gf_matrix"]),
                               bb.sheet_strengths(), np.eye(3))
        self.sheet = LawBonds(sheet_pairs, x, np.tile([1.0, 0, 0], (n_col - 1, 1)), ts * t, sheet_law,
                              volume=volume, label="sheet")
        # adhesive: sheet particle c to the body's bottom particle of column c, the half cells of
        # both in series (the lattice's vertical bonds start at the bottom row's centres)
        bottom = np.flatnonzero(lat.row == 0)[np.argsort(lat.column[lat.row == 0])]
        bond_pairs = np.column_stack([nc + col, bottom])
        E2 = ply_lattice.slice_moduli(materials.plane_stress(bb.sheet_C()))[1]
        K = 1.0 / (0.5 * d / Ey + 0.5 * ts / E2)
        along = np.column_stack([np.where(col > 0, col - 1, -1), np.where(col < n_col - 1, col + 1, -1)])
        self.bond = LawBonds(bond_pairs, x, np.tile([0.0, 1.0, 0.0], (n_col, 1)), np.where(half_s, 0.5, 1.0) * d * t,
                             bb.adhesive_law(K), friction=bb.adhesive["friction"], label="adhesive", along=along)
        self.bond_whole = 2 * np.where(half_s, 0.5, 1.0) * d  # the beam's length per bond, both halves
        mass = np.concatenate([c["rho"] * vol_c, m["rho"] * vol_s])
        radius = np.full(nc + n_col, d / 2)
        pairs = np.vstack([lat.intra_pairs, sheet_pairs, bond_pairs])
        k_ph = 1e-9 * float(np.max(lat.intra_law.K)) * d * t  # placeholder bonds: the laws act through LawBonds
        self.lat, self.x, self.sheet_ids = lat, x, nc + col
        self.column = np.concatenate([lat.column, col])
        self.part = np.concatenate([np.zeros(nc), np.ones(n_col)])
        self.width_index = None
        groups = {"interface": np.flatnonzero(self.column == n_col - 1)} if tied else {}
        self.scene = DemScene(x, radius, mass / (4 / 3 * np.pi * radius**3), pairs, kn=np.full(len(pairs), k_ph),
                              ks=np.zeros(len(pairs)), plane=True, young=float(np.max(lat.intra_law.K)) * d,
                              groups=groups, placeholder_bonds=True)
        self.models = (self.body, self.sheet, self.bond)
        self.d = d

    def load(self, a: float, curve, width_share: float) -> ParticleLoad:
        """The load on the top row's particles under the patch (half of it in the half model),
        each particle taking the patch length its cell covers."""
        lat, d = self.lat, self.d
        top = np.flatnonzero(lat.row == lat.row.max())
        xc = lat.x[top, 0]
        cover = np.clip(np.minimum(xc + d / 2, a) - np.maximum(xc - d / 2, 0.0), 0.0, None)
        top, cover = top[cover > 0], cover[cover > 0]
        share = np.zeros((len(top), 3))
        share[:, 1] = -0.5 * width_share * cover / cover.sum()
        return ParticleLoad(top, share, curve)


class _Zone3:
    """The zone on [0, x_end] x [0, W / 2]: the body's block (rows above z = 0), a sheet
    particle at z = -t_sheet / 2 under each column, their laws, the engine scene."""

    def __init__(self, bb: BondedBeam, p: dict, x_end: float, tied: bool):
        d, ts = bb.d, bb.ts
        M, N = int(round(0.5 * p["geometry.width"] / d)) + 1, int(round(x_end / d)) + 1
        c = bb.body
        E, nu = c["E"], c["nu"]
        G = E / (2 * (1 + nu))
        mat = ply_lattice.PlyMaterial(E, E, G, G, c["rho"], bb.body_strengths(), c["Gf"], c["Gf"])
        half = [(0, 0), (1, 0), (1, M - 1)] + ([(0, N - 1)] if tied else [])
        blk = ply_block.build((0.0, 0.0, 0.0), (N, M), [bb.rows], [0.0], d, mat, half_planes=half)
        blk.intra_law.strength_scale[:] = strength_scale(blk.x, blk.intra_pairs, d, c["seed"], c["strength_scatter"])
        nc = blk.n
        I, J = (a.ravel() for a in np.meshgrid(np.arange(N), np.arange(M), indexing="ij"))
        cut = np.ones((I.size, 2))
        cut[(I == 0) | ((I == N - 1) & tied), 0] = 0.5
        cut[(J == 0) | (J == M - 1), 1] = 0.5
        xs = np.column_stack([I * d, J * d, np.full(I.size, -ts / 2)])
        vol_s = ts * d**2 * cut.prod(axis=1)
        x = np.vstack([blk.x, xs])
        volume = np.concatenate([blk.volume, vol_s])
        l = x[blk.intra_pairs[:, 1]] - x[blk.intra_pairs[:, 0]]
        self.d = d
        self.body = LawBonds(blk.intra_pairs, x, l, blk.intra_area, blk.intra_law, volume=volume, label="concrete")
        self.sheet = _membrane(bb, I, J, cut, nc, x, volume)
        # adhesive: the sheet particle under each column to the column's bottom body particle
        bottom = np.flatnonzero(blk.index[:, 2] == 0)
        bottom = bottom[np.lexsort((blk.index[bottom, 1], blk.index[bottom, 0]))]  # (i, j) order, as the sheet
        bond_pairs = np.column_stack([nc + np.arange(I.size), bottom])
        K = 1.0 / (0.5 * d / E + 0.5 * ts / bb.sheet["E22"])
        k = np.arange(I.size)
        along = np.column_stack([np.where(I > 0, k - M, -1), np.where(I < N - 1, k + M, -1),
                                 np.where(J > 0, k - 1, -1), np.where(J < M - 1, k + 1, -1)])
        area = d**2 * cut.prod(axis=1)
        self.bond = LawBonds(bond_pairs, x, np.tile([0.0, 0.0, 1.0], (I.size, 1)), area, bb.adhesive_law(K),
                             friction=bb.adhesive["friction"], label="adhesive", along=along)
        self.bond_whole = 4 * area / p["geometry.width"]  # lengths along the beam: areas (whole) over the width
        mass = np.concatenate([c["rho"] * blk.volume, bb.sheet["rho"] * vol_s])
        radius = np.full(len(x), d / 2)
        pairs = np.vstack([blk.intra_pairs, self.sheet.pairs, bond_pairs])
        k_ph = 1e-9 * float(np.max(blk.intra_law.K)) * d**2
        self.block, self.x, self.sheet_ids = blk, x, nc + k
        self.column = np.concatenate([blk.index[:, 0], I])
        self.width_index = np.concatenate([blk.index[:, 1], J])
        self.part = np.concatenate([np.zeros(nc), np.ones(I.size)])
        groups = {"interface": np.flatnonzero(self.column == N - 1)} if tied else {}
        self.scene = DemScene(x, radius, mass / (4 / 3 * np.pi * radius**3), pairs, kn=np.full(len(pairs), k_ph),
                              ks=np.zeros(len(pairs)), young=float(np.max(blk.intra_law.K)) * d, groups=groups,
                              placeholder_bonds=True)
        self.models = (self.body, self.sheet, self.bond)

    def load(self, a: float, curve, width_share: float) -> ParticleLoad:
        """The load on the top particles under the patch (a quarter of it in the quarter model),
        each particle taking the patch area its cell covers."""
        blk, d = self.block, self.d
        top = np.flatnonzero(blk.index[:, 2] == blk.index[:, 2].max())
        xc = blk.x[top, 0]
        cover = np.clip(np.minimum(xc + d / 2, a) - np.maximum(xc - d / 2, 0.0), 0.0, None)
        jj = blk.index[top, 1]
        cover = cover * d * np.where((jj == 0) | (jj == jj.max()), 0.5, 1.0)  # x its share of the width
        top, cover = top[cover > 0], cover[cover > 0]
        share = np.zeros((len(top), 3))
        share[:, 2] = -0.25 * cover / cover.sum()
        return ParticleLoad(top, share, curve)


def _membrane(bb: BondedBeam, I, J, cut, nc: int, x: np.ndarray, volume: np.ndarray) -> LawBonds:
    """The sheet as a membrane: axial bonds along x (fibres) and y, two diagonals per cell
    (G12), the square-lattice closed form of ply_lattice with the sheet's thickness as the
    cell's; a bond lying in a half plane (both ends on it) carries half the area."""
    d, ts, m = bb.d, bb.ts, bb.sheet
    kx, ky, k2 = ply_lattice.lattice_stiffness(m["E11"], m["E22"], m["G12"], ts)
    M = J.max() + 1
    flat = lambda i, j: i * M + j
    pairs, k, gf = [], [], []
    Gf = np.array([m["Gf_fibre"], m["Gf_matrix"]])  # cracks normal to x (across the fibres) and to y
    for di, dj, kk, share in ((1, 0, kx, (kx / (kx + k2), 0.0)), (0, 1, ky, (0.0, ky / (ky + k2))),
                              (1, 1, k2, (0.5 * k2 / (kx + k2), 0.5 * k2 / (ky + k2))),
                              (1, -1, k2, (0.5 * k2 / (kx + k2), 0.5 * k2 / (ky + k2)))):
        ok = (I + di <= I.max()) & (J + dj >= 0) & (J + dj <= J.max())
        a = np.flatnonzero(ok)
        pairs.append(np.column_stack([a, flat(I[a] + di, J[a] + dj)]))
        k.append(np.full(a.size, kk))
        gf.append(np.tile(np.maximum(np.array(share), 1e-3) * Gf, (a.size, 1)))
    pairs = np.vstack(pairs)
    k = np.concatenate(k)
    same_i = I[pairs[:, 0]] == I[pairs[:, 1]]
    same_j = J[pairs[:, 0]] == J[pairs[:, 1]]
    f = np.where(same_i, cut[pairs[:, 0], 0], 1.0) * np.where(same_j, cut[pairs[:, 0], 1], 1.0)
    law = PlyBondLaw(k / (d * ts), np.vstack(gf), bb.sheet_strengths(), np.eye(3))
    pairs = nc + pairs
    return LawBonds(pairs, x, x[pairs[:, 1]] - x[pairs[:, 0]], d * ts * f, law, volume=volume, label="sheet")
