"""cfrp_beam_impact_3d: the seed paper's example 5.4 in 3D, the variant of cfrp_beam_impact.

The same 3 x 3 x 30 in concrete beam, three-ply CFRP sheet, adhesive, supports and measured
drop load as cfrp_beam_impact (its docstring has the data, the choices and why), in 3D: a
quarter of the beam (symmetry planes at mid-span x = 0 and at mid-width y = 0), free side
faces at y = W / 2, the depth along z, the sheet under z = 0.

Modes (the same beam, supports and load):
- coupled: DEM zone |x| < zone.half_width over the whole depth and width: the concrete as a
  3D lattice (dem_region/ply_block.py, isotropic: E and G = E / (2 (1 + nu)) exact, the
  lattice's Poisson ratio its Cauchy value) with PlyBondLaw (Hoffman with ft, fc and
  sqrt(ft fc / 3), Gf-regularised, 1 +- scatter on the strengths); the sheet as a layer of
  particles under the bottom row, a membrane lattice (axial bonds along the fibres and across,
  diagonals for G12); Hashin adhesive bonds between them with rotation-free slip along x
  and y; the drop load on the top particles under the patch; Hex8 elsewhere with the sheet
  smeared into the bottom element layer; kinematic tie at x = zone.half_width;
- fem: all Hex8, no fracture (the no-fracture curve of the checks);
- dem: all particles.

qoi and checks as cfrp_beam_impact; lengths along the beam (debonded length) are areas over
the width: mean lengths.
"""
from __future__ import annotations

import numpy as np

from dem_region import ply_block, ply_lattice
from physics.law_bonds import LawBonds
from physics.laws import HashinCohesiveLaw, PlyBondLaw
from dem_region.particle_load import ParticleLoad
from dem_region.scene import DemScene
from fem_region import loads, materials, mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from physics.failure import HoffmanStrengths

from ..params import CaseError, Param
from . import cfrp_beam_impact as cfrp
from .cfrp_beam_impact import T_END, drop_load, geometry_check, rows
from ..participants.dem import hold_symmetry_planes
from ..participants.fem import fem_only, make_region
from ..participants.coupled import coupled_simulation
from ..participants.dem import dem_only

NAME = "cfrp_beam_impact_3d"
DESCRIPTION = "seed 5.4 in 3D: a quarter of the concrete beam with its CFRP sheet, drop load"
MODES = ("coupled", "fem", "dem")

PARAMETERS = {
    **cfrp.PARAMETERS,
    "mesh.elements_width": Param(4, "Hex8 elements across the modelled half width", kind="int", low=1, high=200),
}


def concrete_C(p: dict) -> np.ndarray:
    return materials.isotropic(p["concrete.E"], p["concrete.nu"])


def sheet_C(p: dict) -> np.ndarray:
    """(6, 6) Pa of the sheet, fibres along x (its transverse constants: cfrp_beam_impact)."""
    E1, E2, G, nu = p["cfrp.E1"], p["cfrp.E2"], p["cfrp.G12"], p["cfrp.nu12"]
    return materials.orthotropic(E1, E2, E2, nu, nu, 0.4, G, G, E2 / 2.8)


def columns(p: dict) -> int:
    """Particle columns across the modelled half width."""
    _, d = rows(p)
    m = 0.5 * p["geometry.width"] / d
    if abs(m - round(m)) > 1e-6 or round(m) < 1:
        raise CaseError(f"zone.particle_size = {d:g}: half the width {p['geometry.width']:g} m must hold a whole "
                        "number of particle spacings")
    return int(round(m)) + 1


