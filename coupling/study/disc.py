"""The assembler of a disc: a quarter of a circular laminated plate (symmetry planes x = 0 and
y = 0), clamped at its rim (diameter geometry.span), struck on its centre by a rod (the seed
paper's example 5.3, the numerical-stability study).

FEM: Hex8 on a quarter disc mapped from a square grid (mesh.elements_along per radius,
mesh.elements_per_ply through each ply), Total Lagrangian or linear, full or one-point
integration with Flanagan-Belytschko hourglass control. With the laminate's
``far_field_interfaces = "cohesive"`` each interface between plies of different angle has
its nodes doubled and joined node to node by the interface's Hashin law (its penalty K as
stiffness per area, each pair standing for its node's tributary area), evaluated by the same
law code as on particles. The rod is rigid, in penalty contact with the top surface: a
node's stiffness is impactors.*.penalty times its share of the rod's face (rod_footprint).

Coupled: the square [0, zone.half_width]^2 under the rod through the whole thickness is a 3D
ply lattice (dem_region/ply_block.py) with the laminate's interface law between plies, the
rod on its top particles (its edge rounded by the particle radius), the FEM plate around it
an O-grid whose hole is the zone's square exactly, tied at x = a and y = a. A zone that grows
(zone.grow, study/growth.py) keeps a reserve: the O-grid's square is then the growth limit's
(zone.grow_to, or half the radius), one element per particle spacing, so a grown zone's far
field is the old one less the square's new cells and every remaining node keeps its state.

Penalties are stiffness per area (Pa/m): a node gets penalty x its tributary area. This
reading makes the paper's observations consistent: at 2e14 a surface node's contact mode
needs dt < ~4e-7 s (hence its 1e-7 s), at 2e10 the rod sinks metres into the plate.
"""
from __future__ import annotations

import numpy as np
import skfem

from dem_region import ply_block
from dem_region.particle_impactor import ParticleImpactor
from fem_region import mesh
from fem_region.elements import ELEMENTS
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from fem_region.region import FemRegion
from physics.impactor import RigidImpactor
from physics.law_bonds import LawBonds
from physics.laws import HashinCohesiveLaw

from ..params import CaseError
from ..participants.coupled import coupled_simulation
from ..participants.dem import hold_symmetry_planes
from ..participants.fem import cohesive_node_bonds, energies_with, fem_only
from .assemble import Built, body_of, check_growth, interlaminar_law, spacing_below
from .closed_forms import SMALL_MASS, disc_mass_ratio
from .schema import section


def core_cells(p: dict) -> int:
    """Grid cells along each side of the square hole the DEM zone fills (coupled mode)."""
    return max(1, int(round(p["mesh.elements_along"] * p["zone.half_width"] / (0.5 * p["geometry.span"]))))


def grid(p: dict, core: bool, reserve: float = 0.0) -> tuple[np.ndarray, float, float, int]:
    """(g (N + 1,), A m, s, c): the square grid's lines g on [0, 1] (both directions), the
    square [0, s]^2 of the grid mapped onto [0, A]^2 of the plate, and the c x c cells of the
    DEM zone's hole. Without a reserve A is the zone's half width over core_cells of
    mesh.elements_along equal cells; with one (m, a zone that may grow to there, a whole number
    of particle spacings d) the square is the reserve, one cell per d, so any grown zone's edge
    is a grid line and its far field the old one less cells (study/growth.py), and the blend to
    the rim keeps about its share of mesh.elements_along."""
    n, R = p["mesh.elements_along"], 0.5 * p["geometry.span"]
    if not reserve:
        c = core_cells(p) if core else 0
        return np.linspace(0.0, 1.0, n + 1), p["zone.half_width"], c / n, c
    d = p["zone.particle_size"]
    m, n_out = int(round(reserve / d)), max(2, int(round(n * (R - reserve) / R)))
    s = m / (m + n_out)
    g = np.concatenate([np.linspace(0.0, s, m + 1), np.linspace(s, 1.0, n_out + 1)[1:]])
    return g, reserve, s, int(round(p["zone.half_width"] / d)) if core else 0


