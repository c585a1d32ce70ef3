"""panel_buckling: the seed paper's example 5.2, a [0_20] panel with a through-width
delamination between the 0_4 and 0_16 sublaminates under slow axial compression, clamped
ends, geometrically nonlinear (Total Lagrangian FEM), quasi-static by slow end shortening
(``load.duration_periods`` periods of the panel's first mode, sin^2 ramp) with mass damping at
2 omega_1 (as column_buckling).

Dimensions (not in the paper; chosen so the closed forms land at the reference study's loads,
Perugini et al. 1999: 5.8 / 34.8 kN): ply 0.127 mm (panel H = 2.54 mm), width 25.4 mm,
free length L = 74 mm between the clamps, delamination l = 36 mm centred, 0_4 on top.
The delamination is a crack in the mesh (nodes doubled along it between its tips) whose faces
touch through frictionless node-to-node penalty contact (``interface.contact``: fully debonded
Hashin bonds, LawBonds on the FEM nodes as in rod_impact); the sublaminate starts with an
outward bump of local.imperfection x h and the panel with the clamped first mode of
global.imperfection x H.

Closed forms (from the run's parameters):
- local: the clamped thin film buckles at eps_c = (pi^2 / 3) (h / l)^2 (Chai, Babcock & Knauss
  1981), i.e. at the panel load P_local = E11 H b eps_c (uniform strain before buckling).
  Its tips are not rigid clamps: the laminate ahead of each tip lets the film's end turn, as
  it lets a DCB arm's root turn. The check takes the film lengthened by corrected beam theory's
  crack-length correction chi h at each tip (Hashemi, Kinloch & Williams 1990; chi = 1.81 for
  Table 2's ply, a 10 % lower load) and Engesser's shear flexibility (2 %):
  eps_c = e / (1 + E11 e / (kappa G12)), e = (pi^2 / 3) (h / (l + 2 chi h))^2. The rigid-clamp
  value is reported beside it (``closed_form_local_clamped``). Measured on the full mesh,
  all-FEM, ramps of 32 / 64 / 128 periods: 5.62 / 5.41 / 5.30 kN, approaching the corrected
  5.23 kN as the ramp slows (the rigid-clamp 5.88 kN is left behind);
- global: once the film has buckled it holds about its critical force and the 0_16 base alone
  bends in the middle half. The panel then buckles as a clamped stepped column (Timoshenko &
  Gere 2.10: intact ends EI(H), the base EI(H - h) in the middle carrying P minus the film's
  force), with Engesser's shear flexibility (kappa G12 A, kappa = 5/6; E11 / G12 = 25 makes it a
  10 % effect). The intact panel's Euler load 4 pi^2 E11 I / L^2 (34.8 kN, 31.1 kN with shear)
  is reported beside it: with the reference loads' ratio the delamination spans half the free
  length (P_global / P_local = 25 (l / L)^2 for a 4 / 20 sublaminate gives l / L = 0.49), and
  a panel whose middle half has lost the film's bending stiffness does not reach it (measured:
  the base bends away from the buckled film, the opening mode; the faces never touch).
Readings (no reference enters them): local, the film's membrane strain (mean of its two faces'
arc lengths over l) at its least compression after it has opened by more than h, times
E11 H b; global, the panel's limit load (the largest axial force: an eccentrically loaded
column has a limit point, not a bifurcation). Southwell's fits on the opening A - B and on the
base deflection B are reported too (the film's and the base's growth are not an ideal strut's,
so they read 30 % high and 10 % low). The tips' energy release rate at the limit load comes
from Hutchinson & Suo; growth itself is not modelled (Table 2 gives no toughness).

The film's membrane strain is read over a gauge that stops zone.window_behind short of each
tip (the same in both modes; near the tips the film is not yet free).

Modes: ``fem`` (the delamination cannot grow) and ``coupled``: a DEM window at each tip, the
four-row band of delamination.py across the delamination plane (particle spacing d = 2 r =
two plies; the FEM above and below it tied to the outer rows), zone.window_behind into the
delamination and zone.window_ahead into the intact laminate. Across the plane the seed's
Hashin law with linear softening (Z0, R0 of Table 2; Gc not in Table 2: Table 1's
graphite/epoxy GIc = 147, GIIc = 526 J/m^2, B-K), debonded inside the delamination (contact
only), intact ahead, in corotated kinematics (LawBonds finite_rotation): the panel's bow turns
the tips by 0.04-0.11 rad, whose theta^2 / 2 is the film's critical strain. The delamination
grows from both tips once the energy release rate of the buckled film reaches the mixed-mode
toughness; the growth onset is checked against Hutchinson & Suo with the measured mode mix,
the global load against the stepped column with the delamination length at the limit load.
Measured (2026-12-02): README table; a faster ramp reads the film higher (the snap lags the
ramp: 5.62 / 5.41 / 5.30 kN at 32 / 64 / 128 periods, full mesh, all-FEM).
"""
from __future__ import annotations

import numpy as np

from physics.law_bonds import LawBonds
from physics.laws import HashinCohesiveLaw
from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from fem_region.modal import lowest_modes

from ..checks import bound, check, within
from ..params import density, modulus, Param, positive
from . import delamination as dl
from ..participants.fem import FEM_OPTIONS, FemNodes, fem_only, make_region
from ..participants.coupled import COUPLING, coupled_simulation

