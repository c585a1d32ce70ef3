"""The assembler of a block: a quarter of a rectangular block of one isotropic quasi-brittle
material (symmetry planes x = 0 and y = 0, the depth along z), resting on its bottom face,
struck on the centre of its top face by a sphere or a flat-faced rod, or loaded there by a
pressure history on a disc ([loads.*] kind = "pressure": consistent nodal forces on the FEM's
faces, each top particle the part of its footprint under the disc).

Particles: the body as a cubic lattice (ply_block with E and G = E / (2 (1 + nu)) exact, as a
bonded beam's body) whose bonds fail by Hoffman with ft, fc and the isotropic shear strength
sqrt(ft fc / 3) (Hoffman 1967), Gf-regularised softening, strengths scattered by
1 +- strength_scatter. The zone is a column through the whole depth whose footprint
zone.shape selects (study/selectors.py: box, cylinder, or a cylinder about the impactor);
all-DEM fills the block. FEM: Hex8, one element layer per particle row, mesh.elements_width
equal elements over the zone's square, then mesh.elements_along graded to the sides; or a
Gmsh file's hexahedra (mesh.file: its physical group named after the material is the body, one
named after the support holds the floor's nodes; elements of one particle cell over the
zone's square).

Supports ([supports.NAME] at = "bottom"): fixed (every DOF of the bottom face held) or
sliding (its vertical DOF only: a frictionless rigid floor).
"""
from __future__ import annotations

import numpy as np

from dem_region import ply_block
from dem_region.scatter import strength_scale
from fem_region import mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from physics.law_bonds import LawBonds

from ..params import CaseError
from ..participants.coupled import coupled_simulation
from ..participants.dem import dem_only
from ..participants.fem import fem_only, make_region
from .assemble import Built, Laminate, _fem_striker, _particle_striker, _plate_axis
from .bonded import load_curve
from .pressure import fem_pressure, particle_pressure
from .schema import section
from .selectors import footprint, tie_particles, whole_spacings


def body(p: dict) -> Laminate:
    """The block as a one-run 'laminate' of its isotropic material, one run of rows of
    zone.particle_size through the depth: the plate's helpers (strikers, selectors) read its
    thickness, its through-thickness modulus E22 and density. CaseError if the depth holds no
    whole number (>= 4) of rows."""
    m = section(p, f"materials.{p['geometry.material']}")
    d, H = p["zone.particle_size"], p["geometry.depth"]
    rows = int(round(H / d)) if d > 0 else 0
    if rows < 4 or abs(rows * d - H) > 1e-6 * H:
        raise CaseError(f"zone.particle_size = {d:g}: the depth {H:g} m must hold a whole number (>= 4) of rows")
    G = m["E"] / (2 * (1 + m["nu"]))
    S = np.sqrt(m["ft"] * m["fc"] / 3)  # Hoffman's isotropic shear strength (Hoffman 1967)
    ply = {"E11": m["E"], "E22": m["E"], "G12": G, "G23": G, "nu12": m["nu"], "nu23": m["nu"], "rho": m["rho"],
           "Xt": m["ft"], "Xc": m["fc"], "Yt": m["ft"], "Yc": m["fc"], "S12": S, "S23": S,
           "Gf_fibre": m["Gf"], "Gf_matrix": m["Gf"]}
    return Laminate([0.0], [rows], d, ply, {"Z0": np.inf, "R0": np.inf})  # (no interfaces: index 0)