def _map(u: np.ndarray, v: np.ndarray, p: dict, core: bool, A: float = 0.0, s: float = 0.0
         ) -> tuple[np.ndarray, np.ndarray]:
    """The square grid [0, 1]^2 onto the quarter disc. Without a core:
    (u sqrt(1 - v^2 / 2), v sqrt(1 - u^2 / 2)). With one (an O-grid): the grid square
    [0, s]^2 onto the plate's square [0, A]^2 exactly (the DEM zone's, or the reserve it may
    grow in: ``grid``), and each ray from it blended linearly from the square's side to the rim."""
    R = 0.5 * p["geometry.span"]
    if not core:
        return R * u * np.sqrt(1 - v**2 / 2), R * v * np.sqrt(1 - u**2 / 2)
    rho = np.maximum(u, v)
    w = np.clip((rho - s) / (1 - s), 0.0, 1.0)[None]
    uv = np.array([u, v])
    with np.errstate(invalid="ignore", divide="ignore"):
        square = np.nan_to_num(A * uv / rho)
        circle = np.nan_to_num(R * uv / np.hypot(u, v))
    out = np.where(rho >= s, (1 - w) * square + w * circle, A * uv / s)
    return out[0], out[1]


def disc_mesh(p: dict, lam, core: bool, reserve: float = 0.0):
    """(Hex8 quarter disc, run of each element (nel,), interface node pairs (k, 2) lower /
    upper, grid key (n_nodes,) of each node on the (N + 1)^2 surface grid). With cohesive
    far-field interfaces the nodes on each interface between runs are doubled (the upper
    run's elements take the twins). core: the DEM zone's square left out; reserve: see grid."""
    m, tp = p["mesh.elements_per_ply"], lam.ply_thickness
    g, A, s, c = grid(p, core, reserve)
    n = len(g) - 1
    box = mesh.box(g, g, np.linspace(0.0, lam.thickness, sum(lam.plies) * m + 1), "hex8")
    P, T = box.p, box.t
    levels = np.cumsum(lam.plies)[:-1] * tp  # interfaces between runs, bottom up
    run = np.searchsorted(levels, P[2, T].mean(axis=0))
    cohesive = p[f"laminates.{p['geometry.laminate']}.far_field_interfaces"] == "cohesive"
    P, T, pairs = mesh.split_interfaces(P, T, run, levels if cohesive else [], 2, 1e-9 * tp)
    u, v = P[0].copy(), P[1].copy()
    P[0], P[1] = _map(u, v, p, core, A, s)
    line = lambda w: np.abs(np.subtract.outer(w, g)).argmin(axis=1)  # the grid line a coordinate is on
    key = line(v) * (n + 1) + line(u)
    if core:  # drop the hole's elements, then the nodes no element uses
        keep = np.maximum(u[T].mean(axis=0), v[T].mean(axis=0)) > g[c]
        T, run = T[:, keep], run[keep]
        used = np.unique(T)
        renumber = np.full(P.shape[1], -1)
        renumber[used] = np.arange(used.size)
        P, T, key = P[:, used], renumber[T], key[used]
        pairs = renumber[pairs]
        pairs = pairs[(pairs >= 0).all(axis=1)]
    return skfem.MeshHex1(np.ascontiguousarray(P), np.ascontiguousarray(T)), run, pairs, key.astype(int)


def tributary_area(p: dict, core: bool, reserve: float = 0.0) -> np.ndarray:
    """((N + 1)^2,) m^2 by grid key: a quarter of each adjoining quad of the mapped surface grid
    (none from the DEM zone's hole); reserve: see grid."""
    g, A, s, c = grid(p, core, reserve)
    n = len(g) - 1
    U, V = np.meshgrid(g, g)  # row = v, column = u: key = row (n + 1) + column
    xy = np.stack(_map(U, V, p, core, A, s), axis=-1)
    a = xy[1:, 1:] - xy[:-1, :-1]
    b = xy[:-1, 1:] - xy[1:, :-1]
    quad = 0.5 * np.abs(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0])
    quad[:c, :c] = 0.0
    area = np.zeros((n + 1, n + 1))
    for di in (0, 1):
        for dj in (0, 1):
            area[di:n + di, dj:n + dj] += quad / 4
    return area.ravel()


def rod_footprint(region: FemRegion, key: np.ndarray, n: int, H: float, r: float) -> np.ndarray:
    """(n_nodes,) m^2: each top-surface node's share (the surface at z = H, grid keys ``key`` of
    the (n + 1)^2 surface grid) of the face of a rod of radius r (quad_shares). Sums to the
    quarter face's area (to the sums' resolution of its edge), whatever the mesh: a rod whose
    radius falls between node rings still presses with its whole face (on the coarse mesh a
    17.7 mm rod covered one node and inverted its element)."""
    top = np.flatnonzero(np.abs(region.X[:, 2] - H) < 1e-9 * H)
    xy = np.full(((n + 1) ** 2, 2), np.nan)
    xy[key[top]] = region.X[top, :2]
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    corners = np.stack([i * (n + 1) + j, i * (n + 1) + j + 1, (i + 1) * (n + 1) + j, (i + 1) * (n + 1) + j + 1],
                       axis=-1).reshape(-1, 4)  # (quads, 4): (u, v) = (0, 0), (1, 0), (0, 1), (1, 1)
    corners = corners[~np.isnan(xy[corners]).any(axis=(1, 2))]  # the quads the mesh has
    by_key = quad_shares(xy[corners], corners, (n + 1) ** 2, r, np.ptp(region.X[top, 0]) / n)
    out = np.zeros(region.n_nodes)
    out[top] = by_key[key[top]]
    return out