NAME = "panel_buckling"
DESCRIPTION = "seed 5.2: delaminated [0_20] panel, local and global buckling loads vs closed forms"
MODES = ("fem", "coupled")
PARAMETERS = {
    "material.E11": modulus(139.2e9, "ply modulus along the fibres (Table 2)"),
    "material.E22": modulus(9.72e9, "transverse ply modulus (Table 2)"),
    "material.G12": modulus(5.5e9, "in-plane shear modulus (not in Table 2; AS4-type value)"),
    "material.nu12": Param(0.29, "Poisson ratio (Table 2)", low=0.0, high=0.49),
    "material.rho": density(1600.0, "ply density (not in Table 2)"),
    "geometry.ply_thickness": positive(0.127e-3, "ply thickness", "m"),
    "geometry.width": positive(25.4e-3, "panel width b", "m"),
    "geometry.length": positive(74e-3, "free length L between the clamped ends", "m"),
    "geometry.delamination_length": positive(36e-3, "delamination length l (centred)", "m"),
    "geometry.sublaminate_plies": Param(4, "plies above the delamination", kind="int", low=1, high=19),
    "geometry.plies": Param(20, "plies in the panel", kind="int", low=2, high=200),
    "local.imperfection": Param(0.02, "initial outward bump of the sublaminate / its thickness", low=1e-4, high=1.0),
    "global.imperfection": Param(0.02, "initial first-mode bow of the panel / its thickness", low=1e-4, high=1.0),
    "load.shortening_factor": Param(1.6, "final shortening / the intact panel's Euler shortening P_euler L / (E A)",
                                    low=1.1, high=5.0),
    # the film's snap lags a fast ramp: its reading fell 4 % from 32 to 64 periods and 2 % more
    # at 128 (full mesh, all-FEM); 64 is within 2 % of the slowest
    "load.duration_periods": Param(64.0, "loading time in periods of the panel's first mode", low=2.0),
    "interface.contact": Param(True, "frictionless penalty contact between the delaminated faces "
                               "(no interpenetration)", kind="bool"),
    "interface.penalty": Param(0.0, "contact stiffness per area; 0 = E22 / (sublaminate element height), "
                               "softened so that it does not lower the elements' stable step", unit="Pa/m", low=0.0),
    # the delamination's growth (coupled mode): Table 2 gives the strengths, no toughness
    "interface.Z0": positive(40e6, "interlaminar normal strength (Table 2)", "Pa"),
    "interface.R0": positive(20e6, "interlaminar shear strength (Table 2)", "Pa"),
    "interface.GIc": Param(147.0, "mode I toughness (not in Table 2: Table 1's graphite/epoxy)", unit="J/m^2",
                           low=0.0, open_low=True),
    "interface.GIIc": Param(526.0, "mode II toughness (not in Table 2: Table 1's graphite/epoxy)", unit="J/m^2",
                            low=0.0, open_low=True),
    "interface.eta": Param(2.284, "B-K (or power-law) exponent", low=0.5, high=10.0),
    "interface.mixed_mode": Param("bk", "mixed-mode criterion", kind="str", choices=("bk", "power")),
    "interface.cohesive_zone_bonds": Param(20.0, "fewest bonds in the cohesive zone (strengths lowered to "
                                           "sqrt(9 pi E22 Gc / (32 N d)), Turon et al. 2007); 0 keeps them",
                                           low=0.0, high=50.0),
    "interface.friction": Param(0.0, "Coulomb friction of the delaminated faces in the DEM windows", low=0.0,
                                high=2.0),
    "zone.particle_size": Param(0.0, "DEM particle size d (coupled mode; the lattice spacing); 0: two plies, or "
                                "half the thinner sublaminate if less (the band's four rows fit)", unit="m",
                                low=0.0, plausible=(0.0, 1.0)),
    "zone.window_ahead": Param(0.0, "DEM window ahead of each tip, into the intact laminate (room to grow); 0: the "
                               "intact end less max(3 mm, a tenth of it), the room to the clamps (16 mm on the "
                               "default panel: with Table 1's toughness the delamination runs from the limit load "
                               "through a 14 mm window)", unit="m", low=0.0),
    # behind the tip the window holds the film's lower half as two particle rows: 2 mm of it
    # made the film's clamped ends 3 % softer (coupled elastic 5.75 kN against all-FEM 5.94 kN
    # on the coarse mesh; 0.5 mm: 5.94 against 5.97 kN)
    "zone.window_behind": positive(0.5e-3, "DEM window behind each tip, inside the delamination; also where the "
                                  "film strain gauge stops short of the tips (both modes)", "m"),
    **COUPLING,
    "mesh.elements_along": Param(148, "elements along the panel", kind="int", low=20),
    "mesh.elements_sublaminate": Param(3, "elements through the sublaminate", kind="int", low=1, high=20),
    "mesh.elements_base": Param(6, "elements through the base laminate", kind="int", low=1, high=40),
    **{**{k: v for k, v in FEM_OPTIONS.items() if k != "mesh.element"},
       "fem.formulation": Param("total_lagrangian", "internal force path", kind="str",
                                choices=("total_lagrangian", "linear"))},
}


