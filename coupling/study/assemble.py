"""The assembler: a study's resolved parameters -> the FEM participant, the DEM participant and
the coupled assembly of the requested mode.

Modes of one body: ``fem``, the whole body as FEM (no damage, the cheap bound); ``dem``, the
whole body as particles (the expensive reference); ``coupled``, particles inside the zone and
FEM outside, tied at the zone's faces. Geometry shapes: ``beam``, a plane-strain slice of a
laminated beam along x, y through the thickness, half model about x = 0.

The particle zone is a ply lattice (dem_region.ply_lattice): one particle row per
``zone.plies_per_particle`` plies, the Hoffman intralaminar law on the bonds within a ply and
the laminate's interface law on the bonds across plies of different angle. Particles on a
symmetry plane or on the FEM's face stand for half a cell: half the mass, and their bonds
along that plane half the area.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dem_region import ply_lattice
from dem_region.particle_impactor import ParticleImpactor
from dem_region.scene import DemScene
from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from physics.failure import HoffmanStrengths
from physics.impactor import RigidImpactor
from physics.law_bonds import LawBonds

from ..params import CaseError
from ..participants.coupled import coupled_simulation
from ..participants.dem import dem_only
from ..participants.fem import fem_only, make_region
from .schema import section


@dataclass
class Laminate:
    """A laminate's runs of equal plies, bottom up, and its materials (Pa, kg/m^3, J/m^2)."""

    angles: list[float]  # degrees, one per run
    plies: list[int]  # plies per run
    ply_thickness: float  # m
    ply: dict  # the [materials.*] fields
    interface: dict  # the [interfaces.*] fields

    @property
    def thickness(self) -> float:
        return sum(self.plies) * self.ply_thickness

    def D(self, angle: float) -> np.ndarray:
        """(3, 3) plane-strain stiffness Pa of a ply at ``angle`` in the slice."""
        m = self.ply
        C = materials.orthotropic(m["E11"], m["E22"], m["E22"], m["nu12"], m["nu12"], m["nu23"], m["G12"], m["G12"],
                                  m["G23"])
        return materials.plane_strain(materials.rotate(C, materials.ply_axes(angle, 2)))

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
    lam: Laminate
    half_span: float
    t: float  # slice thickness (out of plane) = particle size, m
    width_factor: float
    lattice: ply_lattice.PlyLattice | None = None
    intra: LawBonds | None = None
    inter: LawBonds | None = None
    backend: object = None
    dyn: ExplicitDynamics | None = None
    fem_elements: int = 0
    end_held: bool = False  # the zone's last column is tied to the FEM or clamped
    impactors: dict = field(default_factory=dict)  # name -> ParticleImpactor (particles) or RigidImpactor (FEM)


def beam_of(p: dict, mode: str) -> Built:
    """The beam's laminate and slice, before its participants exist."""
    lam = laminate(p, p["geometry.laminate"])
    k = p["zone.plies_per_particle"]
    if any(n % k for n in lam.plies):
        raise CaseError(f"zone.plies_per_particle = {k}: must divide every ply run of the laminate ({lam.plies})")
    t = k * lam.ply_thickness
    return Built(p, mode, lam, 0.5 * p["geometry.span"], t, 2 * p["geometry.width"] / t)  # whole width, both halves


def particle_zone(p: dict, x_end: float, tied: bool, clamped: bool):
    """(lattice, engine scene, intralaminar LawBonds, interlaminar LawBonds) of a study's beam on
    [0, x_end] (benchmarks and kernel tests take the law families from here)."""
    return _particle_zone(beam_of(p, "dem"), x_end, tied, clamped)