def face_shares(region: FemRegion, H: float, r: float) -> np.ndarray:
    """(n_nodes,) m^2: each node's share of a rod's face of radius r centred on x = y = 0 on the
    top faces (z = H) of a Hex8 mesh whose elements are boxes along the axes (a plate's)."""
    X = region.X
    T = region.mesh.t
    on_top = np.abs(X[T, 2] - H) < 1e-9 * H  # (8, nel)
    faces = np.flatnonzero(on_top.sum(axis=0) == 4)
    corners = T[:, faces].T[on_top[:, faces].T].reshape(-1, 4)
    size = float(np.min(np.ptp(X[corners, 0], axis=1)))
    grid = np.round(X[corners, :2] / (1e-6 * size))  # (a mesh file's coordinates carry round-off)
    order = np.lexsort((grid[..., 0], grid[..., 1]), axis=-1)  # by y, then x: (0, 0), (1, 0), (0, 1), (1, 1)
    corners = np.take_along_axis(corners, order, axis=1)
    return quad_shares(X[corners][..., :2], corners, region.n_nodes, r, size)


def quad_shares(X: np.ndarray, corners: np.ndarray, n: int, r: float, size: float) -> np.ndarray:
    """(n,) m^2: the integral of each corner's bilinear shape function over the part of its quads
    inside the radius r about the origin. X: (quads, 4, 2) m, the corners in (u, v) = (0, 0),
    (1, 0), (0, 1), (1, 1) order; corners: (quads, 4) their indices below n; size: m, a quad's
    typical side (midpoint sums on cells of at most r / 40)."""
    n_sub = max(24, int(np.ceil(40 * size / r)))
    g = (np.arange(n_sub) + 0.5) / n_sub
    xi, eta = (a.ravel() for a in np.meshgrid(g, g, indexing="ij"))
    N = np.stack([(1 - xi) * (1 - eta), xi * (1 - eta), (1 - xi) * eta, xi * eta], axis=-1)  # (s, 4)
    dN_dxi = np.stack([-(1 - eta), 1 - eta, -eta, eta], axis=-1)
    dN_deta = np.stack([-(1 - xi), -xi, 1 - xi, xi], axis=-1)
    x = np.einsum("sa,qai->qsi", N, X)
    a, b = np.einsum("sa,qai->qsi", dN_dxi, X), np.einsum("sa,qai->qsi", dN_deta, X)
    dA = np.abs(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]) / n_sub**2  # (quads, s)
    # each cell's covered fraction, linear in the edge's distance across the cell (exact for a
    # straight edge along the cell's side): the plain midpoint indicator's edge error is one
    # cell's order in area (the Gauss circle problem), 3e-3 of the face at r / 40
    inside = np.clip(0.5 + (r - np.hypot(x[..., 0], x[..., 1])) / np.sqrt(dA), 0.0, 1.0)
    share = np.einsum("qs,sa->qa", dA * inside, N)
    return np.bincount(corners.ravel(), share.ravel(), minlength=n)


def _region(p: dict, lam, core: bool, reserve: float = 0.0):
    """(FEM plate, interface node pairs, grid key); reserve: see grid."""
    m, run, pairs, key = disc_mesh(p, lam, core, reserve)
    if p["fem.integration"] == "selective":
        raise CaseError("fem.integration = 'selective': a 90 ply couples normal and shear terms in 3D; "
                        "allowed full or reduced")
    C = np.array([lam.C(a) for a in lam.angles])[run]
    region = FemRegion(m, ELEMENTS["hex8"], C, lam.ply["rho"], 1.0, p["fem.integration"], p["fem.formulation"],
                       hourglass=p["fem.hourglass"], hourglass_kappa=p["fem.hourglass_kappa"])
    return region, pairs, key