def closed_forms(p: dict) -> dict:
    """N: local (thin film: with its tips' root rotation and shear, and with rigid clamps),
    global of the intact panel (Euler) and global of the delaminated panel once the film has
    buckled (stepped column)."""
    E, b, tp = p["material.E11"], p["geometry.width"], p["geometry.ply_thickness"]
    H, h = p["geometry.plies"] * tp, p["geometry.sublaminate_plies"] * tp
    l, L = p["geometry.delamination_length"], p["geometry.length"]
    kG = 5.0 / 6.0 * p["material.G12"]  # Pa, Engesser's shear flexibility (kappa = 5/6)
    eps_clamped = np.pi**2 / 3 * (h / l) ** 2
    # the film's ends turn as a DCB arm's root does: each tip moves chi h into the laminate
    e_root = np.pi**2 / 3 * (h / (l + 2 * dl.chi({**p, "material.G13": p["material.G12"]}) * h)) ** 2
    eps_c = e_root / (1 + E * e_root / kG)
    euler = 4 * np.pi**2 * E * (b * H**3 / 12) / L**2
    kGA = kG * b  # N per unit thickness
    return {"local": E * H * b * eps_c, "local_clamped": E * H * b * eps_clamped,
            "global_intact": euler, "global_intact_shear": euler / (1 + euler / (kGA * H)),
            "global": stepped_column_load(E * b * H**3 / 12, E * b * (H - h) ** 3 / 12, L, l, E * h * b * eps_c, euler,
                                          kGA * H, kGA * (H - h))}


def stepped_column_load(EI1: float, EI2: float, L: float, l: float, P_film: float, P_max: float,
                        kGA1: float = np.inf, kGA2: float = np.inf) -> float:
    """N, symmetric buckling load of a clamped-clamped stepped column (Timoshenko & Gere,
    Theory of Elastic Stability, 2.10): ends of length (L - l) / 2 and bending stiffness EI1
    (N m^2) carrying P, a middle part of length l and stiffness EI2 (the base sublaminate)
    carrying P - P_film (the buckled film holds its critical force P_film and no lateral
    load). Shear flexibility by Engesser: each part's wave number k^2 = N / (EI (1 - N / kGA))
    with kGA (N) its shear stiffness (for a uniform column P = P_E / (1 + P_E / kGA)). The
    lowest root in (P_film, P_max) of the determinant of the support and continuity
    conditions, bracketed on a grid; nan if none."""
    from scipy.optimize import brentq
    a = 0.5 * (L - l)

    def det(P):
        k1 = np.sqrt(P / (EI1 * (1 - P / kGA1)))
        k2 = np.sqrt((P - P_film) / (EI2 * (1 - (P - P_film) / kGA2)))
        c1, s1, c2, s2 = np.cos(k1 * a), np.sin(k1 * a), np.cos(k2 * (a - L / 2)), np.sin(k2 * (a - L / 2))
        # end part: w = A + B x + C cos k1 x + D sin k1 x; middle (symmetric): w = A2 + C2 cos k2 (x - L/2)
        return np.linalg.det(np.array([
            [1, 0, 1, 0, 0, 0],  # w(0) = 0
            [0, 1, 0, k1, 0, 0],  # w'(0) = 0
            [1, a, c1, s1, -1, -c2],  # w continuous at x = a
            [0, 1, -k1 * s1, k1 * c1, 0, k2 * s2],  # slope
            [0, 0, -EI1 * k1**2 * c1, -EI1 * k1**2 * s1, 0, EI2 * k2**2 * c2],  # moment EI w"
            [0, 1, 0, 0, 0, 0],  # shear: EI w""" + N w' is P B at the ends, 0 in the middle
        ], float))

    P = np.linspace(max(1.001 * P_film, 1e-3 * P_max), min(P_max, 0.999 * kGA1, P_film + 0.999 * kGA2), 2000)
    d = np.array([det(x) for x in P])
    k = np.flatnonzero(np.sign(d[:-1]) != np.sign(d[1:]))
    return float(brentq(det, P[k[0]], P[k[0] + 1])) if k.size else float("nan")