# -- particles ----------------------------------------------------------------------------------
class Zone:
    """The particle zone on [0, x_end] x [0, W / 2]: concrete block (rows above z = 0), a
    sheet particle at z = -t_sheet / 2 under each column, their laws, the engine scene."""

    def __init__(self, p: dict, x_end: float, tied: bool):
        n_rows, d = rows(p)
        M, N = columns(p), int(round(x_end / d)) + 1
        ts = p["cfrp.thickness"]
        self.d, self.n_col = d, N
        E, nu = p["concrete.E"], p["concrete.nu"]
        G = E / (2 * (1 + nu))
        ft, fc = p["concrete.ft"], p["concrete.fc"]
        S = np.sqrt(ft * fc / 3)  # Hoffman's criterion for an isotropic material (Hoffman 1967)
        k = HoffmanStrengths(Xt=ft, Xc=fc, Yt=ft, Yc=fc, Zt=ft, Zc=fc, S23=S, S13=S, S12=S)
        mat = ply_lattice.PlyMaterial(E, E, G, G, p["concrete.rho"], k, p["concrete.Gf"], p["concrete.Gf"])
        half = [(0, 0), (1, 0), (1, M - 1)] + ([(0, N - 1)] if tied else [])
        blk = ply_block.build((0.0, 0.0, 0.0), (N, M), [n_rows], [0.0], d, mat, half_planes=half)
        rng = np.random.default_rng(p["concrete.seed"])
        blk.intra_law.strength_scale[:] = 1 + p["concrete.strength_scatter"] * rng.uniform(-1, 1, len(blk.intra_pairs))
        nc = blk.n
        # the sheet: one particle under each column, a membrane lattice in its plane
        I, J = (a.ravel() for a in np.meshgrid(np.arange(N), np.arange(M), indexing="ij"))
        cut = np.ones((I.size, 2))
        cut[(I == 0) | ((I == N - 1) & tied), 0] = 0.5
        cut[(J == 0) | (J == M - 1), 1] = 0.5
        xs = np.column_stack([I * d, J * d, np.full(I.size, -ts / 2)])
        vol_s = ts * d**2 * cut.prod(axis=1)
        x = np.vstack([blk.x, xs])
        volume = np.concatenate([blk.volume, vol_s])
        l = x[blk.intra_pairs[:, 1]] - x[blk.intra_pairs[:, 0]]
        self.concrete = LawBonds(blk.intra_pairs, x, l, blk.intra_area, blk.intra_law, volume=volume,
                                 label="concrete")
        self.sheet = self._sheet(p, I, J, cut, nc, x, volume)
        # adhesive: sheet particle under each column to the column's bottom concrete particle
        bottom = np.flatnonzero(blk.index[:, 2] == 0)
        bottom = bottom[np.lexsort((blk.index[bottom, 1], blk.index[bottom, 0]))]  # (i, j) order, as the sheet
        bond_pairs = np.column_stack([nc + np.arange(I.size), bottom])
        K = 1.0 / (0.5 * d / E + 0.5 * ts / p["cfrp.E2"])
        law = HashinCohesiveLaw(K=K, Z0=p["bond.Z0"], R0=p["bond.R0"], GIc=p["bond.GIc"], GIIc=p["bond.GIIc"])
        m = np.arange(I.size)
        along = np.column_stack([np.where(I > 0, m - M, -1), np.where(I < N - 1, m + M, -1),
                                 np.where(J > 0, m - 1, -1), np.where(J < M - 1, m + 1, -1)])
        area = d**2 * cut.prod(axis=1)
        self.bond = LawBonds(bond_pairs, x, np.tile([0.0, 0.0, 1.0], (I.size, 1)), area, law,
                             friction=p["bond.friction"], label="adhesive", along=along)
        self.bond_area = area
        mass = np.concatenate([p["concrete.rho"] * blk.volume, p["cfrp.rho"] * vol_s])
        radius = np.full(len(x), d / 2)  # the sheet's spheres get the lattice's radius (cfrp_beam_impact)
        pairs = np.vstack([blk.intra_pairs, self.sheet.pairs, bond_pairs])
        k_ph = 1e-9 * float(np.max(blk.intra_law.K)) * d**2
        self.block, self.x, self.sheet_ids = blk, x, nc + m
        self.column = np.concatenate([blk.index[:, 0], I])
        self.width_index = np.concatenate([blk.index[:, 1], J])
        groups = {"interface": np.flatnonzero(self.column == N - 1)} if tied else {}
        self.scene = DemScene(x, radius, mass / (4 / 3 * np.pi * radius**3), pairs, kn=np.full(len(pairs), k_ph),
                              ks=np.zeros(len(pairs)), young=float(np.max(blk.intra_law.K)) * d, groups=groups,
                              placeholder_bonds=True)
        self.models = (self.concrete, self.sheet, self.bond)

    def _sheet(self, p, I, J, cut, nc, x, volume) -> LawBonds:
        """Axial bonds along x (fibres) and y, two diagonals per cell (G12): the square-lattice
        closed form of ply_lattice with the sheet's thickness as the cell's."""
        d, ts = self.d, p["cfrp.thickness"]
        kx, ky, k2 = ply_lattice.lattice_stiffness(p["cfrp.E1"], p["cfrp.E2"], p["cfrp.G12"], ts)
        M = J.max() + 1
        flat = lambda i, j: i * M + j
        pairs, k, gf = [], [], []
        Gf = p["cfrp.Gf"]
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
        # a bond lying in a half plane (both ends on it) carries half the area
        same_i = I[pairs[:, 0]] == I[pairs[:, 1]]
        same_j = J[pairs[:, 0]] == J[pairs[:, 1]]
        f = np.where(same_i, cut[pairs[:, 0], 0], 1.0) * np.where(same_j, cut[pairs[:, 0], 1], 1.0)
        area = d * ts * f
        ks = HoffmanStrengths(Xt=p["cfrp.T0"], Xc=p["cfrp.T0"], Yt=p["cfrp.sigma_t"], Yc=4 * p["cfrp.sigma_t"],
                              Zt=p["cfrp.sigma_t"], Zc=4 * p["cfrp.sigma_t"], S23=2 * p["cfrp.sigma_t"],
                              S13=2 * p["cfrp.sigma_t"], S12=2 * p["cfrp.sigma_t"])
        law = PlyBondLaw(k / (d * ts), np.vstack(gf), ks, np.eye(3))
        pairs = nc + pairs
        return LawBonds(pairs, x, x[pairs[:, 1]] - x[pairs[:, 0]], area, law, volume=volume, label="sheet")

    def load(self, p: dict) -> ParticleLoad:
        """The drop load on the top particles under the patch (a quarter of it in the quarter
        model), each particle taking the patch area its cell covers."""
        blk, d = self.block, self.d
        a = p["load.patch_width"] / 2
        top = np.flatnonzero(blk.index[:, 2] == blk.index[:, 2].max())
        xc = blk.x[top, 0]
        cover = np.clip(np.minimum(xc + d / 2, a) - np.maximum(xc - d / 2, 0.0), 0.0, None)
        jj = blk.index[top, 1]
        cover = cover * d * np.where((jj == 0) | (jj == jj.max()), 0.5, 1.0)  # x its share of the width
        top, cover = top[cover > 0], cover[cover > 0]
        share = np.zeros((len(top), 3))
        share[:, 2] = -0.25 * cover / cover.sum()
        return ParticleLoad(top, share, drop_load(p))