def _supports(region: FemRegion, p: dict) -> list[PrescribedMotion]:
    """Clamped rim, symmetry planes x = 0 and y = 0."""
    X, R = region.X, 0.5 * p["geometry.span"]
    rim = np.flatnonzero(np.hypot(X[:, 0], X[:, 1]) > R * (1 - 1e-9))
    sym_x, sym_y = np.flatnonzero(X[:, 0] < 1e-9 * R), np.flatnonzero(X[:, 1] < 1e-9 * R)
    return [PrescribedMotion(np.concatenate([3 * rim + k for k in range(3)])),
            PrescribedMotion(3 * sym_x), PrescribedMotion(3 * sym_y + 1)]


def _node_bonds(p: dict, lam, dyn: ExplicitDynamics, pairs: np.ndarray, area: np.ndarray) -> LawBonds | None:
    """The far field's cohesive interfaces (None when its plies share nodes)."""
    if len(pairs) == 0:
        return None
    itf, name = lam.interface, p[f"laminates.{p['geometry.laminate']}.interface"]
    try:
        law = HashinCohesiveLaw(K=itf["penalty"], Z0=itf["Z0"], R0=itf["R0"], GIc=itf["GIc"], GIIc=itf["GIIc"])
    except ValueError as exc:
        raise CaseError(f"interfaces.{name}.penalty = {itf['penalty']:g}: {exc}") from None
    return cohesive_node_bonds(dyn, pairs, area, law, itf["friction"])


def rod(p: dict, name: str, H: float, penalty: float, rounding: float = 0.0) -> RigidImpactor:
    """The quarter model's share of the rod, its face on the top surface at z = H."""
    q = section(p, f"impactors.{name}")
    mass = 0.25 * q["rho"] * np.pi * q["radius"] ** 2 * q["length"]
    return RigidImpactor("rod", np.array([0.0, 0.0, H + 1e-9]), q["radius"], mass,
                         np.array([0.0, 0.0, -q["velocity"]]), penalty, axis=np.array([0.0, 0.0, 1.0]),
                         rounding=rounding)


def grow_limit(p: dict, built: Built) -> float:
    """The farthest a disc's grown zone may reach (m): zone.grow_to, or the last whole particle
    spacing below half the plate's radius (beyond, the O-grid's elements at the square's corner
    grow thin against the rim)."""
    return p["zone.grow_to"] or spacing_below(0.25 * p["geometry.span"], built.t)


def disc(study, p: dict, mode: str, dem: str, start=None):
    """(Simulation, Built) of the quarter disc in ``mode`` (fem or coupled); start: the state a
    coupled run continues from (a grown zone's, coupled_simulation's)."""
    built = body_of(p, mode)
    lam, H = built.lam, built.lam.thickness
    (support,) = study.layout.names["supports"]
    if p[f"supports.{support}.condition"] != "clamped":
        raise CaseError(f"supports.{support}.condition = {p[f'supports.{support}.condition']!r}: a disc is clamped "
                        "at its rim; allowed: clamped")
    (rod_name,) = study.layout.names["impactors"]
    penalty = p[f"impactors.{rod_name}.penalty"]
    if mode == "fem":
        region, pairs, key = _region(p, lam, core=False)
        area_by_key = tributary_area(p, core=False)
        top = np.flatnonzero(np.abs(region.X[:, 2] - H) < 1e-9 * lam.ply_thickness)
        striker = rod(p, rod_name, H, penalty * float(np.median(area_by_key[key[top]])))
        striker.footprint = penalty * rod_footprint(region, key, p["mesh.elements_along"], H,
                                                p[f"impactors.{rod_name}.radius"])
        dyn = ExplicitDynamics(region, supports=_supports(region, p), impactors=[striker])
        bonds = _node_bonds(p, lam, dyn, pairs, area_by_key[key[pairs[:, 0]]])
        sim = fem_only(dyn, p, study.t_end, {})
        built.dyn, built.fem_elements, built.impactors = dyn, region.n_elements, {rod_name: striker}
    else:
        reserve = 0.0
        if p.get("zone.grow"):
            reserve = grow_limit(p, built)
            check_growth(p, built.t, p["zone.half_width"], reserve, reserve <= 0.25 * p["geometry.span"],
                         f"at most half the plate's radius ({0.25 * p['geometry.span']:g} m)")
        block, scene, intra, inter, impactor = _particle_zone(p, built, rod_name, penalty, reserve)
        area_by_key = tributary_area(p, core=True, reserve=reserve)
        made = []

        def make(extra_mass):
            region, pairs, key = _region(p, lam, core=True, reserve=reserve)
            dyn = ExplicitDynamics(region, supports=_supports(region, p), extra_mass=extra_mass)
            made.append(_node_bonds(p, lam, dyn, pairs, area_by_key[key[pairs[:, 0]]]))
            built.fem_pairs = pairs
            return dyn

        i, j, _ = block.index.T

        def hold(backend) -> None:  # the symmetry planes, before the engine starts
            hold_symmetry_planes(backend, i, j, held=scene.groups["interface"])

        models = (intra, inter, impactor)
        sim, clock = coupled_simulation(p, make, scene, dem, study.t_end, models=models, start=start, hold=hold)
        bonds, backend = made[-1], clock.dem
        built.lattice, built.intra, built.inter, built.backend = block, intra, inter, backend
        built.column = np.maximum(i, j)  # the zone's edge: the largest
        built.dyn, built.fem_elements, built.impactors = clock.fem, clock.fem.region.n_elements, {rod_name: impactor}
        built.clock, built.models = clock, models
        sim.counts.update({"law_bonds": len(intra.pairs)})
    ratio = disc_mass_ratio(study, p)
    if ratio < SMALL_MASS:
        sim.warnings.append(f"the rod is {ratio:.2f} of the plate's mass, below Olsson's small-mass limit "
                            f"{SMALL_MASS}: the response is wave-controlled and only the spring-mass bracket's upper "
                            "bound (the delaminated plate) is checked")
    built.node_bonds = bonds
    if bonds is not None:
        sim.energies = energies_with(sim.energies, [bonds])
    sim.counts.update({"interface_bonds": (len(bonds.pairs) if bonds is not None else 0)
                       + (len(built.inter.pairs) if built.inter is not None else 0)})
    return sim, built