def build(p: dict, mode: str, dem: str):
    from ..params import CaseError
    tp, L, l = p["geometry.ply_thickness"], p["geometry.length"], p["geometry.delamination_length"]
    n_sub = p["geometry.sublaminate_plies"]
    if n_sub >= p["geometry.plies"]:
        raise CaseError(f"geometry.sublaminate_plies = {n_sub}: allowed below geometry.plies = {p['geometry.plies']}")
    if not l < 0.9 * L:
        raise CaseError(f"geometry.delamination_length = {l:g}: allowed below 0.9 x geometry.length = {0.9 * L:g} m")
    H, h = p["geometry.plies"] * tp, n_sub * tp
    yc = H - h  # the delamination plane
    x1, x2 = 0.5 * (L - l), 0.5 * (L + l)
    win = windows(p, x1, x2, h, yc) if mode == "coupled" else []
    region, X0, upper, xs, D = panel_region(p, win)
    X = region.X
    left = np.flatnonzero(X[:, 0] < 1e-9 * L)
    right = np.flatnonzero(X[:, 0] > L * (1 - 1e-9))
    clamp = np.concatenate([left * 2, left * 2 + 1, right * 2 + 1])
    # the panel's first mode on the whole FEM panel (with windows cut out, the thin FEM strips
    # over them have modes of their own, far below the panel's)
    whole = region if not win else panel_region(p, [])[0]
    ends = lambda r, c: np.flatnonzero(np.abs(r.X[:, 0] - c) < 1e-9 * L)
    fixed = np.concatenate([ends(whole, 0) * 2, ends(whole, 0) * 2 + 1, ends(whole, L) * 2, ends(whole, L) * 2 + 1])
    omega1 = lowest_modes(whole, fixed, whole.mass)[0][0]
    T = p["load.duration_periods"] * 2 * np.pi / omega1
    cf = closed_forms(p)
    total = p["load.shortening_factor"] * cf["global_intact"] * L / (p["material.E11"] * H * p["geometry.width"])
    speed = lambda t: -2 * total / T * np.sin(np.pi * t / T) ** 2 if t < T else 0.0  # integrates to -total
    contacts = []

    def make_fem(extra_mass=None):
        dyn = ExplicitDynamics(region, supports=[PrescribedMotion(clamp), PrescribedMotion(right * 2, speed)],
                               alpha=2 * omega1, extra_mass=extra_mass)
        if p["interface.contact"]:
            contacts.append(face_contact(p, dyn, X0, upper, yc, h))
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
        scene, bonds = window_scene(p, win, D, x1, x2, yc, H, h)
        sim, clock = coupled_simulation(p, make_fem, scene, dem, T, models=(bonds,))
        dyn = clock.fem
    else:
        dyn = make_fem()
    contact = contacts[-1] if contacts else None
    mid = np.abs(X0[0] - L / 2) < 0.5 * np.diff(xs).min()
    point_a = np.flatnonzero(mid & (np.abs(X0[1] - H) < 1e-9 * H))[:1]
    point_b = np.flatnonzero(mid & (X0[1] < 1e-9 * H))[:1]
    probes = {"axial_force": lambda: -float(dyn.f_int[right, 0].sum()) if hasattr(dyn, "f_int") else 0.0,
              "end_shortening": lambda: -float(dyn.state.u[right, 0].mean()),
              "deflection_A": lambda: float(X[point_a, 1][0] + dyn.state.u[point_a, 1][0] - X0[1, point_a][0]),
              "deflection_B": lambda: float(X[point_b, 1][0] + dyn.state.u[point_b, 1][0] - X0[1, point_b][0])}

    def film_strain():
        x = X + dyn.state.u
        arcs = [np.linalg.norm(np.diff(x[f], axis=0), axis=1).sum() for f in faces]
        return float(0.5 * sum(arcs) / (X0[0, faces[0][-1]] - X0[0, faces[0][0]]) - 1.0)
    probes["film_strain"] = film_strain
    if contact is not None:  # N, the faces pressed together; m, their deepest overlap
        probes["contact_force"] = lambda: float(np.sum(np.maximum(-contact.traction[:, 1], 0.0) * contact.area))
        probes["interpenetration"] = lambda: float(max(-contact.delta[:, 1].min(), 0.0))
    if bonds is not None:
        probes.update(growth_probes(bonds, x1, x2))
        sim.probes.update(probes)
        sim.counts["law_bonds"] = len(bonds.pairs)
        e_run = clock.energies
    else:
        sim = fem_only(dyn, p, T, probes)
        e_run = dyn.energies
    if contact is not None:
        def energies():
            e = dict(e_run())
            e["internal"] += contact.stored_energy()
            return e
        sim.energies = energies
    return sim


def panel_region(p: dict, win: list):
    """(FemRegion, X0 (2, n) m positions without imperfections, upper (n,) bool nodes of the
    cells above the delamination, xs the mesh's x lines, D (3, 3) Pa): the panel's Quad4 mesh
    on the imperfect geometry, its crack doubled between the tips (fem) or between the DEM
    windows ``win`` [(x_a, x_b)], whose band |y - y_c| < d is left to the particles."""
    tp, L, l = p["geometry.ply_thickness"], p["geometry.length"], p["geometry.delamination_length"]
    H, h = p["geometry.plies"] * tp, p["geometry.sublaminate_plies"] * tp
    yc, x1, x2 = H - h, 0.5 * (L - l), 0.5 * (L + l)
    dx = L / p["mesh.elements_along"]
    d = particle_size(p)
    band = d if win else 0.0  # the windows' half-height cut out of the FEM
    xs = np.linspace(0, L, p["mesh.elements_along"] + 1)
    for xa, xb in win:  # the windows' own lines; none closer than half an element to their edges
        xs = xs[(xs < xa - 0.5 * dx) | (xs > xb + 0.5 * dx)]
        xs = np.concatenate([xs, np.linspace(xa, xb, int(np.ceil((xb - xa) / dx - 1e-9)) + 1)])
    xs = np.unique(np.round(np.concatenate([xs, [] if win else [x1, x2]]), 12))  # the tips on lines
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
    m = type(m)(imperfect(p, X0, upper, x1, x2, H, h), m.t)
    C = materials.transversely_isotropic(p["material.E11"], p["material.E22"], p["material.nu12"], 0.4,
                                         p["material.G12"])
    D = materials.reduce(C, 2, p["fem.hypothesis"])
    return make_region(m, p, D, p["material.rho"], p["geometry.width"]), X0, upper, xs, D


