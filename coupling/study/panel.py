"""The assembler of a panel: a plane-stress slice of a laminate along x (y through the
thickness) with one through-width delamination, clamped at x = 0 and x = span, shortened
axially (the seed paper's example 5.2). Geometrically nonlinear (Total Lagrangian FEM),
quasi-static by slow end shortening (the load's ``duration_periods`` periods of the panel's
first mode, sin^2 ramp of the rate) with mass damping at 2 omega_1.

The delamination is a crack in the mesh (nodes doubled along it between its tips) whose faces
touch through frictionless node-to-node penalty contact (the delamination's ``contact``: fully
debonded Hashin bonds, LawBonds on the FEM nodes); the sublaminate starts with an outward bump
of the delamination's ``imperfection`` x h, the panel with the clamped first mode of
geometry.imperfection x H. The closed forms and readings are in study/buckling.py.

Readings (no reference enters them): local, the film's membrane strain (mean of its two faces'
arc lengths over a gauge that stops zone.window_behind short of each tip, the same in both
modes) at its least compression after it has opened by more than h, times E11 H b; global,
the panel's limit load (the largest axial force: an eccentrically loaded column has a limit
point, not a bifurcation). Southwell's fits on the opening A - B and on the base deflection B
are reported too (the film's and the base's growth are not an ideal strut's, so they read 30 %
high and 10 % low). The tips' energy release rate at the limit load comes from Hutchinson & Suo.

Modes: ``fem`` (the delamination cannot grow) and ``coupled``: a DEM window at each tip
(zone.shape = "crack_tips"), the four-row band of scenes/delamination.py across the
delamination plane (particle spacing d; the FEM above and below it tied to the outer rows),
zone.window_behind into the delamination and zone.window_ahead into the intact laminate.
Across the plane the laminate's Hashin law with linear softening, debonded inside the
delamination (contact only), intact ahead, in corotated kinematics (LawBonds
finite_rotation): the panel's bow turns the tips by 0.04-0.11 rad, whose theta^2 / 2 is the
film's critical strain. The delamination grows from both tips once the energy release rate of
the buckled film reaches the mixed-mode toughness.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dem_region.ply_lattice import lattice_stiffness, slice_moduli
from dem_region.scene import DemScene
from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from fem_region.modal import lowest_modes
from fem_region.stable_step import pair_springs
from physics.law_bonds import LawBonds
from physics.laws import HashinCohesiveLaw

from ..params import CaseError
from ..participants.coupled import coupled_simulation
from ..participants.fem import FemNodes, fem_only, make_region
from ..scenes import delamination as dl
from . import buckling
from .assemble import Built, laminate
from .schema import section


@dataclass(frozen=True)
class Panel:
    """A panel's numbers (SI) from the resolved parameters, and where each lives."""

    E11: float
    E22: float
    G12: float
    nu12: float
    nu23: float
    rho: float
    tp: float  # ply thickness
    plies: int
    n_sub: int  # plies above the delamination
    b: float  # width
    L: float  # free length
    l: float  # delamination length
    delamination: str  # its table's key prefix, "delaminations.NAME"
    interface: str  # "interfaces.NAME"
    load: str  # "loads.NAME"
    material: str  # "materials.NAME"

    @property
    def H(self) -> float:
        return self.plies * self.tp

    @property
    def h(self) -> float:
        return self.n_sub * self.tp

    @property
    def yc(self) -> float:  # the delamination plane
        return self.H - self.h

    @property
    def x1(self) -> float:
        return 0.5 * (self.L - self.l)

    @property
    def x2(self) -> float:
        return 0.5 * (self.L + self.l)

    def loads(self, l: float | None = None) -> dict:
        """The closed forms (buckling.panel_loads), with another delamination length l (m) if given."""
        chi = dl.chi_of(self.E11, self.E22, self.G12)
        return buckling.panel_loads(self.E11, self.G12, chi, self.b, self.H, self.h, self.L, self.l if l is None else l)


def panel_of(p: dict) -> Panel:
    """The Panel of the resolved parameters (one [delaminations.*] and one [loads.*])."""
    lam_name = p["geometry.laminate"]
    lam = laminate(p, lam_name)
    (delam,) = {k.split(".")[1] for k in p if k.startswith("delaminations.")}
    (load,) = {k.split(".")[1] for k in p if k.startswith("loads.")}
    m = lam.ply
    return Panel(m["E11"], m["E22"], m["G12"], m["nu12"], m["nu23"], m["rho"], lam.ply_thickness, sum(lam.plies),
                 p[f"delaminations.{delam}.sublaminate_plies"], p["geometry.width"], p["geometry.span"],
                 p[f"delaminations.{delam}.length"], f"delaminations.{delam}",
                 f"interfaces.{p[f'laminates.{lam_name}.interface']}", f"loads.{load}",
                 f"materials.{p[f'laminates.{lam_name}.material']}")