def _particle_zone(p: dict, built: Built, rod_name: str, penalty: float, reserve: float = 0.0):
    """(block, scene, intralaminar LawBonds, interlaminar LawBonds, the rod on the particles):
    the square [0, a]^2 through the whole thickness; columns on x = 0, y = 0 (symmetry) and on
    x = a, y = a (tied to the FEM) carry half cells. reserve (m): a growing zone's limit, which
    the zone may reach (else it stays within twice the rod's radius)."""
    lam = built.lam
    a, d, tp = p["zone.half_width"], p["zone.particle_size"], lam.ply_thickness
    for key, length in (("laminates.*.ply_thickness", tp), ("zone.half_width", a)):
        if abs(length / d - round(length / d)) > 1e-6:
            raise CaseError(f"zone.particle_size = {d:g}: must divide {key} = {length:g} m")
    r = p[f"impactors.{rod_name}.radius"]
    top = reserve or min(2 * r, 0.25 * p["geometry.span"])
    if not top * (1 + 1e-9) >= a > r + 2 * d:
        limit = "zone.grow_to (or half the plate radius)" if reserve else "twice the rod radius or half the plate radius"
        raise CaseError(f"zone.half_width = {a:g}: allowed above the rod radius + 2 particles ({r + 2 * d:g} m) and "
                        f"up to {limit} ({top:g} m)")
    N, rows = int(round(a / d)) + 1, [int(round(n * tp / d)) for n in lam.plies]
    names = section(p, f"laminates.{p['geometry.laminate']}")
    try:
        block = ply_block.build((0.0, 0.0, 0.0), (N, N), rows, lam.angles, d, lam.material(),
                                half_planes=[(0, 0), (1, 0), (0, N - 1), (1, N - 1)])
    except ValueError as exc:
        raise CaseError(f"materials.{names['material']}.G12 = {lam.ply['G12']:g}: {exc}") from None
    l = block.x[block.intra_pairs[:, 1]] - block.x[block.intra_pairs[:, 0]]
    intra = LawBonds(block.intra_pairs, block.x, l, block.intra_area, block.intra_law, volume=block.volume,
                     label="intralaminar")
    itf = lam.interface
    law = interlaminar_law(p, lam, block.inter_K, d)
    inter = LawBonds(block.inter_pairs, block.x, np.tile([0.0, 0.0, 1.0], (len(block.inter_pairs), 1)),
                     block.inter_area, law, friction=itf["friction"], along=block.inter_along, label="interlaminar")
    i, j, k = block.index.T
    scene = ply_block.engine_scene(block, groups={"interface": np.flatnonzero((i == N - 1) | (j == N - 1))})
    # the rod grown by the particle radius meets the particle centres (rounded edge: a particle
    # beside the rod is pushed aside, not found deep under the face)
    striker = rod(p, rod_name, lam.thickness, penalty * d**2, rounding=block.radius)
    return block, scene, intra, inter, ParticleImpactor(striker, np.flatnonzero(k >= k.max() - 1), fixed=(True, True, False))