def beam(study, p: dict, mode: str, dem: str):
    """(Simulation, Built) of a laminated beam slice under its impactors and supports."""
    built = beam_of(p, mode)
    t, L = built.t, built.half_span
    t_end = study.t_end
    if mode == "fem":
        return _fem_beam(study, p, built, t_end), built
    w = L if mode == "dem" else p["zone.half_width"]
    if mode == "coupled" and not 2 * t < w < 0.8 * L:
        raise CaseError(f"zone.half_width = {w:g}: allowed between two particle sizes ({2 * t:g} m) and 0.8 x "
                        "half the span")
    clamp = _support_fix(study, p) == "xy"
    lat, scene, intra, inter = _particle_zone(built, w, tied=(mode == "coupled"), clamped=(mode == "dem" and clamp))
    built.lattice, built.intra, built.inter = lat, intra, inter
    built.end_held = mode == "coupled" or clamp
    built.impactors = {name: _particle_impactor(p, name, built) for name in study.layout.names["impactors"]}
    models = (intra, inter, *built.impactors.values())
    axis = np.flatnonzero(lat.column == 0)
    if mode == "dem":
        sim, backend, _ = dem_only(p, scene, dem, t_end, models=models)
        if not clamp:  # simply supported: the bottom particle of the last column
            last = np.flatnonzero(lat.column == lat.column.max())
            corner = last[[np.argmin(lat.x[last, 1])]]
            backend.prescribe(corner, "y")
            backend.set_velocities(corner, np.zeros((1, 3)))
    else:
        def make(extra_mass):
            region = _fem_region(p, built, lat.x[:, 0].max())
            return ExplicitDynamics(region, supports=_fem_supports(study, p, region, L), extra_mass=extra_mass)
        sim, clock = coupled_simulation(p, make, scene, dem, t_end, models=models)
        backend, built.dyn = clock.dem, clock.fem
        built.fem_elements = clock.fem.region.n_elements
    built.backend = backend
    backend.prescribe(axis, "x")  # the symmetry plane
    backend.set_velocities(axis, np.zeros((len(axis), 3)))
    sim.counts.update({"law_bonds": len(intra.pairs) + len(inter.pairs)})
    return sim, built


def _support_fix(study, p: dict) -> str:
    names = list(study.layout.names["supports"])
    if len(names) != 1:
        raise CaseError(f"supports: a beam takes one [supports.NAME] table at its ends; given {len(names)}")
    return p[f"supports.{names[0]}.fix"]


def _fem_supports(study, p: dict, region, L: float) -> list[PrescribedMotion]:
    X = region.X
    end = np.flatnonzero(np.abs(X[:, 0] - L) < 1e-9 * L)
    if _support_fix(study, p) == "xy":
        return [PrescribedMotion(np.concatenate([2 * end, 2 * end + 1]))]
    corner = end[[np.argmin(X[end, 1])]]
    return [PrescribedMotion(2 * corner + 1)]