@dataclass
class PanelParts:
    """What the probes read: the FEM, node sets, the film gauge's faces, the contact and the
    windows' interface bonds (coupled)."""

    g: Panel
    dyn: ExplicitDynamics
    X: np.ndarray  # (n, 2) m, the imperfect reference positions
    X0: np.ndarray  # (2, n) m, the flat (imperfection-free) positions
    right: np.ndarray  # the moving end's nodes
    point_a: np.ndarray  # (1,) mid-span, top face
    point_b: np.ndarray  # (1,) mid-span, bottom face
    faces: list  # the film gauge's two faces, nodes sorted along x
    contact: LawBonds | None
    bonds: LawBonds | None  # the windows' interface bonds


def panel(study, p: dict, mode: str, dem: str):
    """(Simulation, Built) of the panel in ``mode`` (fem or coupled)."""
    g = panel_of(p)
    L, l, n_sub = g.L, g.l, g.n_sub
    if n_sub >= g.plies:
        raise CaseError(f"{g.delamination}.sublaminate_plies = {n_sub}: allowed below the laminate's {g.plies} plies")
    if not l < 0.9 * L:
        raise CaseError(f"{g.delamination}.length = {l:g}: allowed below 0.9 x geometry.span = {0.9 * L:g} m")
    (support,) = study.layout.names["supports"]
    if p[f"supports.{support}.condition"] != "clamped":
        raise CaseError(f"supports.{support}.condition = {p[f'supports.{support}.condition']!r}: a panel is clamped "
                        "at its ends; allowed: clamped")
    H, yc, x1, x2 = g.H, g.yc, g.x1, g.x2
    win = windows(p, g) if mode == "coupled" else []
    region, X0, upper, xs, D = panel_region(p, g, win)
    X = region.X
    left = np.flatnonzero(X[:, 0] < 1e-9 * L)
    right = np.flatnonzero(X[:, 0] > L * (1 - 1e-9))
    clamp = np.concatenate([left * 2, left * 2 + 1, right * 2 + 1])
    # the panel's first mode on the whole FEM panel (with windows cut out, the thin FEM strips
    # over them have modes of their own, far below the panel's)
    whole = region if not win else panel_region(p, g, [])[0]
    ends = lambda r, c: np.flatnonzero(np.abs(r.X[:, 0] - c) < 1e-9 * L)
    fixed = np.concatenate([ends(whole, 0) * 2, ends(whole, 0) * 2 + 1, ends(whole, L) * 2, ends(whole, L) * 2 + 1])
    omega1 = lowest_modes(whole, fixed, whole.mass)[0][0]
    T = p[f"{g.load}.duration_periods"] * 2 * np.pi / omega1
    cf = g.loads()
    total = p[f"{g.load}.shortening_factor"] * cf["global_intact"] * L / (g.E11 * H * g.b)
    speed = lambda t: -2 * total / T * np.sin(np.pi * t / T) ** 2 if t < T else 0.0  # integrates to -total
    contacts = []

    def make_fem(extra_mass=None):
        dyn = ExplicitDynamics(region, supports=[PrescribedMotion(clamp), PrescribedMotion(right * 2, speed)],
                               alpha=2 * omega1, extra_mass=extra_mass)
        if p[f"{g.delamination}.contact"]:
            contacts.append(face_contact(p, g, dyn, X0, upper))
        return dyn

    # the sublaminate's membrane strain: mean of its two faces' arc lengths (bending strains
    # cancel) over a gauge that stops zone.window_behind short of the tips (FEM in both modes;
    # the membrane force of a film without face tractions is the same all along it)
    g1, g2 = x1 + p["zone.window_behind"], x2 - p["zone.window_behind"]
    gauge = (X0[0] >= g1 - 1e-9 * L) & (X0[0] <= g2 + 1e-9 * L)
    top_face = np.flatnonzero(gauge & (np.abs(X0[1] - H) < 1e-9 * H))
    crack_face = np.flatnonzero(gauge & upper & (np.abs(X0[1] - yc) < 1e-9 * H))
    faces = [f[np.argsort(X0[0, f])] for f in (top_face, crack_face)]
    if not all(len(f) > 1 and np.array_equal(X0[0, f], X0[0, faces[0]]) for f in faces):
        raise CaseError(f"zone.window_behind = {p['zone.window_behind']:g}: the film gauge needs FEM crack faces "
                        f"between the windows; allowed below {0.45 * l:g} m")

    bonds = None  # (every input checked above: no engine starts for a refused case)
    if win:
        scene, bonds = window_scene(p, g, win, D)
        sim, clock = coupled_simulation(p, make_fem, scene, dem, T, models=(bonds,))
        dyn = clock.fem
        sim.counts["law_bonds"] = len(bonds.pairs)
        e_run = clock.energies
    else:
        dyn = make_fem()
        sim = fem_only(dyn, p, T, {})
        e_run = dyn.energies
    contact = contacts[-1] if contacts else None
    if contact is not None:
        def energies():
            e = dict(e_run())
            e["internal"] += contact.stored_energy()
            return e
        sim.energies = energies
    mid = np.abs(X0[0] - L / 2) < 0.5 * np.diff(xs).min()
    point_a = np.flatnonzero(mid & (np.abs(X0[1] - H) < 1e-9 * H))[:1]
    point_b = np.flatnonzero(mid & (X0[1] < 1e-9 * H))[:1]
    lam = laminate(p, p["geometry.laminate"])
    lam.elastic = True
    built = Built(p, mode, lam, 0.5 * L, particle_size(p, g), 1.0, dyn=dyn, fem_elements=region.n_elements,
                  backend=clock.dem if win else None, particles=len(scene.x) if win else 0)
    built.panel = PanelParts(g, dyn, X, X0, right, point_a, point_b, faces, contact, bonds)
    return sim, built