def imperfect(p: dict, X: np.ndarray, upper: np.ndarray, x1: float, x2: float, H: float, h: float) -> np.ndarray:
    """(2, n) positions X (2, n) m moved by the imperfections: the panel's clamped first mode of
    global.imperfection x H, and the sublaminate's (``upper``) outward bump of
    local.imperfection x h between the tips."""
    L = p["geometry.length"]
    pts = X.copy()
    pts[1] += p["global.imperfection"] * H * 0.5 * (1 - np.cos(2 * np.pi * X[0] / L))
    inside = upper & (X[0] > x1) & (X[0] < x2)
    pts[1, inside] += p["local.imperfection"] * h * 0.5 * (1 - np.cos(2 * np.pi * (X[0, inside] - x1) / (x2 - x1)))
    return pts


def particle_size(p: dict) -> float:
    """m, zone.particle_size, or (0) two plies, or half the thinner of the sublaminate and the
    base when that is less (the band's four rows, 2 d across the plane, fit in both)."""
    tp, n, n_sub = p["geometry.ply_thickness"], p["geometry.plies"], p["geometry.sublaminate_plies"]
    return p["zone.particle_size"] or min(2 * tp, 0.5 * min(n_sub, n - n_sub) * tp)


def window_ahead(p: dict) -> float:
    """m, zone.window_ahead, or (0) the intact end x1 less max(3 mm, x1 / 10): the delamination may
    run to the clamps' neighbourhood whatever its length."""
    x1 = 0.5 * (p["geometry.length"] - p["geometry.delamination_length"])
    return p["zone.window_ahead"] or x1 - max(3e-3, 0.1 * x1)


def windows(p: dict, x1: float, x2: float, h: float, yc: float) -> list[tuple[float, float]]:
    """[(x_a, x_b)] m of the two DEM windows, whole particle spacings d, each tip on a column:
    zone.window_ahead into the intact laminate and zone.window_behind into the delamination."""
    from ..params import CaseError
    d = particle_size(p)
    if 2 * d > h or 2 * d > yc:
        raise CaseError(f"zone.particle_size = {d:g}: the band (four rows, {2 * d:g} m across the plane) needs the "
                        f"sublaminate and the base thicker than it; allowed <= {min(h, yc) / 2:g} m")
    n_out = max(2, int(round(window_ahead(p) / d)))
    n_in = max(2, int(round(p["zone.window_behind"] / d)))
    if x1 - n_out * d < 0.1 * x1 or x1 + n_in * d >= 0.5 * (x1 + x2) - d:
        raise CaseError(f"zone.window_ahead = {p['zone.window_ahead']:g}, zone.window_behind = {p['zone.window_behind']:g}: "
                        f"the windows must stay off the clamps (a tenth of the intact ends) and apart; allowed ahead "
                        f"<= {0.9 * x1:g} m, behind < {0.45 * (x2 - x1):g} m")
    return [(x1 - n_out * d, x1 + n_in * d), (x2 - n_in * d, x2 + n_out * d)]


def window_scene(p: dict, win, D: np.ndarray, x1: float, x2: float, yc: float, H: float, h: float):
    """(DemScene, LawBonds): the two windows' four-row bands (delamination.band_window) on the
    imperfect geometry, the lattice of the FEM's slice moduli over the panel's width, and the
    seed's Hashin law across the plane (debonded inside the delamination, finite rotation: the
    tips turn with the panel's bow by more than the film's critical strain)."""
    from dem_region.ply_lattice import lattice_stiffness, slice_moduli
    from dem_region.scene import DemScene
    r, b, rho = 0.5 * particle_size(p), p["geometry.width"], p["material.rho"]
    d = 2 * r
    E_x, E_y, G = slice_moduli(D)
    K = E_y / d
    k = lattice_stiffness(E_x, E_y, G, b)
    parts = [dl.band_window(xa, int(round((xb - xa) / d)), yc, d, k, K * d * b) for xa, xb in win]
    off = np.cumsum([0] + [len(w.x) for w in parts])
    x = np.vstack([w.x for w in parts])
    x[:, :2] = imperfect(p, x[:, :2].T, x[:, 1] > yc, x1, x2, H, h).T
    cat = lambda f: np.concatenate([f(w, o) for w, o in zip(parts, off)])
    pairs = cat(lambda w, o: w.pairs + o)
    sphere_rho = rho * d**2 * b / (4.0 / 3.0 * np.pi * r**3)  # a particle stands for d x d x the width
    scene = DemScene(x, r, sphere_rho, pairs, kn=cat(lambda w, o: w.kn), ks=0.0, plane=True, young=E_y,
                     groups={"interface": cat(lambda w, o: np.flatnonzero(w.tied) + o)}, placeholder_bonds=False)
    Z0, R0 = dl.resolved_strengths(p, d)
    law = HashinCohesiveLaw(K=K, Z0=Z0, R0=R0, GIc=p["interface.GIc"], GIIc=p["interface.GIIc"],
                            eta=p["interface.eta"], mixed_mode=p["interface.mixed_mode"])
    lower, upper = cat(lambda w, o: w.lower + o), cat(lambda w, o: w.upper + o)
    n0 = np.concatenate([[0], np.cumsum([len(w.lower) for w in parts])])
    along = np.vstack([np.where(w.along >= 0, w.along + n0[i], -1) for i, w in enumerate(parts)])
    bonds = LawBonds(np.column_stack([lower, upper]), x, np.tile([0.0, 1.0, 0.0], (len(lower), 1)),
                     cat(lambda w, o: w.share) * d * b, law, friction=p["interface.friction"], along=along,
                     finite_rotation=True, label="delamination")
    xb = x[lower, 0]
    inside = (xb > x1 + 1e-9 * d) & (xb < x2 - 1e-9 * d)
    bonds.damage[inside], bonds.t_failed[inside] = 1.0, 0.0  # the delamination: faces in contact only
    return scene, bonds