# -- FEM ----------------------------------------------------------------------------------------
def fem_region(p: dict, x0: float):
    """Hex8 quarter beam on [x0, length / 2] x [0, W / 2] x [-t_sheet, depth]: element layers
    of d, the first (the sheet and the bottom d of concrete) smeared; columns as cfrp_beam_impact."""
    n, d = rows(p)
    ts, L, s = p["cfrp.thickness"], p["geometry.length"] / 2, p["geometry.span"] / 2
    xs = cfrp._lines(x0, s, d, p["mesh.growth"], p["mesh.max_size"])
    xs += list(np.linspace(s, L, max(2, int(np.ceil((L - s) / p["mesh.max_size"]))) + 1)[1:])
    ys = np.linspace(0.0, 0.5 * p["geometry.width"], p["mesh.elements_width"] + 1)
    zs = np.concatenate([[-ts], d * np.arange(1, n + 1)])
    m = mesh.box(np.array(xs), ys, zs, "hex8")
    bottom = m.p[2, m.t].mean(axis=0) < d / 2
    Cc, Cs = concrete_C(p), sheet_C(p)
    C = np.where(bottom[:, None, None], (d * Cc + ts * Cs) / (d + ts), Cc)
    rho = np.where(bottom, (d * p["concrete.rho"] + ts * p["cfrp.rho"]) / (d + ts), p["concrete.rho"])
    return make_region(m, p, C, rho, 1.0)


def supports(region, p: dict, symmetry_x: bool) -> list[PrescribedMotion]:
    """The support line under the sheet at x = span / 2 (z held), symmetry at mid-width (and
    at mid-span when the FEM reaches it)."""
    X = region.X
    s = p["geometry.span"] / 2
    xs = np.unique(X[:, 0])
    line = np.flatnonzero((np.abs(X[:, 0] - xs[np.argmin(np.abs(xs - s))]) < 1e-12) & (X[:, 2] < X[:, 2].min() + 1e-12))
    out = [PrescribedMotion(3 * line + 2), PrescribedMotion(3 * np.flatnonzero(X[:, 1] < 1e-12) + 1)]
    if symmetry_x:
        out.append(PrescribedMotion(3 * np.flatnonzero(X[:, 0] < 1e-12)))
    return out


