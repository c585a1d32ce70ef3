"""ply_fracture: a ply strip pulled to failure, Hoffman initiation and energy regularisation.

A slice of one ply (square lattice of spacing d, PlyBondLaw on every bond, dem_region/
ply_lattice.py) is held at its left column and pulled at its right column along x (roller
ends: only x is prescribed, so the strip contracts freely and the stress is uniaxial); the
strip's middle cell column is 2 % weaker (an imperfection, so the crack localises there).
Angle 0 pulls along the fibres (crack across them, Xt, Gf_fibre); angle 90 pulls across
them (the 90 ply of a beam slice: matrix crack, Yt, Gf_matrix).

Checks, from the run's own parameters: the peak stress (force / (height x t)) equals the
uniaxial Hoffman strength of that direction reduced by the imperfection, times the share of
the section the lattice carries (its free top and bottom rows miss half their diagonals:
effective_rows), within 5 %;
the energy the bonds dissipate equals Gf x crack area (height x t) within 5 %, for any
particle size (the regularisation; the test suite runs two sizes). The strip is shorter than
2 E Gf / X^2 (2.2 mm across the fibres of the default ply, 5.5 mm along them): longer strips
store more elastic energy than one crack dissipates, snap, and the rebound breaks a second
section (measured: 10 mm, 2 sections, 2.8 x Gf x area).
"""
from __future__ import annotations

import numpy as np

from dem_region import ply_lattice
from physics.law_bonds import LawBonds
from dem_region.scene import DemScene
from physics.failure import HoffmanStrengths

from ..checks import check
from ..params import density, modulus, Param, particle_size, positive
from ..participants.dem import dem_only

NAME = "ply_fracture"
DESCRIPTION = "DEM: ply strip to failure, Hoffman strength and Gf x area, size independent"
MODES = ("dem",)
WEAK = 0.98

# T300/epoxy-like ply (Table 1 moduli of the seed; strengths and fracture energies of the
# order Camanho et al. 2007 and Pinho et al. 2006 report for carbon/epoxy)
PLY: dict[str, Param] = {
    "material.E11": modulus(156e9, "ply modulus along the fibres"),
    "material.E22": modulus(9.09e9, "transverse ply modulus"),
    "material.G12": modulus(4.5e9, "in-plane shear modulus"),
    "material.G23": modulus(3.25e9, "transverse shear modulus (E22 / (2 (1 + nu23)), nu23 = 0.4)"),
    "material.rho": density(1540.0, "ply density"),
    "strength.Xt": positive(1.5e9, "tensile strength along the fibres", "Pa"),
    "strength.Xc": positive(1.2e9, "compressive strength along the fibres", "Pa"),
    "strength.Yt": positive(50e6, "transverse tensile strength", "Pa"),
    "strength.Yc": positive(200e6, "transverse compressive strength", "Pa"),
    "strength.S12": positive(75e6, "in-plane shear strength", "Pa"),
    "strength.S23": positive(60e6, "transverse shear strength", "Pa"),
    "fracture.Gf_fibre": Param(40e3, "fracture energy of a crack across the fibres", unit="J/m^2", low=0.0,
                               open_low=True),
    "fracture.Gf_matrix": Param(300.0, "fracture energy of a matrix crack (along the fibres)", unit="J/m^2",
                                low=0.0, open_low=True),
}

PARAMETERS = {
    **PLY,
    "ply.angle": Param(90.0, "0: pull along the fibres; 90: fibres out of the slice's plane", choices=None,
                       low=0.0, high=90.0),
    "zone.particle_size": particle_size(0.125e-3, "particle size d (the lattice spacing)"),
    "geometry.length": positive(1.5e-3, "strip length (below 2 E Gf / X^2, so that the strip's elastic energy "
                                "cannot break a second section)", "m"),
    "geometry.height": positive(2e-3, "strip height", "m"),
    "load.duration_transits": Param(60.0, "time to the strength in wave transits of the strip", low=5.0),
}


def ply_material(p: dict) -> ply_lattice.PlyMaterial:
    Yt, Yc, S23 = p["strength.Yt"], p["strength.Yc"], p["strength.S23"]
    k = HoffmanStrengths(Xt=p["strength.Xt"], Xc=p["strength.Xc"], Yt=Yt, Yc=Yc, Zt=Yt, Zc=Yc, S23=S23,
                         S13=p["strength.S12"], S12=p["strength.S12"])
    return ply_lattice.PlyMaterial(p["material.E11"], p["material.E22"], p["material.G12"], p["material.G23"],
                                   p["material.rho"], k, p["fracture.Gf_fibre"], p["fracture.Gf_matrix"])


def law_bonds_of(lat: ply_lattice.PlyLattice) -> LawBonds:
    """The lattice's intralaminar bonds as coupling-layer law bonds (area d t each)."""
    l = lat.x[lat.intra_pairs[:, 1]] - lat.x[lat.intra_pairs[:, 0]]
    return LawBonds(lat.intra_pairs, lat.x, l, lat.d**2, lat.intra_law, volume=lat.cell_volume(), label="intralaminar")