def growth_probes(bonds: LawBonds, x1: float, x2: float) -> dict:
    """m, how far each tip has run into the intact laminate (fully debonded pairs beyond it),
    and J, the interface's dissipation (the initial delamination's bonds start debonded)."""
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
            "interface_dissipated": bonds.dissipated_energy}


def face_contact(p: dict, dyn: ExplicitDynamics, X0: np.ndarray, upper: np.ndarray, yc: float,
                 h: float) -> LawBonds:
    """Frictionless node-to-node penalty contact across the delamination: each doubled node
    pair on the crack line (lower i, upper j) is a fully debonded Hashin bond, which pushes
    back only in compression, measured from the flat (imperfection-free) faces so the gap is
    the real one. Area: the pair's tributary length x width. Sets the FEM's extra stable step."""
    tol = 1e-9 * np.ptp(X0[1])
    on = np.flatnonzero(np.abs(X0[1] - yc) < tol)
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
    area = np.diff(edges) * p["geometry.width"]
    m_pair = np.minimum(dyn.m[pairs[:, 0]], dyn.m[pairs[:, 1]])  # Gershgorin on the lighter node
    dt_elements = dyn.region.critical_dt(dyn.density_scale)
    K = p["interface.penalty"] or min(p["material.E22"] / (h / p["mesh.elements_sublaminate"]),
                                      float(np.min(m_pair / area)) / dt_elements**2)
    # the law's strengths and toughness do not enter: every bond starts fully debonded
    law = HashinCohesiveLaw(K=K, Z0=1.0, R0=1.0, GIc=1.0, GIIc=1.0)
    X3 = np.pad(X0.T, ((0, 0), (0, 1)))
    bonds = LawBonds(pairs, X3, np.tile([0.0, 1.0, 0.0], (len(pairs), 1)), area, law, label="delamination")
    bonds.damage[:] = 1.0
    dyn.node_forces = [FemNodes(dyn).model(bonds, dyn)]
    dyn.critical_dt_extra = float(np.min(2.0 / np.sqrt(4 * K * area / m_pair)))
    return bonds


def southwell(P: np.ndarray, w: np.ndarray, lo: float = 0.5, hi: float = 5.0) -> float:
    """Critical load by Southwell's plot: the added deflection d = w - w0 of an imperfect strut
    is w0 (P / P_cr) / (1 - P / P_cr), so d / P against d is a line of slope 1 / P_cr. Fitted
    over the samples where d grew from lo to hi times w0 (before it first exceeds hi w0)."""
    w0 = w[0]
    d = np.abs(w - w0)
    grown = np.flatnonzero(d > hi * abs(w0))
    end = grown[0] if grown.size else len(w)
    sel = np.flatnonzero((d[:end] > lo * abs(w0)) & (P[:end] > 0))
    if sel.size < 4:
        return float("nan")
    slope = np.polyfit(d[sel], d[sel] / P[sel], 1)[0]
    return float(1.0 / slope) if slope > 0 else float("nan")


def film_critical_strain(P: np.ndarray, w_open: np.ndarray, eps_film: np.ndarray, h: float,
                         end: int | None = None) -> float:
    """The sublaminate's critical membrane strain (-, compression positive): the least
    compression it carries once buckled, from the sample where its opening first exceeds its
    thickness h (past the dynamic overshoot of the snap) to the panel's limit load. An
    elastica's membrane force is lowest, at its critical value, just after buckling and rises
    slowly in post-buckling (and as the panel bends); nan if the film never opened that far.
    end: the last sample to read (before the delamination grows: a longer film is softer)."""
    grown = np.flatnonzero(np.abs(w_open - w_open[0]) > h)
    end = int(np.argmax(P)) if end is None else min(end, int(np.argmax(P)))
    if not grown.size or grown[0] >= end:
        return float("nan")
    return float(-np.max(eps_film[grown[0]:end + 1]))


def base_strain(P: float, E: float, H: float, h: float, b: float, eps_c: float) -> float:
    """(-, compression positive) strain of the base laminate under the panel load P (N) once the
    film (thickness h of H) holds its critical strain eps_c: the strain the film would carry
    unbuckled, which drives its tips (compatibility of the end shortening)."""
    return float((P - E * eps_c * h * b) / (E * (H - h) * b))