def block(study, p: dict, mode: str, dem: str):
    """(Simulation, Built) of the quarter block in ``mode``."""
    lam = body(p)
    d = lam.ply_thickness
    built = Built(p, mode, lam, 0.5 * p["geometry.span"], d, 4.0, dim=3)
    a2, b2 = 0.5 * p["geometry.span"], 0.5 * p["geometry.width"]
    whole_spacings(p, d)
    (support,) = study.layout.names["supports"]
    fixed = p[f"supports.{support}.condition"] == "fixed"
    named = _named(p, support)
    fp = footprint(study, p, built)
    names = list(study.layout.names["impactors"])
    loads = list(study.layout.names["loads"])
    curve = load_curve(p, loads[0]) if loads else None
    if mode == "fem":
        region = _fem_block(p, lam, fp, hole=False)
        imps = {name: _fem_striker(study, p, name, built, region) for name in names}
        dyn = ExplicitDynamics(region, supports=_supports(region, fixed, named), impactors=list(imps.values()),
                               loads=fem_pressure(p, loads, region, lam.thickness, curve))
        built.dyn, built.impactors, built.fem_elements = dyn, imps, region.n_elements
        if loads:
            built.load_probes = {loads[0]: lambda: float(curve(dyn.state.t))}
        return fem_only(dyn, p, study.t_end, {}), built
    tied = mode == "coupled"
    n = int(round(fp.w / d)) + 1 if tied else None
    nx, ny = (n, n) if tied else (int(round(a2 / d)) + 1, int(round(b2 / d)) + 1)
    lattice = ply_block.build((0.0, 0.0, 0.0), (nx, ny), lam.plies, [0.0], d, lam.material(),
                              half_planes=[] if tied else [(0, 0), (1, 0), (0, nx - 1), (1, ny - 1)])
    if tied:
        cells = fp.cells(d)
        lattice, _ = ply_block.carve(lattice, cells)
    i, j, k = lattice.index.T
    if tied:  # the tie: particles on the faces between the zone's cells and the FEM's
        held = np.flatnonzero(tie_particles(cells, i, j))
        groups = {"interface": held}
    else:  # the floor: prescribed below (a clamp on every DOF would be the engine's fixed group)
        held, groups = np.zeros(0, int), {}
    mat_name = p["geometry.material"]
    lattice.intra_law.strength_scale[:] = strength_scale(lattice.x, lattice.intra_pairs, d,
                                                         p[f"materials.{mat_name}.seed"],
                                                         p[f"materials.{mat_name}.strength_scatter"])
    l = lattice.x[lattice.intra_pairs[:, 1]] - lattice.x[lattice.intra_pairs[:, 0]]
    intra = LawBonds(lattice.intra_pairs, lattice.x, l, lattice.intra_area, lattice.intra_law, volume=lattice.volume,
                     label="body")
    scene = ply_block.engine_scene(lattice, groups=groups)
    built.lattice, built.intra = lattice, intra
    built.column = np.zeros(lattice.n, int)  # (the zone's edge: probes of laminates' plies only)
    built.impactors = {name: _particle_striker(study, p, name, built) for name in names}
    models = (intra, *built.impactors.values())
    if loads:
        load = particle_pressure(p, loads[0], lattice, cells if tied else None, (a2, b2), curve)
        models += (load,)
        built.particle_loads = [load]
        built.load_probes = {loads[0]: lambda: float(curve(load.time))}
    if mode == "dem":
        sim, backend, _ = dem_only(p, scene, dem, study.t_end, models=models)
    else:
        def make(extra_mass):
            region = _fem_block(p, lam, fp, hole=True)
            return ExplicitDynamics(region, supports=_supports(region, fixed, named), extra_mass=extra_mass,
                                    loads=fem_pressure(p, loads, region, lam.thickness, curve))
        sim, clock = coupled_simulation(p, make, scene, dem, study.t_end, models=models)
        backend, built.dyn, built.fem_elements = clock.dem, clock.fem, clock.fem.region.n_elements
    built.backend = backend
    _hold(backend, i, j, k, held, fixed)
    sim.counts.update({"law_bonds": len(intra.pairs)})
    return sim, built


def _hold(backend, i: np.ndarray, j: np.ndarray, k: np.ndarray, held: np.ndarray, fixed: bool) -> None:
    """The symmetry planes (x on i == 0, y on j == 0) and the floor under the bottom row (every
    DOF, or z on a sliding floor), one prescription per particle with all its DOFs; ``held``:
    particles the tie drives."""
    dofs = np.char.add(np.char.add(np.where(i == 0, "x", ""), np.where(j == 0, "y", "")),
                       np.where(k == 0, "z", ""))
    dofs = np.where((k == 0) & fixed, "xyz", dofs)
    free = np.ones(len(i), bool)
    free[held] = False
    for kind in ("x", "y", "z", "xy", "xz", "yz", "xyz"):
        ids = np.flatnonzero(free & (dofs == kind))
        if ids.size:
            backend.prescribe(ids, kind)
            backend.set_velocities(ids, np.zeros((ids.size, 3)))