def engine_scene(lat: ply_lattice.PlyLattice, extra_pairs=(), **kw) -> DemScene:
    """The engine's view: particles plus placeholder bonds on every law pair."""
    pairs = np.vstack([lat.intra_pairs, lat.inter_pairs, *(np.reshape(e, (-1, 2)) for e in extra_pairs)])
    k = 1e-9 * float(np.max(lat.intra_law.K)) * lat.d**2
    return DemScene(lat.x, lat.radius, lat.density, pairs, kn=k, ks=0.0, plane=True,
                    young=float(np.max(lat.intra_law.K)) * lat.d, placeholder_bonds=True, **kw)


def strength(p: dict) -> tuple[float, float]:
    """(uniaxial strength along x of the slice, fracture energy of the crack across x)."""
    if p["ply.angle"] == 0:
        return p["strength.Xt"], p["fracture.Gf_fibre"]
    return p["strength.Yt"], p["fracture.Gf_matrix"]


def build(p: dict, mode: str, dem: str):
    from ..params import CaseError
    if p["ply.angle"] not in (0.0, 90.0):
        raise CaseError(f"ply.angle = {p['ply.angle']:g}: allowed 0 or 90 (a beam slice's plies)")
    d = p["zone.particle_size"]
    nx, ny = int(round(p["geometry.length"] / d)) + 1, max(2, int(round(p["geometry.height"] / d)))
    mat = ply_material(p)
    lat = ply_lattice.build(0.0, nx, 0.0, [ny], [p["ply.angle"]], d, mat)
    bonds = law_bonds_of(lat)
    mid = (nx - 1) // 2
    c = lat.column[lat.intra_pairs]
    crossing = (np.minimum(c[:, 0], c[:, 1]) == mid) & (np.maximum(c[:, 0], c[:, 1]) == mid + 1)
    lat.intra_law.strength_scale[crossing] = WEAK
    scene = engine_scene(lat)
    left, right = np.flatnonzero(lat.column == 0), np.flatnonzero(lat.column == nx - 1)
    E_x = mat.in_plane(p["ply.angle"])[0]
    X, _ = strength(p)
    L = (nx - 1) * d
    transit = L / np.sqrt(E_x / p["material.rho"])
    t_peak = p["load.duration_transits"] * transit
    v = WEAK * X / E_x * L / t_peak
    t_end = t_peak * (1 + 1.5 * (2 * strength(p)[1] / X) / (WEAK * X / E_x * L))  # and the softening, 1.5 x
    n_left = len(left)

    def velocity_field(t):
        out = np.zeros((n_left + len(right), 3))
        out[n_left:, 0] = v * min(1.0, t / (0.1 * t_peak))
        return out

    sim, backend, _ = dem_only(p, scene, dem, t_end, drive=(np.concatenate([left, right]), velocity_field),
                               models=(bonds,), drive_dofs="x")  # roller ends: free lateral contraction
    area = ny * d * d
    sim.probes.update({
        "stress": lambda: -float(bonds.force_on(right)[0] / area),  # the bonds pull the end back
        "extension": lambda: float(backend.positions_of(right[:1])[0, 0] - lat.x[right[0], 0]),
        "bond_dissipated": lambda: bonds.dissipated_energy(),
        "failed_bonds": lambda: float(bonds.failed().sum()),
    })
    sim.counts["law_bonds"] = len(bonds.pairs)
    return sim


def effective_rows(p: dict) -> float:
    """Rows' worth of C_xx the strip carries: the free top and bottom rows miss half of their
    cells' diagonals, so a strip of ny rows carries ny - k_2 / (k_x + k_2) (for force and for
    the fracture energy, which is shared between the families in proportion to stiffness)."""
    ny = max(2, int(round(p["geometry.height"] / (p["zone.particle_size"]))))
    kx, _, k2 = ply_lattice.lattice_stiffness(*ply_material(p).in_plane(p["ply.angle"]), 1.0)
    return ny - k2 / (kx + k2)


def evaluate(p: dict, h: dict, mode: str):
    X, Gf = strength(p)
    d = p["zone.particle_size"]
    ny = max(2, int(round(p["geometry.height"] / d)))
    area = ny * d * d
    eff = effective_rows(p) / ny
    qoi = {"peak_stress": float(np.max(h["stress"])), "dissipated": float(h["bond_dissipated"][-1]),
           "failed_bonds": float(h["failed_bonds"][-1])}
    qoi["dissipated_energy_ratio"] = qoi["dissipated"] / (Gf * area * eff)
    src = "Hoffman criterion, uniaxial (strength of the weakened column), free-edge rows of the lattice"
    return qoi, {
        "peak_stress": check(qoi["peak_stress"], WEAK * X * eff, 0.05, src),
        "dissipated_energy_ratio": check(qoi["dissipated_energy_ratio"], 1.0, 0.05, "energy: Gf x crack area"),
    }


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5, 3.5))
    ax.plot(1e6 * np.asarray(h["extension"]), 1e-6 * np.asarray(h["stress"]))
    ax.axhline(1e-6 * WEAK * strength(p)[0], color="k", ls=":", label="Hoffman strength (weak column)")
    ax.set(xlabel="extension (um)", ylabel="stress (MPa)", title=f"ply {p['ply.angle']:g} strip")
    ax.legend()
    fig.tight_layout()
    fig.savefig(plots_dir / "stress_extension.png", dpi=120)
    plt.close(fig)