def panel_region(p: dict, g: Panel, win: list):
    """(FemRegion, X0 (2, n) m positions without imperfections, upper (n,) bool nodes of the
    cells above the delamination, xs the mesh's x lines, D (3, 3) Pa): the panel's Quad4 mesh
    on the imperfect geometry, its crack doubled between the tips (fem) or between the DEM
    windows ``win`` [(x_a, x_b)], whose band |y - y_c| < d is left to the particles."""
    L, H, h, yc, x1, x2 = g.L, g.H, g.h, g.yc, g.x1, g.x2
    dx = L / p["mesh.elements_along"]
    d = particle_size(p, g)
    band = d if win else 0.0  # the windows' half-height cut out of the FEM
    xs = np.linspace(0, L, p["mesh.elements_along"] + 1)
    for xa, xb in win:  # the windows' own lines; none closer than half an element to their edges
        xs = xs[(xs < xa - 0.5 * dx) | (xs > xb + 0.5 * dx)]
        xs = np.concatenate([xs, np.linspace(xa, xb, int(np.ceil((xb - xa) / dx - 1e-9)) + 1)])
    if not win:  # the tips on lines: each takes its nearest line's place (no sliver beside a tip)
        for x in (x1, x2):
            xs[1 + np.argmin(np.abs(xs[1:-1] - x))] = x
    xs = np.unique(np.round(xs, 12))
    # through the thickness: the band's rows are FEM outside the windows; the sublaminate
    # keeps its element height above it (a thinner element would lower the FEM's stable step)
    n_film = max(1, int(round(p["mesh.elements_sublaminate"] * (h - band) / h)))
    ys = np.unique(np.concatenate([np.linspace(0, yc - band, p["mesh.elements_base"] + 1), [yc],
                                   np.linspace(yc + band, H, n_film + 1)]))
    tol = 1e-9 * L
    in_window = lambda cx, cy: any(xa - tol < cx < xb + tol for xa, xb in win) and abs(cy - yc) < band
    if win:  # the FEM's crack runs between the windows (its faces' nodes doubled)
        crack = dict(crack_x_min=win[0][1] - 0.5 * d, crack_x_max=win[1][0] + 0.5 * d)
    else:
        crack = dict(crack_x_min=x1, crack_x_max=x2 - 0.5 * np.diff(xs).min())
    m = mesh.cut_rectangle(xs, ys, lambda cx, cy: not in_window(cx, cy), crack_y=yc, **crack)
    X0 = m.p.copy()
    upper = np.zeros(m.p.shape[1], bool)
    upper[np.unique(m.t[:, m.p[1, m.t].mean(axis=0) > yc])] = True
    m = type(m)(imperfect(p, g, X0, upper), m.t)
    C = materials.transversely_isotropic(g.E11, g.E22, g.nu12, g.nu23, g.G12)
    D = materials.reduce(C, 2, p["fem.hypothesis"])
    return make_region(m, p, D, g.rho, g.b), X0, upper, xs, D