def hutchinson_suo(E: float, h: float, eps_c: float, eps: float) -> float:
    """J/m^2, energy release rate at the tips of a buckled thin film of thickness h (m) under the
    applied strain eps above its critical strain eps_c (Hutchinson & Suo 1992, VALIDATION.md):
    G = (h / 2E) (sigma - sigma_c) (sigma + 3 sigma_c), sigma = E eps."""
    s, sc = E * eps, E * eps_c
    return float(h / (2 * E) * (s - sc) * (s + 3 * sc)) if s > sc else 0.0


def evaluate(p: dict, h: dict, mode: str):
    cf = closed_forms(p)
    E, b, tp = p["material.E11"], p["geometry.width"], p["geometry.ply_thickness"]
    H, h_sub = p["geometry.plies"] * tp, p["geometry.sublaminate_plies"] * tp
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
    k_closed = E * H * b / p["geometry.length"]
    # local: the panel load at which the film reaches its critical strain (uniform strain before
    # buckling: P = E11 H b eps); global: the panel's limit load (the delaminated panel bends
    # towards its base after the film has buckled, a limit point rather than a bifurcation)
    # the film's reading stops where a tip has grown by a bond (coupled mode)
    tips = np.maximum(h["growth_left"], h["growth_right"]) if "growth_left" in h else np.zeros(len(P))
    moved = np.flatnonzero(np.asarray(tips) > 0)
    eps_c = film_critical_strain(P, w_open, np.asarray(h["film_strain"]), h_sub, moved[0] - 1 if moved.size else None)
    qoi = {"local_buckling_load": E * H * b * eps_c, "global_buckling_load": float(P.max()),
           "film_critical_strain": eps_c, "local_buckling_load_southwell": southwell(P, w_open),
           "global_buckling_load_southwell": southwell(P, w_glob),
           "axial_stiffness": k_axial, "closed_form_axial_stiffness": k_closed,
           "peak_axial_force": float(P.max()), "closed_form_local": cf["local"], "closed_form_global": cf["global"],
           "closed_form_local_clamped": cf["local_clamped"],
           "max_interpenetration": float(np.max(h["interpenetration"])) if "interpenetration" in h else float("nan"),
           "closed_form_global_intact": cf["global_intact"], "closed_form_global_intact_shear": cf["global_intact_shear"],
           "tip_energy_release_rate": hutchinson_suo(E, h_sub, eps_c, base_strain(float(P.max()), E, H, h_sub, b, eps_c)),
           "seed_local": 6.3e3, "seed_global": 31.7e3, "reference_local": 5.8e3, "reference_global": 34.8e3}
    src = "closed forms for this geometry (VALIDATION.md)"
    global_src = ("clamped stepped column (Timoshenko & Gere 2.10): intact ends, the base sublaminate in the middle "
                  "carrying P minus the film's critical force")
    if "growth_left" in h:
        qoi.update(growth(p, h, P, eps_c))
        l_peak = qoi["delamination_length_at_limit_load"]
        cf["global"] = qoi["closed_form_global"] = closed_forms({**p, "geometry.delamination_length": l_peak})["global"]
        global_src += ", with the delamination length at the limit load"
    checks = {
        "axial_stiffness": check(k_axial, k_closed, 0.02, "pre-buckling axial stiffness E11 H b / L"),
        "local_buckling_load": check(qoi["local_buckling_load"], cf["local"], 0.10,
                                     src + ": thin film clamped at its tips, E11 H b (pi^2/3)(h/l)^2, with l + 2 chi h "
                                     "(corrected beam theory's root rotation) and Engesser's shear"),
        "global_buckling_load": check(qoi["global_buckling_load"], cf["global"], 0.10, global_src),
    }
    if "growth_left" in h and qoi["delamination_growth_left"] + qoi["delamination_growth_right"] > 0:
        # Hutchinson & Suo's film on a substrate that does not bend, with the measured critical
        # strain and the toughness of the measured mode mix; the onset is read on the history's
        # samples (about 1000 over the run)
        checks["growth_onset_load"] = check(qoi["growth_onset_load"], qoi["closed_form_growth_onset_load"], 0.15,
                                            "Hutchinson & Suo (1992): G = (h / 2E)(sigma - sigma_c)(sigma + 3 sigma_c) "
                                            "= Gc(B) of the measured mode mix, sigma the base laminate's stress")
        # a tip stopped by its window's end is the window's growth, unless the window spans the
        # intact end up to the clamp's neighbourhood (a fifth of it): then it ran into the clamp
        near_clamp = qoi["intact_end_beyond_window"] <= 0.2 * 0.5 * (p["geometry.length"] - p["geometry.delamination_length"])
        checks["growth_not_window_limited"] = bound(qoi["growth_reached_window_edge"] * (not near_clamp), 0.0,
                                                    "the delamination stopped inside the DEM windows, or they reach "
                                                    "the clamps' neighbourhood (else raise zone.window_ahead)")
        checks["dissipated_per_new_area"] = within(qoi["dissipated_per_new_area"], p["interface.GIc"],
                                                   p["interface.GIIc"], "energy: the interface dissipates between "
                                                   "GIc and GIIc per new crack area (B-K toughness range)")
    return qoi, checks