def _fem_region(p: dict, built: Built, x0: float):
    """FEM laminate on [x0, span / 2] x [0, H], one element row per particle row, graded from x0."""
    lam, k = built.lam, p["zone.plies_per_particle"]
    n = p["mesh.elements_along"]
    ratio = p["mesh.element_ratio"] ** (1.0 / max(n - 1, 1))
    xs = mesh.graded(x0, built.half_span, n, ratio, x0)
    ys = np.linspace(0.0, lam.thickness, sum(lam.plies) // k + 1)
    m = mesh.rectangle(xs, ys, p["mesh.element"])
    cy = m.p[1, m.t].mean(axis=0)
    run = np.searchsorted(np.cumsum(lam.plies) * lam.ply_thickness, cy)
    D = np.array([lam.D(lam.angles[b]) for b in run])
    return make_region(m, p, D, lam.ply["rho"], built.t)


def _fem_beam(study, p: dict, built: Built, t_end: float):
    """All-FEM: the impactors on the top face nodes, the symmetry plane held in x."""
    region = _fem_region(p, built, 0.0)
    X, L, H = region.X, built.half_span, built.lam.thickness
    axis = np.flatnonzero(X[:, 0] < 1e-9 * L)
    top = X[:, 1] > H - 1e-9 * H
    h_node = np.diff(np.unique(X[top, 0])).min()
    imps = {}
    for name in study.layout.names["impactors"]:
        q = section(p, f"impactors.{name}")
        k_pen = (q["penalty"] or built.lam.transverse_modulus() * built.t) * max(1.0, h_node / built.t)
        imps[name] = RigidImpactor("cylinder", np.array([0.0, H + q["radius"] + 1e-9]), q["radius"],
                                   0.5 * q["mass_per_width"] * built.t, np.array([0.0, -q["velocity"]]), k_pen,
                                   friction=q["friction"])
    dyn = ExplicitDynamics(region, supports=[*_fem_supports(study, p, region, L), PrescribedMotion(2 * axis)],
                           impactors=list(imps.values()))
    built.dyn, built.impactors, built.fem_elements = dyn, imps, region.n_elements
    return fem_only(dyn, p, t_end, {})


def _particle_zone(built: Built, x_end: float, tied: bool, clamped: bool):
    """(lattice, engine scene, intralaminar LawBonds, interlaminar LawBonds) on [0, x_end] x
    [0, H]: column 0 on the symmetry plane; the last on the FEM's face (``tied``), or the
    beam's end, held by a clamp if ``clamped``."""
    lam, d = built.lam, built.t
    k = round(d / lam.ply_thickness)
    m = lam.ply
    strengths = HoffmanStrengths(Xt=m["Xt"], Xc=m["Xc"], Yt=m["Yt"], Yc=m["Yc"], Zt=m["Yt"], Zc=m["Yc"],
                                 S23=m["S23"], S13=m["S12"], S12=m["S12"])
    mat = ply_lattice.PlyMaterial(m["E11"], m["E22"], m["G12"], m["G23"], m["rho"], strengths, m["Gf_fibre"],
                                  m["Gf_matrix"], moduli={a: ply_lattice.slice_moduli(lam.D(a)) for a in set(lam.angles)})
    lat = ply_lattice.build(0.0, int(round(x_end / d)) + 1, 0.0, [n // k for n in lam.plies], lam.angles, d, mat)
    last = lat.column == lat.column.max()
    on_plane = (lat.column == 0) | (last & tied)  # half cells
    l = lat.x[lat.intra_pairs[:, 1]] - lat.x[lat.intra_pairs[:, 0]]
    intra = LawBonds(lat.intra_pairs, lat.x, l, np.where(on_plane[lat.intra_pairs].all(axis=1), 0.5, 1.0) * d * d,
                     lat.intra_law, volume=lat.cell_volume() * np.where(on_plane, 0.5, 1.0), label="intralaminar")
    itf = lam.interface
    law = ply_lattice.interlaminar_law(lat, itf["Z0"], itf["R0"], itf["GIc"], itf["GIIc"])
    inter = LawBonds(lat.inter_pairs, lat.x, np.tile([0.0, 1.0, 0.0], (len(lat.inter_pairs), 1)),
                     np.where(on_plane[lat.inter_pairs].all(axis=1), 0.5, 1.0) * d * d, law,
                     friction=itf["friction"], label="interlaminar", along=lat.inter_along)
    lat.density = lat.density * np.where(on_plane, 0.5, 1.0)
    groups = {"interface": np.flatnonzero(last)} if tied else {"fixed": np.flatnonzero(last)} if clamped else {}
    pairs = np.vstack([lat.intra_pairs, lat.inter_pairs])
    k_hold = 1e-9 * float(np.max(lat.intra_law.K)) * d**2  # placeholder bonds: the laws act through LawBonds
    scene = DemScene(lat.x, lat.radius, lat.density, pairs, kn=k_hold, ks=0.0, plane=True,
                     young=float(np.max(lat.intra_law.K)) * d, placeholder_bonds=True, groups=groups)
    return lat, scene, intra, inter


def _particle_impactor(p: dict, name: str, built: Built) -> ParticleImpactor:
    """Half of the cylinder (the symmetry plane cuts it) on the top rows, its x motion held."""
    q, lat, d = section(p, f"impactors.{name}"), built.lattice, built.t
    R, r, H = q["radius"], lat.radius, built.lam.thickness
    k_pen = q["penalty"] or built.lam.transverse_modulus() * d
    top = np.flatnonzero(lat.row >= lat.row.max() - 1)
    imp = RigidImpactor("sphere", np.array([0.0, H - d / 2 + R + r + 1e-9, 0.0]), R + r, 0.5 * q["mass_per_width"] * d,
                        np.array([0.0, -q["velocity"], 0.0]), k_pen, friction=q["friction"])
    return ParticleImpactor(imp, top, fixed=(True, False, True))