def imperfect(p: dict, g: Panel, X: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """(2, n) positions X (2, n) m moved by the imperfections: the panel's clamped first mode of
    geometry.imperfection x H, and the sublaminate's (``upper``) outward bump of the
    delamination's imperfection x h between the tips."""
    L, x1, x2 = g.L, g.x1, g.x2
    pts = X.copy()
    pts[1] += p["geometry.imperfection"] * g.H * 0.5 * (1 - np.cos(2 * np.pi * X[0] / L))
    inside = upper & (X[0] > x1) & (X[0] < x2)
    pts[1, inside] += (p[f"{g.delamination}.imperfection"] * g.h * 0.5
                       * (1 - np.cos(2 * np.pi * (X[0, inside] - x1) / (x2 - x1))))
    return pts


def particle_size(p: dict, g: Panel) -> float:
    """m, zone.particle_size, or (0) two plies, or half the thinner of the sublaminate and the
    base when that is less (the band's four rows, 2 d across the plane, fit in both)."""
    return p["zone.particle_size"] or min(2 * g.tp, 0.5 * min(g.n_sub, g.plies - g.n_sub) * g.tp)


def window_ahead(p: dict, g: Panel) -> float:
    """m, zone.window_ahead, or (0) the intact end x1 less max(3 mm, x1 / 10): the delamination may
    run to the clamps' neighbourhood whatever its length."""
    return p["zone.window_ahead"] or g.x1 - max(3e-3, 0.1 * g.x1)


def windows(p: dict, g: Panel) -> list[tuple[float, float]]:
    """[(x_a, x_b)] m of the two DEM windows, whole particle spacings d, each tip on a column:
    zone.window_ahead into the intact laminate and zone.window_behind into the delamination."""
    x1, x2 = g.x1, g.x2
    d = particle_size(p, g)
    if 2 * d > g.h or 2 * d > g.yc:
        raise CaseError(f"zone.particle_size = {d:g}: the band (four rows, {2 * d:g} m across the plane) needs the "
                        f"sublaminate and the base thicker than it; allowed <= {min(g.h, g.yc) / 2:g} m")
    n_out = max(2, int(round(window_ahead(p, g) / d)))
    n_in = max(2, int(round(p["zone.window_behind"] / d)))
    if x1 - n_out * d < 0.1 * x1 or x1 + n_in * d >= 0.5 * (x1 + x2) - d:
        raise CaseError(f"zone.window_ahead = {p['zone.window_ahead']:g}, zone.window_behind = {p['zone.window_behind']:g}: "
                        f"the windows must stay off the clamps (a tenth of the intact ends) and apart; allowed ahead "
                        f"<= {0.9 * x1:g} m, behind < {0.45 * (x2 - x1):g} m")
    return [(x1 - n_out * d, x1 + n_in * d), (x2 - n_in * d, x2 + n_out * d)]


def window_scene(p: dict, g: Panel, win, D: np.ndarray):
    """(DemScene, LawBonds): the two windows' four-row bands (delamination.band_window) on the
    imperfect geometry, the lattice of the FEM's slice moduli over the panel's width, and the
    laminate's Hashin law across the plane (debonded inside the delamination, finite rotation:
    the tips turn with the panel's bow by more than the film's critical strain)."""
    x1, x2, yc = g.x1, g.x2, g.yc
    r, b, rho = 0.5 * particle_size(p, g), g.b, g.rho
    d = 2 * r
    E_x, E_y, G = slice_moduli(D)
    K = E_y / d
    k = lattice_stiffness(E_x, E_y, G, b)
    parts = [dl.band_window(xa, int(round((xb - xa) / d)), yc, d, k, K * d * b) for xa, xb in win]
    off = np.cumsum([0] + [len(w.x) for w in parts])
    x = np.vstack([w.x for w in parts])
    x[:, :2] = imperfect(p, g, x[:, :2].T, x[:, 1] > yc).T
    cat = lambda f: np.concatenate([f(w, o) for w, o in zip(parts, off)])
    pairs = cat(lambda w, o: w.pairs + o)
    sphere_rho = rho * d**2 * b / (4.0 / 3.0 * np.pi * r**3)  # a particle stands for d x d x the width
    scene = DemScene(x, r, sphere_rho, pairs, kn=cat(lambda w, o: w.kn), ks=0.0, plane=True, young=E_y,
                     groups={"interface": cat(lambda w, o: np.flatnonzero(w.tied) + o)}, placeholder_bonds=False)
    itf = g.interface
    keys = {"Z0": f"{itf}.Z0", "R0": f"{itf}.R0", "GIc": f"{itf}.GIc", "GIIc": f"{itf}.GIIc",
            "E22": f"{g.material}.E22", "N": "zone.cohesive_zone_bonds"}
    Z0, R0 = dl.resolved_strengths(p, d, keys)
    law = HashinCohesiveLaw(K=K, Z0=Z0, R0=R0, GIc=p[f"{itf}.GIc"], GIIc=p[f"{itf}.GIIc"])
    lower, upper = cat(lambda w, o: w.lower + o), cat(lambda w, o: w.upper + o)
    n0 = np.concatenate([[0], np.cumsum([len(w.lower) for w in parts])])
    along = np.vstack([np.where(w.along >= 0, w.along + n0[i], -1) for i, w in enumerate(parts)])
    bonds = LawBonds(np.column_stack([lower, upper]), x, np.tile([0.0, 1.0, 0.0], (len(lower), 1)),
                     cat(lambda w, o: w.share) * d * b, law, friction=p[f"{itf}.friction"], along=along,
                     finite_rotation=True, label="delamination")
    xb = x[lower, 0]
    inside = (xb > x1 + 1e-9 * d) & (xb < x2 - 1e-9 * d)
    bonds.damage[inside], bonds.t_failed[inside] = 1.0, 0.0  # the delamination: faces in contact only
    return scene, bonds


def face_contact(p: dict, g: Panel, dyn: ExplicitDynamics, X0: np.ndarray, upper: np.ndarray) -> LawBonds:
    """Frictionless node-to-node penalty contact across the delamination: each doubled node
    pair on the crack line (lower i, upper j) is a fully debonded Hashin bond, which pushes
    back only in compression, measured from the flat (imperfection-free) faces so the gap is
    the real one. Area: the pair's tributary length x width. Its springs enter the FEM's
    stable step (fem_region.stable_step)."""
    tol = 1e-9 * np.ptp(X0[1])
    on = np.flatnonzero(np.abs(X0[1] - g.yc) < tol)
    xs = np.round(X0[0, on] / tol)
    pairs = []
    for x in np.unique(xs):
        nodes = on[xs == x]
        if len(nodes) == 2:  # doubled: inside the delamination
            lo, up = sorted(nodes, key=lambda k: upper[k])
            pairs.append((lo, up))
    pairs = np.array(sorted(pairs, key=lambda ij: X0[0, ij[0]]), int)
    x = X0[0, pairs[:, 0]]
    edges = np.concatenate([[x[0] - 0.5 * (x[1] - x[0])], 0.5 * (x[1:] + x[:-1]), [x[-1] + 0.5 * (x[-1] - x[-2])]])
    area = np.diff(edges) * g.b
    m_pair = np.minimum(dyn.m[pairs[:, 0]], dyn.m[pairs[:, 1]])  # the penalty no stiffer than the lighter node allows
    dt_elements = dyn.region.critical_dt(dyn.density_scale)
    K = p[f"{g.delamination}.penalty"] or min(g.E22 / (g.h / p["mesh.elements_sublaminate"]),
                                              float(np.min(m_pair / area)) / dt_elements**2)
    # the law's strengths and toughness do not enter: every bond starts fully debonded
    law = HashinCohesiveLaw(K=K, Z0=1.0, R0=1.0, GIc=1.0, GIIc=1.0)
    X3 = np.pad(X0.T, ((0, 0), (0, 1)))
    bonds = LawBonds(pairs, X3, np.tile([0.0, 1.0, 0.0], (len(pairs), 1)), area, law, label="delamination")
    bonds.damage[:] = 1.0
    dyn.node_forces = [FemNodes(dyn).model(bonds, dyn)]
    # the penalty as springs along every axis (it pushes along the normal only: a safe excess)
    dyn.add_springs(pair_springs(dyn.region.n_nodes, dyn.region.dim, pairs, K * area))
    return bonds


# -- probes -----------------------------------------------------------------------------------

def buckling_series(built, name, f) -> dict:
    """N, m, -: the axial force at the moving end, the end shortening, the mid-span deflections of
    the top (A) and bottom (B) faces from the flat geometry, the film's membrane strain; with
    contact, the faces' contact force (N) and deepest overlap (m)."""
    q = getattr(built, "panel", None)
    if q is None:
        return {}
    dyn, X, X0, right, point_a, point_b, faces = q.dyn, q.X, q.X0, q.right, q.point_a, q.point_b, q.faces
    out = {"axial_force": lambda: -float(dyn.f_int[right, 0].sum()) if hasattr(dyn, "f_int") else 0.0,
           "end_shortening": lambda: -float(dyn.state.u[right, 0].mean()),
           "deflection_A": lambda: float(X[point_a, 1][0] + dyn.state.u[point_a, 1][0] - X0[1, point_a][0]),
           "deflection_B": lambda: float(X[point_b, 1][0] + dyn.state.u[point_b, 1][0] - X0[1, point_b][0])}

    def film_strain():
        x = X + dyn.state.u
        arcs = [np.linalg.norm(np.diff(x[f], axis=0), axis=1).sum() for f in faces]
        return float(0.5 * sum(arcs) / (X0[0, faces[0][-1]] - X0[0, faces[0][0]]) - 1.0)
    out["film_strain"] = film_strain
    contact = q.contact
    if contact is not None:  # N, the faces pressed together; m, their deepest overlap
        out["contact_force"] = lambda: float(np.sum(np.maximum(-contact.traction[:, 1], 0.0) * contact.area))
        out["interpenetration"] = lambda: float(max(-contact.delta[:, 1].min(), 0.0))
    return out


def growth_series(built, name, f) -> dict:
    """m, how far each tip has run into the intact laminate (fully debonded pairs beyond it); the
    mode ratio of the bonds softening now; J, the interface's dissipation (the initial
    delamination's bonds start debonded). Coupled runs only."""
    q = getattr(built, "panel", None)
    if q is None or q.bonds is None:
        return {}
    bonds, x1, x2 = q.bonds, q.g.x1, q.g.x2
    xb = bonds.X[bonds.pairs[:, 0], 0]

    def run(side):
        failed = bonds.failed()
        ahead = failed & ((xb < x1) if side < 0 else (xb > x2))
        return float(np.max(np.where(side < 0, x1 - xb, xb - x2)[ahead])) if ahead.any() else 0.0

    def mode_ratio():  # B = G_II / G of the bonds softening now (their separations' mix); -1: none
        soft = (bonds.damage > 0) & ~bonds.failed()
        if not soft.any():
            return -1.0
        dn, ds = bonds.split(bonds.delta)
        s2, n2 = np.sum(ds[soft] ** 2, axis=1), np.maximum(dn[soft], 0.0) ** 2
        return float(np.sum(bonds.area[soft] * s2) / np.sum(bonds.area[soft] * (s2 + n2)))
    return {"growth_left": lambda: run(-1), "growth_right": lambda: run(+1), "tip_mode_ratio": mode_ratio,
            "interface_dissipated": bonds.decohesion_energy}


def film_critical_strain(h: dict, h_sub: float) -> float:
    """The film's critical strain read from the history (buckling.film_critical_strain on the
    opening A - B), up to the sample before a tip has grown by a bond (coupled)."""
    P = np.asarray(h["axial_force"])
    w_open = np.asarray(h["deflection_A"]) - np.asarray(h["deflection_B"])
    tips = np.maximum(h["growth_left"], h["growth_right"]) if "growth_left" in h else np.zeros(len(P))
    moved = np.flatnonzero(np.asarray(tips) > 0)
    return buckling.film_critical_strain(P, w_open, np.asarray(h["film_strain"]), h_sub,
                                         moved[0] - 1 if moved.size else None)


def buckling_qoi(name, f, h, p) -> dict:
    """The buckling loads read from the history (module docstring), the pre-buckling axial
    stiffness, the closed forms no check records, and the tips' energy release rate at the
    limit load (Hutchinson & Suo); nothing when the run has no panel."""
    if "axial_force" not in h:
        return {}
    g = panel_of(p)
    cf = g.loads()
    E, b, H, h_sub = g.E11, g.b, g.H, g.h
    P = np.asarray(h["axial_force"])
    wA, wB = np.asarray(h["deflection_A"]), np.asarray(h["deflection_B"])
    # deflections from the perfect geometry (imperfections included): the sublaminate's
    # opening A - B starts at the local bump, B at the global bow
    w_open, w_glob = wA - wB, wB
    # pre-buckling axial stiffness: the load against the end shortening while the load is
    # below a third of the local closed form (the film still flat)
    u = np.asarray(h["end_shortening"])
    early = (P > 0) & (P < cf["local"] / 3)
    k_axial = float(np.polyfit(u[early], P[early], 1)[0]) if early.sum() >= 3 else float("nan")
    eps_c = film_critical_strain(h, h_sub)
    return {"local_buckling_load": E * H * b * eps_c, "global_buckling_load": float(P.max()),
            "film_critical_strain": eps_c, "local_buckling_load_southwell": buckling.southwell(P, w_open),
            "global_buckling_load_southwell": buckling.southwell(P, w_glob),
            "axial_stiffness": k_axial, "peak_axial_force": float(P.max()),
            "closed_form_local_clamped": cf["local_clamped"],
            "max_interpenetration": float(np.max(h["interpenetration"])) if "interpenetration" in h else float("nan"),
            "closed_form_global_intact": cf["global_intact"], "closed_form_global_intact_shear": cf["global_intact_shear"],
            "tip_energy_release_rate": buckling.hutchinson_suo(E, h_sub, eps_c, buckling.base_strain(
                float(P.max()), E, H, h_sub, b, eps_c))}


def growth_qoi(name, f, h, p) -> dict:
    """Delamination growth in the DEM windows: lengths, the onset (a tip two bonds beyond its
    start), the mode mix of the softening bonds then, and the onset Hutchinson & Suo predict
    for a film buckled at its measured critical strain with the B-K toughness of that mix."""
    if "growth_left" not in h:
        return {}
    g = panel_of(p)
    E, b, H, h_sub, l, d = g.E11, g.b, g.H, g.h, g.l, particle_size(p, g)
    P = np.asarray(h["axial_force"])
    eps_film = film_critical_strain(h, h_sub)
    gl, gr = np.asarray(h["growth_left"]), np.asarray(h["growth_right"])
    k = int(np.argmax(P))
    grown = np.flatnonzero(np.maximum(gl, gr) >= 2 * d - 1e-9 * d)
    B = np.asarray(h["tip_mode_ratio"])
    itf = section(p, g.interface)
    law = HashinCohesiveLaw(K=1.0, Z0=1.0, R0=1.0, GIc=itf["GIc"], GIIc=itf["GIIc"])
    out = {"delamination_growth_left": float(gl[-1]), "delamination_growth_right": float(gr[-1]),
           "delamination_length_final": float(l + gl[-1] + gr[-1]),
           "delamination_length_at_limit_load": float(l + gl[k] + gr[k]),
           "growth_onset_load": float("nan"), "growth_mode_ratio": float("nan"),
           "closed_form_growth_onset_load": float("nan"),
           "interface_dissipated": float(np.asarray(h["interface_dissipated"])[-1])}
    # the window's last column is tied to intact FEM: a tip can run (n_out - 1) spacings; the
    # intact end left beyond that, from the clamp
    room = (int(round(window_ahead(p, g) / d)) - 1) * d
    out["growth_room"] = room
    out["growth_reached_window_edge"] = float(max(gl.max(), gr.max()) >= room - 1e-9 * d)
    out["intact_end_beyond_window"] = float(0.5 * (g.L - l) - room - d)
    new_area = b * (gl[-1] + gr[-1])
    if grown.size:
        # Hutchinson & Suo's onset on the measured path: the first sample where the film's G
        # reaches the toughness of the mix the softening bonds carry then
        Gc = np.where(B >= 0, law.toughness(np.clip(B, 0.0, 1.0)), np.nan)
        i, P_onset = buckling.growth_onset_on_path(E, b, H, h_sub, eps_film, P, Gc)
        out.update({"growth_onset_load": float(P[grown[0]]), "growth_mode_ratio": float(B[i]) if i >= 0 else float("nan"),
                    "growth_toughness": float(Gc[i]) if i >= 0 else float("nan"),
                    "closed_form_growth_onset_load": P_onset,
                    "dissipated_per_new_area": out["interface_dissipated"] / new_area})
    return out


# -- closed forms (study/closed_forms.py registers them) ----------------------------------------

def axial_stiffness(study, p: dict, f: dict, qoi: dict) -> float:
    """N/m, E11 H b / L."""
    g = panel_of(p)
    return g.E11 * g.H * g.b / g.L


def film_buckling_load(study, p: dict, f: dict, qoi: dict) -> float:
    """N, the panel load at which the film buckles (buckling.panel_loads' local)."""
    return panel_of(p).loads()["local"]


def stepped_column_buckling_load(study, p: dict, f: dict, qoi: dict) -> float | tuple[float, float]:
    """N, the delaminated panel's limit load (buckling.panel_loads' global). When the
    delamination grew before the limit load (coupled), the bracket of the stepped column's loads
    for its length at the limit load and its initial length: a delamination still running at
    the limit leaves the panel above the column load of its current length (it has not yet
    bowed out to it; the load falls to it once the tips stop), one that stopped before leaves it
    at or below (an imperfect column)."""
    g = panel_of(p)
    l_limit = qoi.get("delamination_length_at_limit_load", g.l)
    if l_limit > g.l:
        return g.loads(l_limit)["global"], g.loads()["global"]
    return g.loads()["global"]


def growth_onset(study, p: dict, f: dict, qoi: dict) -> float | None:
    """N, Hutchinson & Suo's onset for the measured critical strain and mode mix; None (no
    check) when the delamination did not grow."""
    grown = qoi.get("delamination_growth_left", 0.0) + qoi.get("delamination_growth_right", 0.0) > 0
    return qoi["closed_form_growth_onset_load"] if grown else None


def window_room(study, p: dict, f: dict, qoi: dict) -> tuple[float, float] | None:
    """(0, 0): the delamination stopped inside the windows; (0, 1) when they reach the clamps'
    neighbourhood (a fifth of the intact end: the tips then ran into the clamps, not into the
    windows' ends); None (no check) when it did not grow."""
    if growth_onset(study, p, f, qoi) is None:
        return None
    g = panel_of(p)
    near_clamp = qoi["intact_end_beyond_window"] <= 0.2 * 0.5 * (g.L - g.l)
    return (0.0, 1.0) if near_clamp else (0.0, 0.0)


def toughness_range(study, p: dict, f: dict, qoi: dict) -> tuple[float, float] | None:
    """J/m^2, (GIc, GIIc) of the laminate's interface: the B-K toughness of any mode mix lies
    between; None (no check) when the delamination did not grow."""
    if growth_onset(study, p, f, qoi) is None:
        return None
    itf = section(p, panel_of(p).interface)
    return itf["GIc"], itf["GIIc"]


# -- plots ------------------------------------------------------------------------------------

def plot(p: dict, h: dict, qoi: dict, plots_dir) -> None:
    """load_deflection.png (deflections, the film's strain and, coupled, the growth against the
    load) and buckling_loads.md."""
    import matplotlib.pyplot as plt
    if "axial_force" not in h:
        return
    g = panel_of(p)
    P = np.asarray(h["axial_force"]) / 1e3
    growth = "growth_left" in h
    fig, ax = plt.subplots(1, 3 if growth else 2, figsize=(15 if growth else 10, 4))
    ax[0].plot(1e3 * np.asarray(h["deflection_A"]), P, label="A (film, top)")
    ax[0].plot(1e3 * np.asarray(h["deflection_B"]), P, label="B (base, bottom)")
    for key, ls, label in (("local", "--", "local: thin film"), ("global", ":", "global: delaminated column"),
                           ("global_intact", "-.", "intact panel (Euler)")):
        if f"closed_form_{key}" in qoi:
            ax[0].axhline(qoi[f"closed_form_{key}"] / 1e3, color="k", ls=ls, lw=0.8, label=label)
    ax[0].set(xlabel="lateral deflection (mm)", ylabel="axial load (kN)", title="delaminated panel")
    ax[0].legend()
    ax[1].plot(-1e3 * np.asarray(h["film_strain"]), P, label="film, membrane strain")
    if "closed_form_local" in qoi:
        ax[1].axvline(1e3 * qoi["closed_form_local"] / (g.E11 * g.H * g.b), color="k", ls="--", lw=0.8,
                      label="thin-film critical strain")
    ax[1].set(xlabel="compressive strain (1e-3)", ylabel="axial load (kN)")
    ax[1].legend()
    if growth:  # the delamination's growth at each tip against the load
        u = 1e3 * np.asarray(h["end_shortening"])
        for key, label in (("growth_left", "left tip"), ("growth_right", "right tip")):
            ax[2].plot(u, 1e3 * np.asarray(h[key]), label=label)
        ax[2].axhline(1e3 * qoi["growth_room"], color="k", ls=":", lw=0.8, label="end of the DEM window")
        ax2 = ax[2].twinx()
        ax2.plot(u, P, color="0.6", lw=0.8)
        ax2.set_ylabel("axial load (kN)", color="0.4")
        ax[2].set(xlabel="end shortening (mm)", ylabel="delamination growth (mm)", title="growth (DEM windows)")
        ax[2].legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(plots_dir / "load_deflection.png", dpi=120)
    plt.close(fig)
    (plots_dir / "buckling_loads.md").write_text(buckling_table(qoi))


def buckling_table(qoi: dict) -> str:
    """Markdown: the seed's, the reference study's, the closed-form and this run's buckling loads."""
    kN = lambda key: f"{qoi[key] / 1e3:.2f}" if key in qoi and np.isfinite(qoi[key]) else "-"
    rows = [("local (film)", "seed_local", "reference_local", "closed_form_local", "local_buckling_load"),
            ("global (panel)", "seed_global", "reference_global", "closed_form_global", "global_buckling_load")]
    lines = ["| buckling load (kN) | seed paper | reference (Perugini et al. 1999) | closed form, this geometry "
             "| this run |", "|---|---|---|---|---|"]
    lines += [f"| {name} | " + " | ".join(kN(k) for k in keys) + " |" for name, *keys in rows]
    lines.append(f"| local, rigid clamps at the tips | | | {kN('closed_form_local_clamped')} | |")
    lines.append(f"| global, intact panel (Euler; with shear) | | | {kN('closed_form_global_intact')}; "
                 f"{kN('closed_form_global_intact_shear')} | |")
    if "growth_onset_load" in qoi:
        lines.append(f"| delamination growth onset (Hutchinson & Suo) | | | {kN('closed_form_growth_onset_load')} "
                     f"| {kN('growth_onset_load')} |")
    return "\n".join(lines) + "\n"