def build(p: dict, mode: str, dem: str):
    geometry_check(p)
    if mode == "fem":
        return _build_fem(p)
    n_rows, d = rows(p)
    L, s = p["geometry.length"] / 2, p["geometry.span"] / 2
    w = L if mode == "dem" else p["zone.half_width"]
    if mode == "coupled" and not 4 * d <= w <= s - 4 * d:
        raise CaseError(f"zone.half_width = {w:g}: allowed from four particle sizes ({4 * d:g} m) to four short of "
                        f"the support ({s - 4 * d:g} m)")
    w = d * round(w / d)
    zone = Zone(p, w, tied=(mode == "coupled"))
    load = zone.load(p)
    models = zone.models + (load,)
    if mode == "dem":
        sim, backend, _ = dem_only(p, zone.scene, dem, T_END, models=models)
        # the support holds the column line through the adhesive (sheet and bottom concrete)
        c = zone.column[zone.sheet_ids[np.argmin(np.abs(zone.x[zone.sheet_ids, 0] - s))]]
        support = np.flatnonzero((zone.column == c) & (zone.x[:, 2] < zone.d))
        backend.prescribe(support, "z")
        backend.set_velocities(support, np.zeros((len(support), 3)))
        fem_count, held = 0, support
    else:
        def make(extra_mass):
            region = fem_region(p, w)
            return ExplicitDynamics(region, supports=supports(region, p, symmetry_x=False), extra_mass=extra_mass)
        sim, clock = coupled_simulation(p, make, zone.scene, dem, T_END, models=models)
        backend, fem_count = clock.dem, clock.fem.region.n_elements
        held = zone.scene.groups["interface"]
    i, j = zone.column, zone.width_index
    hold_symmetry_planes(backend, i, j, held)
    mid = zone.sheet_ids[0]
    sim.probes.update({
        "midspan_displacement": lambda: -float(backend.positions_of(np.array([mid]))[0, 2] - zone.x[mid, 2]),
        "load": lambda: float(-4 * load.force()[2]),
        "model_size": lambda: float(fem_count + zone.scene.n),
        # lengths along the beam: the bonds' areas (whole beam) over the width
        **cfrp.damage_probes(p, zone, 4 * zone.bond_area / p["geometry.width"], up=2),
    })
    sim.counts.update({"law_bonds": sum(len(b.pairs) for b in zone.models)})
    t_end = p["clock.t_end"] or T_END
    for t_snap in sorted({0.47e-3, 0.75e-3, t_end} - {t for t in (0.47e-3, 0.75e-3) if t > t_end}):
        sim.snapshots[f"damage_{round(t_snap * 1e6)}us"] = (t_snap, lambda: {
            "x": backend.positions(), "width_index": j.astype(float), "concrete_damage": zone.concrete.softened(),
            "bond_damage": zone.bond.softened(), "concrete_pairs": zone.concrete.pairs.astype(float),
            "bond_pairs": zone.bond.pairs.astype(float)})
    return sim


def _build_fem(p: dict):
    region = fem_region(p, 0.0)
    X, H = region.X, p["geometry.depth"]
    a = p["load.patch_width"] / 2
    curve = drop_load(p)
    load = loads.surface_traction(region, lambda x: (x[2] > H * (1 - 1e-9)) & (x[0] < a), [0.0, 0.0, -1.0], curve)
    load.amplitude = load.amplitude * (0.25 / -np.sum(load.amplitude))  # a quarter of the load, exactly
    dyn = ExplicitDynamics(region, supports=supports(region, p, symmetry_x=True), loads=[load])
    mid = np.flatnonzero((X[:, 0] < 1e-12) & (X[:, 1] < 1e-12))
    mid = mid[np.argmin(X[mid, 2])]
    return fem_only(dyn, p, T_END, cfrp.no_fracture_probes(dyn, mid, concrete_C(p)[0], curve))


def evaluate(p: dict, h: dict, mode: str):
    return cfrp.evaluate(p, h, mode, reference=lambda q: cfrp.no_fracture_history(q, build))


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    cfrp.plot(p, {k: v for k, v in h.items() if not k.startswith("damage_")}, qoi, plots_dir)
    for name in sorted({k.split(".")[0] for k in h if k.startswith("damage_") and "." in k}):
        _damage_picture(h, name, plots_dir)


def _damage_picture(h: dict, name: str, plots_dir):
    """x-z sections at mid-width and at the side face: concrete bonds (reds) and adhesive
    (blues) by the share of their softening travelled, deformed, mm."""
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    x = 1e3 * np.asarray(h[f"{name}.x"])
    j = np.asarray(h[f"{name}.width_index"]).astype(int)
    fig, axes = plt.subplots(2, 1, figsize=(12, 6))
    for ax, at, label in zip(axes, (0, j.max()), ("mid-width (symmetry plane)", "side face")):
        on = j == at
        ax.plot(x[on, 0], x[on, 2], ".", ms=1, color="0.75")
        for kind, cmap in (("concrete", plt.cm.Reds), ("bond", plt.cm.Blues)):
            pairs = np.asarray(h[f"{name}.{kind}_pairs"]).astype(int)
            dmg = np.asarray(h[f"{name}.{kind}_damage"])
            hit = (dmg > 0.05) & on[pairs].all(axis=1)
            if hit.any():
                ax.add_collection(LineCollection(x[pairs[hit]][:, :, [0, 2]], colors=cmap(0.3 + 0.7 * dmg[hit]),
                                                 linewidths=1.5))
        ax.set(xlabel="x (mm, from mid-span)", ylabel="z (mm)", title=f"{name.split('_')[1]}, {label}: concrete "
               "cracks (red), sheet debonding (blue)")
        ax.set_aspect("equal")
    fig.tight_layout()
    fig.savefig(plots_dir / f"{name}.png", dpi=120)
    plt.close(fig)