def _fem_block(p: dict, lam: Laminate, fp, hole: bool):
    """Hex8 on the quarter block, one element layer per particle row (or a Gmsh file's); with
    ``hole`` the zone's elements left out."""
    if p["mesh.file"]:
        return _file_block(p, lam, fp, hole)
    n, ratio = p["mesh.elements_along"], p["mesh.element_ratio"] ** (1.0 / max(p["mesh.elements_along"] - 1, 1))
    m = mesh.box(_plate_axis(fp.w, 0.5 * p["geometry.span"], fp.n, n, ratio),
                 _plate_axis(fp.w, 0.5 * p["geometry.width"], fp.n, n, ratio),
                 np.linspace(0.0, lam.thickness, lam.plies[0] + 1), "hex8")
    if hole:
        centre = m.p[:, m.t].mean(axis=1)
        m = m.remove_elements(np.flatnonzero(fp.inside(centre[0], centre[1])))
    return make_region(m, p, lam.C(0.0), lam.ply["rho"], 1.0)


def _named(p: dict, support: str) -> np.ndarray | None:
    """(k, 3) m: the nodes of a mesh file's physical group named as the support, or None."""
    if not p["mesh.file"]:
        return None
    try:
        return mesh.read_gmsh(p["mesh.file"], p["geometry.material"])[1].get(support)
    except (OSError, ValueError) as exc:
        raise CaseError(f"mesh.file = {p['mesh.file']!r}: {exc}") from None


def _file_block(p: dict, lam: Laminate, fp, hole: bool):
    """The block from a Gmsh file: the hexahedra of its physical group named after the material,
    spanning the quarter block; with ``hole`` the elements whose centre the zone's footprint
    holds left out, which must be whole columns of the particle cells it selects (a mesh with
    element faces on the particle grid there). CaseError (one line) otherwise."""
    where, d, H = f"mesh.file = {p['mesh.file']!r}", lam.ply_thickness, lam.thickness
    try:
        m, _ = mesh.read_gmsh(p["mesh.file"], p["geometry.material"])
    except (OSError, ValueError) as exc:
        raise CaseError(f"{where}: {exc}") from None
    if mesh.element_name(m) != "hex8":
        raise CaseError(f"{where}: a block takes hexahedra (its faces on the particle grid under the zone); this one "
                        f"holds {mesh.element_name(m)}")
    X = m.p
    box = (0.5 * p["geometry.span"], 0.5 * p["geometry.width"], H)
    tol = 1e-6 * d
    if np.abs(X.min(axis=1)).max() > tol or np.abs(X.max(axis=1) - box).max() > tol:
        raise CaseError(f"{where}: spans {X.min(axis=1).round(9).tolist()} .. {X.max(axis=1).round(9).tolist()} m; "
                        f"allowed: the quarter block 0 .. {[round(b, 9) for b in box]} m")
    if hole:
        centre = X[:, m.t].mean(axis=1)
        zone = np.flatnonzero(fp.inside(centre[0], centre[1]))
        cells = fp.cells(d)
        corners = X[:2, m.t[:, zone]]  # (2, 8, k): each zone element's corners in the plane
        lo, hi = corners.min(axis=1), corners.max(axis=1)
        volume = float(np.prod(hi - lo, axis=0) @ np.ptp(X[2, m.t[:, zone]], axis=0))
        on_grid = np.abs(corners / d - np.round(corners / d)).max() < 1e-6 if zone.size else True
        if not on_grid or abs(volume - cells.sum() * d**2 * H) > 1e-6 * d**2 * H:
            raise CaseError(f"{where}: the zone's elements (centres inside its footprint) are not its "
                            f"{int(cells.sum())} particle cells of {d:g} m through the depth; allowed: a mesh with "
                            f"element faces on the particle grid over the zone's square (0 .. {fp.w:g} m)")
        m = m.remove_elements(zone)
    return make_region(m, p, lam.C(0.0), lam.ply["rho"], 1.0)


def _supports(region, fixed: bool, named: np.ndarray | None = None) -> list[PrescribedMotion]:
    """The bottom face (every DOF, or vertically), or the nodes at the points ``named`` (k, 3)
    (a mesh file's physical group named as the support); the symmetry planes x = 0 and y = 0."""
    X = region.X
    tol = 1e-9 * np.ptp(X[:, 0])
    if named is not None:
        dist = np.linalg.norm(X[:, None, :] - named[None, :, :], axis=2)
        bottom = np.flatnonzero(dist.min(axis=1) < tol)
    else:
        bottom = np.flatnonzero(X[:, 2] < tol)
    out = [PrescribedMotion(np.concatenate([3 * bottom + c for c in range(3)]) if fixed else 3 * bottom + 2)]
    return out + [PrescribedMotion(3 * np.flatnonzero(np.abs(X[:, 0]) < tol)),
                  PrescribedMotion(3 * np.flatnonzero(np.abs(X[:, 1]) < tol) + 1)]