def growth(p: dict, h: dict, P: np.ndarray, eps_film: float) -> dict:
    """Delamination growth in the DEM windows: lengths, the onset (a tip two bonds beyond its
    start), the mode mix of the softening bonds then, and the onset Hutchinson & Suo predict
    for a film buckled at its measured critical strain with the B-K toughness of that mix."""
    E, b = p["material.E11"], p["geometry.width"]
    H, h_sub = p["geometry.plies"] * p["geometry.ply_thickness"], p["geometry.sublaminate_plies"] * p["geometry.ply_thickness"]
    l, d = p["geometry.delamination_length"], particle_size(p)
    gl, gr = np.asarray(h["growth_left"]), np.asarray(h["growth_right"])
    k = int(np.argmax(P))
    grown = np.flatnonzero(np.maximum(gl, gr) >= 2 * d - 1e-9 * d)
    B = np.asarray(h["tip_mode_ratio"])
    law = HashinCohesiveLaw(K=1.0, Z0=1.0, R0=1.0, GIc=p["interface.GIc"], GIIc=p["interface.GIIc"],
                            eta=p["interface.eta"], mixed_mode=p["interface.mixed_mode"])
    out = {"delamination_growth_left": float(gl[-1]), "delamination_growth_right": float(gr[-1]),
           "delamination_length_final": float(l + gl[-1] + gr[-1]),
           "delamination_length_at_limit_load": float(l + gl[k] + gr[k]),
           "growth_onset_load": float("nan"), "growth_mode_ratio": float("nan"),
           "closed_form_growth_onset_load": float("nan"),
           "interface_dissipated": float(np.asarray(h["interface_dissipated"])[-1])}
    # the window's last column is tied to intact FEM: a tip can run (n_out - 1) spacings; the
    # intact end left beyond that, from the clamp
    room = (int(round(window_ahead(p) / d)) - 1) * d
    out["growth_room"] = room
    out["growth_reached_window_edge"] = float(max(gl.max(), gr.max()) >= room - 1e-9 * d)
    out["intact_end_beyond_window"] = float(0.5 * (p["geometry.length"] - l) - room - d)
    new_area = b * (gl[-1] + gr[-1])
    if grown.size:
        j = grown[0]
        soft = np.flatnonzero(B[: j + 1] >= 0)
        Bj = float(B[soft[-1]]) if soft.size else float("nan")
        Gc = float(law.toughness(Bj))
        s_c = E * eps_film  # Hutchinson & Suo: G(sigma) = Gc solved for sigma, the base's stress
        sigma = -s_c + np.sqrt(4 * s_c**2 + 2 * E * Gc / h_sub)
        out.update({"growth_onset_load": float(P[j]), "growth_mode_ratio": Bj, "growth_toughness": Gc,
                    "closed_form_growth_onset_load": float(sigma * (H - h_sub) * b + s_c * h_sub * b),
                    "dissipated_per_new_area": out["interface_dissipated"] / new_area})
    return out


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    P = np.asarray(h["axial_force"]) / 1e3
    growth = "growth_left" in h
    fig, ax = plt.subplots(1, 3 if growth else 2, figsize=(15 if growth else 10, 4))
    ax[0].plot(1e3 * np.asarray(h["deflection_A"]), P, label="A (0_4, top)")
    ax[0].plot(1e3 * np.asarray(h["deflection_B"]), P, label="B (0_16, bottom)")
    for key, ls, label in (("local", "--", "local: thin film"), ("global", ":", "global: delaminated column"),
                           ("global_intact", "-.", "intact panel (Euler)")):
        ax[0].axhline(qoi[f"closed_form_{key}"] / 1e3, color="k", ls=ls, lw=0.8, label=label)
    ax[0].set(xlabel="lateral deflection (mm)", ylabel="axial load (kN)", title="delaminated panel")
    ax[0].legend()
    ax[1].plot(-1e3 * np.asarray(h["film_strain"]), P, label="0_4 film, membrane strain")
    ax[1].axvline(1e3 * qoi["closed_form_local"] / (p["material.E11"] * p["geometry.plies"] * p["geometry.ply_thickness"]
                                                    * p["geometry.width"]), color="k", ls="--", lw=0.8,
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
    kN = lambda v: f"{v / 1e3:.2f}" if np.isfinite(v) else "-"
    rows = [("local (0_4 film)", "seed_local", "reference_local", "closed_form_local", "local_buckling_load"),
            ("global (panel)", "seed_global", "reference_global", "closed_form_global", "global_buckling_load")]
    lines = ["| buckling load (kN) | seed paper | reference (Perugini et al. 1999) | closed form, this geometry "
             "| this run |", "|---|---|---|---|---|"]
    lines += [f"| {name} | " + " | ".join(kN(qoi[k]) for k in keys) + " |" for name, *keys in rows]
    lines.append(f"| local, rigid clamps at the tips | | | {kN(qoi['closed_form_local_clamped'])} | |")
    lines.append(f"| global, intact panel (Euler; with shear) | | | {kN(qoi['closed_form_global_intact'])}; "
                 f"{kN(qoi['closed_form_global_intact_shear'])} | |")
    if "growth_onset_load" in qoi:
        lines.append(f"| delamination growth onset (Hutchinson & Suo) | | | {kN(qoi['closed_form_growth_onset_load'])} "
                     f"| {kN(qoi['growth_onset_load'])} |")
    return "\n".join(lines) + "\n"
