"""Split-beam specimens (DCB, ENF, SLB) as coupled problems: FEM arms, the crack path as DEM;
and all-FEM (``--mode fem``: the arms meshed apart along the crack plane, joined node to node by
the same law, the far field's cohesive interface; cohesive_specimen).

Geometry (plane stress slice of thickness t = d, the particle spacing; every force is
reported for the whole width b by the factor b / t, exact for this linear-in-thickness model):

      y = 2h  +----------------------------------------------------------+
              |                FEM upper arm (orthotropic ply)           |
      h + d   +--------------+ o o o o o o o o o o o o o o o o o o +-----+   o at h + 1.5 d
              | FEM band     | . . . . . . DEM window . . . . . . |     |   . at h + 0.5 d
          h   |--- crack ----| - - - - - - (law bonds) - - - - - - | FEM |
              | FEM band     | . . . . . . . . . . . . . . . . . .|     |   . at h - 0.5 d
      h - d   +--------------+ o o o o o o o o o o o o o o o o o o +-----+   o at h - 1.5 d
              |                FEM lower arm                             |
          0   +----------------------------------------------------------+
              0             x_a          a0                       x_b    L

The DEM window [x_a, x_b] holds four rows of particles on a square lattice of spacing d. The
outer rows (o) sit half a spacing inside the FEM arms and are tied to them; the inner rows (.)
are free, so each free row's axial bonds stand for exactly the strip d thick between the FEM
face and the mid-plane (placing the tied rows on the FEM face instead leaves a half strip to
be lumped on the free row, which over-stiffens the arms in bending: measured 3 % more
compliance error per 6 mm of window). Bonds: axial k_x, k_y and two diagonals k_2 per cell,
the closed form of calibration.py: C11 = (k_x + k_2)/t = E11 + G13^2/E22,
C22 = (k_y + k_2)/t = E22, C66 = k_2/t = G13, so the uniaxial moduli are E11 and about E22.
Across the mid-plane the vertical pairs are joined by the seed's interlaminar law
(HashinCohesiveLaw, evaluated by the coupling layer on any engine) with the penalty
K = E22 / d of the material it replaces; pairs behind a0 start fully debonded (they keep
compressive contact with friction: the crack faces of the ENF). Left of x_a the band is FEM,
cut along y = h (the initial crack); right of x_b it is intact.

A window that starts ahead of the initial crack (x_a > a0, ``dem.window_start``) leaves the
crack's first stretch to the FEM: the band is cut along y = h up to half a spacing past x_a and
its node pairs are joined by the same law as the all-FEM specimen's (debonded behind a0), so a
crack front starts in the FEM and runs on into the particles (build_specimen, CrackPlane).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from physics.failure import HoffmanStrengths
from physics.law_bonds import LawBonds
from physics.laws import MIXED_MODE, HashinCohesiveLaw, PlyBondLaw
from dem_region.scene import DemScene
from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics
from fem_region.node_to_face import NodeToFace, node_to_face

from ..checks import bound
from ..params import CaseError, Param
from ..participants.coupled import coupled_simulation
from ..participants.fem import (FEM_OPTIONS, cohesive_node_bonds, cohesive_penalty, energies_with, face_pair_mass,
                                fem_only, make_region, node_to_face_bonds)

def ranged(default: float, doc: str, unit: str, low: float, high: float) -> Param:
    """A parameter inside the range over which the specimens are verified (tests/test_delamination_ranges.py
    samples it); a value outside is refused, not extrapolated."""
    return Param(default, doc, "float", unit, low=low, high=high)


# Defaults: AS4/PEEK, the delamination benchmark material of Camanho & Davila
# (NASA/TM-2002-211737) and Turon et al. (2007), and their DCB specimen: b = 25.4 mm,
# h = 1.56 mm, a0 = 32.9 mm, L = 102 mm. Ranges: unidirectional glass to carbon plies and the
# specimen sizes of ASTM D5528 / D7905 and their thick coarse variants (arms of 1 to 5 mm)
PARAMETERS: dict[str, Param] = {
    "material.E11": ranged(122.7e9, "ply modulus along the fibres (beam axis)", "Pa", 40e9, 200e9),
    "material.E22": ranged(10.1e9, "transverse ply modulus (through the thickness)", "Pa", 6e9, 15e9),
    "material.G13": ranged(5.5e9, "transverse shear modulus (x-y plane of the slice), below E22", "Pa", 3e9, 7e9),
    "material.nu12": Param(0.25, "major Poisson ratio", low=0.2, high=0.4),
    "material.rho": ranged(1570.0, "ply density", "kg/m^3", 1200.0, 2200.0),
    "geometry.arm_thickness": ranged(1.56e-3, "thickness h of each arm", "m", 1e-3, 5e-3),
    "geometry.width": ranged(25.4e-3, "specimen width b (out of plane)", "m", 5e-3, 60e-3),
    "geometry.length": ranged(102e-3, "specimen length", "m", 40e-3, 300e-3),
    "interface.GIc": ranged(969.0, "mode I critical energy release rate", "J/m^2", 150.0, 2000.0),
    "interface.GIIc": ranged(1719.0, "mode II critical energy release rate", "J/m^2", 300.0, 4000.0),
    "interface.Z0": ranged(80e6, "interlaminar normal strength", "Pa", 10e6, 150e6),
    "interface.R0": ranged(100e6, "interlaminar shear strength", "Pa", 10e6, 200e6),
    "interface.eta": Param(2.284, "B-K (or power-law) exponent", low=1.0, high=4.0),
    "interface.mixed_mode": Param("bk", "mixed-mode criterion", kind="str", choices=MIXED_MODE),
    "interface.cohesive_zone_bonds": Param(20.0, "fewest bonds in the cohesive zone: strengths above "
                                           "sqrt(9 pi E22 Gc / (32 N d)) are lowered to it (Turon et al. 2007); "
                                           "0 keeps the given strengths", low=0.0, high=50.0),
    "interface.friction": Param(0.0, "Coulomb friction of debonded faces in contact", low=0.0, high=1.0),
    "zone.particle_size": ranged(0.26e-3, "DEM particle size d (the lattice spacing), at most h / 6", "m", 100e-6, 1e-3),
    "mesh.elements_through": Param(3, "FEM elements through each arm outside the band", kind="int", low=1, high=40),
    "mesh.element_length": Param(0.0, "FEM element length along the beam; 0 = 2 d (coupled: the arms), d (fem: "
                                 "the node pairs resolve the cohesive zone as the particles do)", unit="m", low=0.0),
    "mesh.upper_element_length": Param(0.0, "fem: FEM element length along the upper arm; 0 = the lower arm's "
                                       "(the arms' nodes coincide, joined pair by pair); another meshes the arms "
                                       "independently, joined node to face (the finer arm's nodes to the other's "
                                       "faces, the seed's node-to-face bonding)", unit="m", low=0.0),
    "load.ramp_time": Param(0.0, "time over which the load-point speed ramps up; 0 = two periods of the "
                            "cracked arm", unit="s", low=0.0),
    **{k: v for k, v in FEM_OPTIONS.items() if k not in ("mesh.element", "fem.hypothesis")},
    # Total Lagrangian by default: the engine's bonds act along the particles' current directions,
    # so a free row's axial force N (the bending stress of the strip it stands for) turns with the
    # arm; a small-strain FEM, whose matching -N does not turn, takes N theta as a load, a couple
    # int N theta dx along the cracked window (measured: the window's arms 15 % too stiff at
    # E11 = 40 GPa, the DCB's propagation branch 17 % high; 4.7 % with the TL arms)
    "fem.formulation": Param("total_lagrangian", "Total Lagrangian (finite rotations, consistent with the DEM "
                             "window's bonds) or small-strain linear", kind="str",
                             choices=("total_lagrangian", "linear")),
    # its drag on the moving arms is load the closed forms do not have: 0.2 with 6 periods' loading
    # put the coarse DCB's peak 7.8 % high, 0.4 with 10 periods 5.9 %, 1.0 18 % (ENF 6.7 %, SLB 16 %)
    "damping.ratio": Param(0.1, "mass-proportional damping, fraction of critical at the loaded arm's "
                           "first mode (keeps the quasi-static response free of ringing)", low=0.0, high=0.1),
}


def chi(p: dict) -> float:
    """Crack-length correction factor of corrected beam theory (Hashemi, Kinloch & Williams 1990)."""
    return chi_of(p["material.E11"], p["material.E22"], p["material.G13"])


def chi_of(E11: float, E22: float, G13: float) -> float:
    """chi of a ply's moduli (Pa)."""
    gamma = 1.18 * np.sqrt(E11 * E22) / G13
    return float(np.sqrt(E11 / (11 * G13) * (3 - 2 * (gamma / (1 + gamma)) ** 2)))


@dataclass
class Specimen:
    """What a split-beam scene needs: the FEM factory, the DEM scene, the law bonds and the
    node sets (flat x / y DOF indices) for supports and loads. All-FEM (cohesive_specimen): no
    scene; the bonds join the node ``pairs`` (k, 2) lower / upper on the crack plane, each
    standing for ``pair_area`` (k,) m^2, once the FEM exists (``simulate``). Coupled with the
    window ahead of a0: the FEM band's node pairs as well, besides the window's."""

    scene: DemScene | None
    bonds: LawBonds | None
    t: float  # slice thickness, m
    width_factor: float  # b / t
    region: object
    upper_end: np.ndarray  # nodes of the upper arm's face x = 0
    lower_end: np.ndarray
    omega_arm: float  # first bending mode of the loaded (cracked) arm, rad/s
    pairs: np.ndarray | None = None
    pair_area: np.ndarray | None = None
    a0: float = 0.0  # m, the initial crack: bonds behind it start debonded
    face: NodeToFace | None = None  # all-FEM with the arms meshed independently: node-to-face bonds
    springs: LawBonds | None = None  # a growing window's lattice springs (window_growth.py)
    clock: object = None  # the coupled model's CoupledClock, once simulate has built it


def slice_ply(p: dict) -> np.ndarray:
    """Plane-stress stiffness (3, 3) Pa of the ply with the fibres along x."""
    E11, E22, G13, nu = p["material.E11"], p["material.E22"], p["material.G13"], p["material.nu12"]
    return materials.plane_stress(materials.orthotropic(E11, E22, E22, nu, nu, 0.4, G13, G13, E22 / 2.8))


SLIVER = 0.05  # the shortest element two break lines may leave, in particle spacings: its stable
# step is about as much shorter (a run 20 x longer); closer lines are a setting's accident


def _refuse_slivers(p: dict, lines: list[tuple[float, str, str]], d: float, tol: float) -> None:
    """CaseError when two of the mesh's break lines (x m, what places it, the key that moves
    it) fall closer than SLIVER particle spacings d (and apart by more than tol, or they are
    one line): the window's ends, the crack tip and the supports and load lines each take a
    line, and two that nearly meet leave an element whose stable step slows the run without
    bound (enf_coarse with its window ending 0.1 um past the load line: dt 1e-11 s, 2e8 steps).
    A growing window's later mesh lines are not among them (they are meshed from the start
    wherever they fall; one near a support costs steps, as before)."""
    lines = sorted(lines)
    for (xa, what_a, key_a), (xb, what_b, key_b) in zip(lines[:-1], lines[1:]):
        if not tol < xb - xa < SLIVER * d:
            continue
        keys = [k for k in (key_a, key_b) if k]
        key = next((k for k in keys if k in ("dem.window_start", "dem.window_end", "zone.margin") and p.get(k)),
                   keys[0] if keys else "geometry.crack_length")
        raise CaseError(f"{key} = {p[key]:g}: the specimen's mesh would need lines at x = {xa:.6g} m ({what_a}) and "
                        f"{xb:.6g} m ({what_b}), {xb - xa:.2g} m apart: an element that short sets the stable step; "
                        f"allowed: a {key} that keeps them at least {SLIVER:g} particle spacing ({SLIVER * d:.3g} m) "
                        "apart")


def build_specimen(p: dict, a0: float, x_a: float, x_b: float, omega_arm: float,
                   stations: tuple[float, ...] = (), reserve: tuple[float, float, float] | None = None) -> Specimen:
    """Mesh, DEM window [x_a, x_b] (rounded to whole spacings), law bonds debonded for x < a0;
    ``stations`` (m): x of supports and load lines, which get a line of mesh nodes. The
    particle size is the caller's to check (check_resolution, in each specimen's validity).
    reserve (x0, x1, e) m: a window that may grow (window_growth.py): mesh lines every e from
    x0 to x1, so that any grown window ends on one and its FEM is this mesh less the band's
    elements it took; the lattice's springs are then law bonds (``springs``), whose rest
    lengths are the lattice's, not the positions an engine is built with."""
    h, L = p["geometry.arm_thickness"], p["geometry.length"]
    r = 0.5 * p["zone.particle_size"]
    d = 2 * r
    band = d  # half-thickness of the window cut out of the FEM
    E11, E22, G13 = p["material.E11"], p["material.E22"], p["material.G13"]
    if G13 >= E22:
        raise CaseError(f"material.G13 = {G13:g}: the square lattice needs G13 < E22 = {E22:g} Pa")
    n_win = max(4, int(round((x_b - x_a) / d)))
    x_b = min(x_a + n_win * d, L)
    n_win = int(round((x_b - x_a) / d))
    ex = p["mesh.element_length"] or 2 * d
    tol = 1e-9 * L
    # A window ahead of the initial crack (x_a > a0): the crack starts in the FEM band, cut and
    # joined by node pairs at about the particles' spacing from a0 to half a spacing past the
    # window's tied first column, so that the band's elements hold that column's particles as
    # the arms hold the outer rows and the window's first free column meets the band's edge.
    # Measured on dcb_coarse (x_a = 36 mm, a0 = 30 mm), the load on the propagation branch
    # while the cohesive zone crossed x_a, against beam theory: the band ending at x_a, where
    # the tied column's pair saw half the crack's opening, +7.4 % in 1 mm of crack (all-FEM
    # +0.3 %), the crack held there twice as long as elsewhere; ending half a spacing past it,
    # +1.7 % over the crossing (all-FEM +1.3 %). Elements of the particles' spacing along the
    # arms 2 h either side (2 d elsewhere) put enf_coarse's peak (x_a = a0 + 6.5 mm) 0.05 %
    # from all-FEM's, 2.4 % without.
    ahead = x_a > a0 + tol
    x_e = x_a + 0.5 * d if ahead else x_a  # where the band's elements end
    # (a growing window's reserve: the same mesh whatever its end)
    fine = (max(0.0, a0 - 2 * h), min(reserve[0] if reserve else x_b, x_e + 2 * h)) if ahead else (0.0, 0.0)
    # x lines: graded into the window's ends, the window itself at the particle spacing's multiple
    def line(a, b):
        e = d if fine[0] - tol < a and b < fine[1] + tol else ex
        return np.linspace(a, b, max(1, int(np.ceil((b - a) / e - 1e-9))) + 1) if b > a + 1e-12 else np.array([a])
    inner = [x for x in stations if 0.0 < x < L] + ([a0, *fine] if ahead else [])
    if reserve is None:
        breaks = np.unique(np.concatenate([[0.0, x_e, x_b, L], inner]))
        xs = np.unique(np.concatenate([line(a, b) for a, b in zip(breaks[:-1], breaks[1:])]))
    else:
        x0, x1, e = reserve
        grid = x0 + e * np.arange(int(round((x1 - x0) / e)) + 1)
        breaks = np.unique(np.concatenate([[0.0, x_e, x0, x1, L], inner]))
        xs = np.unique(np.concatenate([grid, inner] + [line(a, b) for a, b in zip(breaks[:-1], breaks[1:])
                                                       if not (x0 - 1e-9 * L < a and b < x1 + 1e-9 * L)]))
    # (the key that moves each line: a window's end lies whole spacings from its start)
    start_key = "dem.window_start" if ahead else ""
    end_key = "dem.window_end" if p.get("dem.window_end") else start_key or ("zone.margin" if reserve else
                                                                             "dem.window_end")
    _refuse_slivers(p, [(0.0, "the specimen's end", ""), (L, "its root", ""),
                        (x_e, "the window's start", start_key), (x_b, "the window's end", end_key),
                        *[(x, "a support or load line", "") for x in stations if 0.0 < x < L],
                        *([(a0, "the crack tip", "geometry.crack_length"), (fine[0], "the fine mesh's start",
                                                                           "geometry.crack_length"),
                           (fine[1], "the fine mesh's end", start_key)] if ahead else [])], d, tol)
    nt = p["mesh.elements_through"]
    ys = np.unique(np.concatenate([np.linspace(0, h - band, nt + 1), [h], np.linspace(h + band, 2 * h, nt + 1)]))
    m = mesh.cut_rectangle(xs, ys, lambda cx, cy: not (x_e - tol < cx < x_b + tol and abs(cy - h) < band),
                           crack_y=h, crack_x_max=x_e if x_a > 0 else -np.inf)
    t = d
    D = slice_ply(p)
    rho = p["material.rho"]
    region = make_region(m, p, D, rho, t)

    K = E22 / d
    Z0, R0 = resolved_strengths(p, d)
    w = band_window(x_a, n_win, h, d, ((E11 + G13**2 / E22 - G13) * t, (E22 - G13) * t, G13 * t), K * d * t,
                    tie_first=x_a > 0)
    x, cols = w.x, w.x[w.lower, 0]
    sphere_rho = rho * d**3 / (4.0 / 3.0 * np.pi * r**3)
    springs = None
    if reserve is not None:
        springs = lattice_springs(w, x, d, t, tied=p["coupling.tie"] == "kinematic")
        w.kn[: len(w.kn) - len(w.lower)] *= 1e-9  # the engine's bonds: placeholders (as the law pairs')
    scene = DemScene(x, r, sphere_rho, w.pairs, kn=w.kn, ks=0.0, plane=True, young=E22,
                     groups={"interface": np.flatnonzero(w.tied)}, placeholder_bonds=springs is not None)

    law = HashinCohesiveLaw(K=K, Z0=Z0, R0=R0, GIc=p["interface.GIc"],
                            GIIc=p["interface.GIIc"], eta=p["interface.eta"], mixed_mode=p["interface.mixed_mode"])
    bonds = LawBonds(np.column_stack([w.lower, w.upper]), x, np.tile([0.0, 1.0, 0.0], (n_win + 1, 1)),
                     w.share * d * t, law, friction=p["interface.friction"], along=w.along)
    bonds.damage[cols < a0 - 1e-9 * d] = 1.0  # the initial crack: faces in contact only
    bonds.t_failed[cols < a0 - 1e-9 * d] = 0.0

    cells_above = region.mesh.t[:, region.mesh.p[1, region.mesh.t].mean(axis=0) > h]
    above = np.zeros(region.n_nodes, bool)
    above[np.unique(cells_above)] = True
    end = region.X[:, 0] < tol
    spec = Specimen(scene=scene, bonds=bonds, t=t, width_factor=p["geometry.width"] / t,
                    region=region, upper_end=np.flatnonzero(end & above), lower_end=np.flatnonzero(end & ~above),
                    omega_arm=omega_arm, springs=springs, a0=a0)
    if ahead:  # the band's cut from 0 to x_e joined node to node (debonded behind a0), as all-FEM
        spec.pairs, spec.pair_area = plane_pairs(region.X, above, h, x_e, tol, t)
        bonds.area[0] = 0.0  # the first column's plane is the band's (its particles move with it)
    return spec


def plane_pairs(X: np.ndarray, above: np.ndarray, h: float, x_max: float, tol: float, t: float
                ) -> tuple[np.ndarray, np.ndarray]:
    """(pairs (k, 2) lower / upper node, area (k,) m^2): the coincident nodes on the crack plane
    y = h with x <= x_max (m; X (n, 2) the nodes, above (n,) bool the upper arm's), in order
    along it, each standing for its tributary length times the slice's thickness t."""
    on = np.flatnonzero((np.abs(X[:, 1] - h) < tol) & (X[:, 0] < x_max + tol))
    lower, upper = on[~above[on]], on[above[on]]
    lower, upper = lower[np.argsort(X[lower, 0])], upper[np.argsort(X[upper, 0])]
    x = X[lower, 0]
    edges = np.concatenate([[x[0]], 0.5 * (x[1:] + x[:-1]), [x[-1]]])
    return np.column_stack([lower, upper]), np.diff(edges) * t


# the window's plies do not fail (the specimens test the interface): a lattice spring is a ply
# bond that never initiates
_NEVER = HoffmanStrengths(*(9 * [np.inf]))


def lattice_springs(w: "BandWindow", x: np.ndarray, d: float, t: float, tied: bool) -> LawBonds:
    """The window's lattice springs (w.pairs less the law pairs, stiffness w.kn N/m) as law
    bonds on particles x (n, 3) m: linear central springs along the current axis, rest lengths
    from x (the engine's bonds, in the same corotated form); tied: without the springs
    between two tied particles, as the kinematic tie removes them (the FEM carries them)."""
    n_law = len(w.lower)
    pairs, k = w.pairs[:-n_law], w.kn[:-n_law]
    if tied:
        keep = ~(w.tied[pairs[:, 0]] & w.tied[pairs[:, 1]])
        pairs, k = pairs[keep], k[keep]
    area = d * t
    law = PlyBondLaw(K=k / area, Gf=1.0, strengths=_NEVER, axes=np.eye(3))
    axis = x[pairs[:, 1]] - x[pairs[:, 0]]
    return LawBonds(pairs, x, axis, area, law, volume=np.full(len(x), d * d * t), label="lattice",
                    finite_rotation=True)


def bond_spacing(p: dict, mode: str) -> float:
    """m, the spacing of the bonds across the crack plane: the particles' (coupled) or the FEM
    nodes' along it (fem: mesh.element_length, 0 = d, the particles' resolution of the cohesive
    zone: 2 d put the full DCB's peak 12.7 % above beam theory, d 3.9 %)."""
    if mode == "coupled":
        if p["mesh.upper_element_length"]:  # (checked here: every scene's validity asks for the spacing)
            raise CaseError(f"mesh.upper_element_length = {p['mesh.upper_element_length']:g}: allowed with --mode "
                            "fem only (coupled arms are meshed on the DEM window's columns); 0 keeps it off")
        return p["zone.particle_size"]
    lower = p["mesh.element_length"] or p["zone.particle_size"]
    return min(lower, p["mesh.upper_element_length"] or lower)  # node to face: the finer arm's nodes bond


def specimen(p: dict, mode: str, a0: float, x_a: float, x_b: float, omega_arm: float,
             stations: tuple[float, ...] = (), reserve: tuple[float, float, float] | None = None) -> Specimen:
    """The specimen of ``mode``: coupled (build_specimen: FEM arms, the DEM window [x_a, x_b])
    or fem (cohesive_specimen)."""
    if mode == "coupled":
        return build_specimen(p, a0, x_a, x_b, omega_arm, stations, reserve)
    return cohesive_specimen(p, a0, omega_arm, stations)


def cohesive_specimen(p: dict, a0: float, omega_arm: float, stations: tuple[float, ...] = ()) -> Specimen:
    """All-FEM: both arms meshed apart along the crack plane y = h over the whole length, their
    coincident nodes joined by the same law as the particles' (the far field's cohesive
    interface, participants.fem.cohesive_node_bonds), debonded behind a0. Elements of
    bond_spacing along, mesh.elements_through through each arm; each node pair stands for its
    tributary length of the plane."""
    h, L = p["geometry.arm_thickness"], p["geometry.length"]
    d = p["zone.particle_size"]
    ex = p["mesh.element_length"] or d
    if p["material.G13"] >= p["material.E22"]:  # (the same domain as the coupled specimen)
        raise CaseError(f"material.G13 = {p['material.G13']:g}: allowed below material.E22 = {p['material.E22']:g} Pa")
    breaks = np.unique(np.concatenate([[0.0, L], [x for x in stations if 0.0 < x < L]]))
    lines = lambda e: np.unique(np.concatenate([np.linspace(a, b, max(1, int(np.ceil((b - a) / e - 1e-9))) + 1)
                                                for a, b in zip(breaks[:-1], breaks[1:])]))
    xs = lines(ex)
    nt = p["mesh.elements_through"]
    if p["mesh.upper_element_length"]:
        return _node_to_face_specimen(p, a0, omega_arm, xs, lines(p["mesh.upper_element_length"]))
    ys = np.unique(np.concatenate([np.linspace(0, h, nt + 1), np.linspace(h, 2 * h, nt + 1)]))
    tol = 1e-9 * L
    m = mesh.cut_rectangle(xs, ys, lambda cx, cy: True, crack_y=h, crack_x_max=L)
    region = make_region(m, p, slice_ply(p), p["material.rho"], d)
    X = region.X
    cells_above = region.mesh.t[:, X[region.mesh.t, 1].mean(axis=0) > h]
    above = np.zeros(region.n_nodes, bool)
    above[np.unique(cells_above)] = True
    pairs, area = plane_pairs(X, above, h, L, tol, d)
    end = X[:, 0] < tol
    return Specimen(scene=None, bonds=None, t=d, width_factor=p["geometry.width"] / d, region=region,
                    upper_end=np.flatnonzero(end & above), lower_end=np.flatnonzero(end & ~above),
                    omega_arm=omega_arm, pairs=pairs, pair_area=area, a0=a0)


def _node_to_face_specimen(p: dict, a0: float, omega_arm: float, xs_lower: np.ndarray,
                           xs_upper: np.ndarray) -> Specimen:
    """All-FEM with the arms meshed independently (x lines xs_lower, xs_upper m), joined node
    to face across y = h (fem_region.node_to_face): the finer arm's nodes bond to the other
    arm's edges, each standing for its tributary length."""
    h, d, nt = p["geometry.arm_thickness"], p["zone.particle_size"], p["mesh.elements_through"]
    m, (lower, upper) = mesh.joined(mesh.rectangle(xs_lower, np.linspace(0, h, nt + 1)),
                                    mesh.rectangle(xs_upper, np.linspace(h, 2 * h, nt + 1)))
    region = make_region(m, p, slice_ply(p), p["material.rho"], d)
    face = node_to_face(m.p, m.t, lower, upper, 1, h, 1e-9 * p["geometry.length"])
    above = np.zeros(region.n_nodes, bool)
    above[np.unique(m.t[:, upper])] = True
    end = region.X[:, 0] < 1e-9 * p["geometry.length"]
    return Specimen(scene=None, bonds=None, t=d, width_factor=p["geometry.width"] / d, region=region,
                    upper_end=np.flatnonzero(end & above), lower_end=np.flatnonzero(end & ~above),
                    omega_arm=omega_arm, pair_area=face.area * d, a0=a0, face=face)


def simulate(p: dict, mode: str, dem: str, spec: Specimen, supports, alpha: float, t_end: float, start=None):
    """(Simulation, FEM participant, CrackPlane: the crack plane's law bonds) of a specimen:
    coupled (the DEM window's bonds on the particles, and the FEM band's node pairs ahead of a0
    when the window starts there) or fem (the node pairs' bonds: penalty 50 E22 / h, Turon
    et al. 2007's alpha = 50 against the arm, or the elements' limit if lower
    (participants.fem.cohesive_penalty; the step is that of both together); strengths by
    resolved_strengths on the node spacing). start: a grown window's (coupled_simulation's)."""
    if mode == "coupled":
        models = (spec.bonds,) if spec.springs is None else (spec.bonds, spec.springs)
        node_bonds = []  # the FEM band's pairs ahead of a0, once the FEM exists

        def make(extra_mass):
            dyn = fem_factory(spec, supports, alpha)(extra_mass)
            if spec.pairs is not None:
                node_bonds[:] = [crack_plane_bonds(p, mode, dyn, spec)]
            return dyn
        sim, spec.clock = coupled_simulation(p, make, spec.scene, dem, t_end, models=models, start=start)
        sim.probes["damage_at_zone_edge"] = lambda: float(spec.bonds.damage[-1])  # the window's last column
        end = float(spec.bonds.X[spec.bonds.pairs[-1, 0], 0])
        sim.probes["window_end"] = lambda: end  # m (a grown window's moves)
        if node_bonds:
            sim.energies = energies_with(sim.energies, node_bonds)
            sim.counts["interface_bonds"] = len(node_bonds[0].pairs)
        return sim, spec.clock.fem, CrackPlane((*node_bonds, spec.bonds))
    dyn = ExplicitDynamics(spec.region, supports=supports, alpha=alpha)
    bonds = crack_plane_bonds(p, mode, dyn, spec)
    sim = fem_only(dyn, p, t_end, {})
    sim.energies = energies_with(sim.energies, [bonds])
    sim.counts["interface_bonds"] = len(bonds.pairs)
    return sim, dyn, CrackPlane((bonds,))


def crack_plane_bonds(p: dict, mode: str, dyn: ExplicitDynamics, spec: Specimen) -> LawBonds:
    """The law bonds joining the specimen's FEM node pairs (or node-to-face points) across the
    crack plane, debonded behind a0: penalty 50 E22 / h (Turon et al. 2007's alpha = 50
    against the arm) or the elements' limit if lower (participants.fem.cohesive_penalty; the
    FEM's step is then that of elements and bonds together); strengths by resolved_strengths
    on the node spacing, which is the particles' where the band joins a DEM window."""
    pairs, area, face = spec.pairs, spec.pair_area, spec.face
    m_pair = None if face is None else face_pair_mass(dyn, face)
    K = cohesive_penalty(dyn, pairs, area, 50 * p["material.E22"] / p["geometry.arm_thickness"], m_pair)
    Z0, R0 = resolved_strengths(p, bond_spacing(p, mode), keys_of(mode, p))
    law = HashinCohesiveLaw(K=K, Z0=Z0, R0=R0, GIc=p["interface.GIc"], GIIc=p["interface.GIIc"],
                            eta=p["interface.eta"], mixed_mode=p["interface.mixed_mode"])
    if face is None:
        bonds = cohesive_node_bonds(dyn, pairs, area, law, p["interface.friction"])
    else:  # the arms meshed independently: node to face
        bonds = node_to_face_bonds(dyn, face, area, law, p["interface.friction"])
    behind = bonds.X[bonds.pairs[:, 0], 0] < spec.a0 - 1e-9 * p["geometry.length"]
    bonds.damage[behind], bonds.t_failed[behind] = 1.0, 0.0  # the initial crack: faces in contact only
    return bonds


@dataclass
class CrackPlane:
    """The law bonds across a specimen's crack plane, in one or two families: the FEM's node
    pairs (all-FEM, or the band ahead of a0 before a DEM window) and the window's particle
    pairs. Their debonded positions are nodes' or particles' x along the plane either way."""

    families: tuple

    def tip(self) -> float:
        """x (m) of the furthest fully debonded pair along the plane (nan: none)."""
        return max((crack_tip(b) for b in self.families), key=lambda x: np.nan_to_num(x, nan=-np.inf))

    def softening(self) -> float:
        """Pairs on their softening branch (0 < damage < 1): the cohesive zone, in bonds."""
        return sum(softening_bonds(b) for b in self.families)

    def dissipated_energy(self) -> float:
        """J, what the pairs dissipated (per slice thickness)."""
        return sum(b.dissipated_energy() for b in self.families)

    def decohesion_energy(self) -> float:
        """J, what the pairs' decohesion dissipated (per slice thickness): less the friction of
        closed failed faces, which a toughness does not hold."""
        return sum(b.decohesion_energy() for b in self.families)


@dataclass
class BandWindow:
    """Four rows of particles on a square lattice across a crack plane (module figure):
    x (n, 3) m; pairs (nb, 2) and kn (nb,) N/m, the engine's bonds (the law pairs as
    placeholders); tied (n,) bool, the rows inside the FEM and the end columns that face FEM;
    lower, upper (ncol,) the law pairs across the plane, column by column; along (ncol, 2)
    their neighbours; share (ncol,) each pair's share of a spacing (1/2 at the ends)."""

    x: np.ndarray
    pairs: np.ndarray
    kn: np.ndarray
    tied: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    along: np.ndarray
    share: np.ndarray


def band_window(x_a: float, n_win: int, y_c: float, d: float, k: tuple[float, float, float], k_law: float,
                tie_first: bool = True, tie_last: bool = True) -> BandWindow:
    """Columns x_a + j d (j <= n_win), rows y_c + (-1.5, -0.5, 0.5, 1.5) d; k = (k_x, k_y, k_2)
    N/m, the closed-form lattice (axial along x and y, two diagonals per cell), none across
    the plane y_c; k_law N/m, the law pairs' stiffness (they reach the engine at 1e-9 of it,
    so that it never adds a contact of its own between them: compression would count twice)."""
    kx, ky, k2 = k
    col, row = np.meshgrid(np.arange(n_win + 1), np.arange(4), indexing="ij")
    col, row = col.ravel(), row.ravel()
    x = np.column_stack([x_a + d * col, y_c + d * (row - 1.5), np.zeros(col.size)])
    idx = lambda c, j: c * 4 + j
    tied = (row == 0) | (row == 3) | ((col == n_win) & tie_last) | ((col == 0) & tie_first)
    pairs, ks = [], []
    for c in range(n_win + 1):
        for j in range(4):
            if c < n_win:
                pairs.append((idx(c, j), idx(c + 1, j)))
                ks.append(kx)
            if j < 3 and j != 1:  # vertical, not across the mid-plane
                pairs.append((idx(c, j), idx(c, j + 1)))
                ks.append(ky)
            if c < n_win and j < 3 and j != 1:  # diagonals of the cell
                pairs += [(idx(c, j), idx(c + 1, j + 1)), (idx(c + 1, j), idx(c, j + 1))]
                ks += [k2, k2]
    c = np.arange(n_win + 1)
    lower, upper = idx(c, 1), idx(c, 2)
    pairs += list(zip(lower.tolist(), upper.tolist()))
    ks += [1e-9 * k_law] * len(lower)
    share = np.ones(n_win + 1)
    share[[0, -1]] = 0.5
    along = np.column_stack([np.where(c > 0, c - 1, -1), np.where(c < n_win, c + 1, -1)])
    return BandWindow(x, np.array(pairs, int), np.array(ks, float), tied, lower, upper, along, share)


def check_resolution(p: dict) -> None:
    """Refuses (CaseError) particles coarser than a sixth of the arm: the DEM strip then stands
    for too much of the arm's bending (measured on a DCB with d = h / 4.2: compliance 6.2 % and
    propagation RMS 10.9 % off; with d = h / 6, 1.5 % and 3.9 %)."""
    d, h = p["zone.particle_size"], p["geometry.arm_thickness"]
    if d > h / 6 * (1 + 1e-9):
        raise CaseError(f"zone.particle_size = {d:g}: coarser than a sixth of the arm (h = {h:g} m); "
                        f"allowed <= h / 6 = {h / 6:g} m")


SCENE_KEYS = {"Z0": "interface.Z0", "R0": "interface.R0", "GIc": "interface.GIc", "GIIc": "interface.GIIc",
              "E22": "material.E22", "N": "interface.cohesive_zone_bonds", "d": "zone.particle_size"}


def keys_of(mode: str, p: dict) -> dict:
    """Where a specimen keeps each value in ``mode``: the bonds' spacing is the particles' (coupled)
    or the FEM's element length (fem: the upper arm's when it is the finer, node to face)."""
    if mode == "coupled":
        return SCENE_KEYS
    upper = 0 < p["mesh.upper_element_length"] < (p["mesh.element_length"] or p["zone.particle_size"])
    return {**SCENE_KEYS, "d": "mesh.upper_element_length" if upper else "mesh.element_length"}


def resolved_strengths(p: dict, d: float, keys: dict = SCENE_KEYS) -> tuple[float, float]:
    """(Z0, R0) Pa used by the law: the given strengths, lowered where the cohesive zone would
    span fewer than interface.cohesive_zone_bonds bonds of length d. Turon, Davila, Camanho &
    Costa (2007), Eng. Fract. Mech. 74: l_cz = (9 pi / 32) E22 Gc / tau^2 (Rice's estimate);
    the LEFM peak load does not depend on the strength while l_cz is small against the crack.
    Turon's N = 3 ... 5 is for cohesive elements; these discrete bonds need more (measured on
    the coarse DCB, d = 0.5 mm: N = 5 gave the peak 7.7 % high and a propagation RMS error of
    12 %, N = 19 gave 0.1 % and 8 %), hence the default 20. Refused (CaseError) when a
    strength's elastic energy at initiation, tau^2 / (2 K) with K = E22 / d, exceeds its Gc:
    linear softening cannot start there. A mixed-mode specimen (interface.consistent_strengths)
    then lowers the stronger to R0 = Z0 sqrt(GIIc / GIc) (``consistent``). keys: where the case
    keeps each value (a study's names differ from the scenes')."""
    Z0, R0 = _capped(p, d, keys)
    if p.get("interface.consistent_strengths", False):  # a mixed-mode specimen's (Turon et al. 2010)
        Z0, R0 = consistent(Z0, R0, p[keys["GIc"]], p[keys["GIIc"]])
    K = p[keys["E22"]] / d
    for name, tau, gname in (("Z0", Z0, "GIc"), ("R0", R0, "GIIc")):
        key, gkey = keys[name], keys[gname]
        if p[gkey] < tau**2 / (2 * K):
            raise CaseError(f"{gkey} = {p[gkey]:g}: below the elastic energy at initiation {key}^2 / (2 K) = "
                            f"{tau**2 / (2 * K):.4g} J/m^2 (K = E22 / d, d = {d:g} m); allowed: {gkey} >= that, "
                            f"a lower {key}, or a smaller {keys['d']}")
    return Z0, R0


def _capped(p: dict, d: float, keys: dict) -> tuple[float, float]:
    """(Z0, R0) Pa: the given strengths lowered to interface.cohesive_zone_bonds bonds (N > 0)."""
    N, E22 = p[keys["N"]], p[keys["E22"]]
    Z0, R0 = p[keys["Z0"]], p[keys["R0"]]
    if N > 0:
        Z0, R0 = min(Z0, cap_strength(E22, p[keys["GIc"]], N, d)), min(R0, cap_strength(E22, p[keys["GIIc"]], N, d))
    return Z0, R0


def consistent(Z0: float, R0: float, GIc: float, GIIc: float) -> tuple[float, float]:
    """(Z0, R0) Pa with the stronger lowered to R0 = Z0 sqrt(GIIc / GIc): Turon, Camanho, Costa &
    Renart (2010), Compos. Struct. 92, 1857-1864: with one penalty stiffness for both modes, the
    B-K law dissipates the toughness of the mode mix the crack sees only if the strengths keep
    this ratio. Measured on an SLB (E11 = 40 GPa, GIc = 150 and GIIc = 300 J/m^2, h = 4 mm, Z0
    12.6 MPa after the zone rule): R0 = 10 / 14 / 17.8 MPa dissipated 0.90 / 0.97 / 1.01 x
    Gc(B) per crack area; at 10 MPa the crack ran at GIc (0.99 x), as if in mode I."""
    r = float(np.sqrt(GIIc / GIc))
    if R0 < Z0 * r * (1 - 1e-9):  # (both at the zone rule's caps: already in this ratio, kept as they are)
        return R0 / r, R0
    return Z0, min(R0, Z0 * r)


def cap_strength(E22: float, Gc: float, N: float, d: float) -> float:
    """Pa, the strength whose Rice cohesive zone (9 pi / 32) E22 Gc / tau^2 spans N bonds of length d."""
    return float(np.sqrt(9 * np.pi * E22 * Gc / (32 * N * d)))


def cohesive_zone_length(p: dict, Gc: float, tau: float, mode: str) -> float:
    """m, the cohesive zone length ahead of a crack between two arms of thickness h, in the
    slender-arm form of Yang & Cox (2005): (E11 h^3 Gc / tau^2)^(1/4) in mode I (the arm bends
    over the zone) and (E11 h Gc)^(1/2) / tau in mode II (the arms shear and stretch over it).
    An upper estimate: the zone measured in the runs (qoi cohesive_zone_bonds) has been about
    half of it (coarse DCB: 7 bonds against 15.6; coarse ENF: 9 against 16)."""
    E11, h = p["material.E11"], p["geometry.arm_thickness"]
    if mode == "I":
        return float((E11 * h**3 * Gc / tau**2) ** 0.25)
    return float(np.sqrt(E11 * h * Gc) / tau)


def strength_warnings(p: dict, d: float, keys: dict = SCENE_KEYS, fewest: dict | None = None) -> list[str]:
    """What the cohesive-zone rule changed, said before the run (summary.json "warnings"), and
    the strengths whose Rice zone spans fewer than ``fewest[key]`` bonds of length d (default 2
    for both), where initiation follows the strength rather than the toughness."""
    Z0, R0 = resolved_strengths(p, d, keys)
    fewest = {"interface.Z0": 2.0, "interface.R0": 2.0, **(fewest or {})}
    out = []
    for key, tau, gkey in (("interface.Z0", Z0, "interface.GIc"), ("interface.R0", R0, "interface.GIIc")):
        rice = 9 * np.pi / 32 * p["material.E22"] * p[gkey] / tau**2
        if rice < fewest[key] * d * (1 - 1e-9):
            out.append(f"{key} = {tau:.4g} Pa: its cohesive zone (Rice, {1e3 * rice:.3g} mm) spans fewer than "
                       f"{fewest[key]:g} bonds of d = {d:g} m, so initiation follows the strength rather than {gkey}; "
                       f"for the checks: interface.cohesive_zone_bonds >= {fewest[key]:g}, or a smaller {keys['d']}")
    capped = _capped(p, d, keys)
    for key, given, cap, used in (("interface.Z0", p["interface.Z0"], capped[0], Z0),
                                  ("interface.R0", p["interface.R0"], capped[1], R0)):
        if used < cap * (1 - 1e-9):
            out.append(f"{key} lowered from {given:.4g} to {used:.4g} Pa: R0 = Z0 sqrt(GIIc / GIc), the mixed-mode "
                       "law's condition (Turon et al. 2010), with the other strength")
        elif used < given:
            out.append(f"{key} lowered from {given:.4g} to {used:.4g} Pa: its cohesive zone then spans "
                       f"interface.cohesive_zone_bonds = {p['interface.cohesive_zone_bonds']:g} bonds of "
                       f"d = {d:g} m (Turon et al. 2007; LEFM loads do not depend on the strength)")
    return out


def crack_tip(bonds: LawBonds) -> float:
    """x (m) of the furthest fully debonded pair along the mid-plane (pairs of no area stand for
    no interface)."""
    failed = bonds.failed() & (bonds.area > 0)
    return float(bonds.X[bonds.pairs[failed, 0], 0].max()) if failed.any() else float("nan")


def softening_bonds(bonds: LawBonds) -> float:
    """Number of law pairs on their softening branch (0 < damage < 1): the cohesive zone,
    counted in bonds."""
    return float(np.count_nonzero((bonds.damage > 0.0) & (bonds.damage < 1.0) & (bonds.area > 0)))


def cohesive_zone_qoi(p: dict, h: dict, k: int, Gc: float, tau: float, mode: str, d: float) -> dict:
    """The cohesive zone in bonds: measured (the most pairs softening at once up to the peak
    load, sample k, when the zone has formed) and estimated (cohesive_zone_length / d, d the
    bonds' spacing m)."""
    zone = np.asarray(h.get("cohesive_zone_bonds", [np.nan]))[: k + 1]
    out = {"cohesive_zone_bonds": float(np.max(zone)) if zone.size else float("nan"),
           "cohesive_zone_bonds_estimate": cohesive_zone_length(p, Gc, tau, mode) / d}
    if "damage_at_zone_edge" in h:  # coupled: the window's last column, the most it was damaged
        out["damage_at_zone_edge"] = float(np.max(h["damage_at_zone_edge"]))
    if "window_end" in h:  # coupled: where the window ended last (m)
        out["window_end"] = float(np.asarray(h["window_end"])[-1])
    return out


def window_checks(qoi: dict) -> dict:
    """Coupled: the crack and its cohesive zone stayed inside the DEM window (no damage ever at
    its last column). A crack that reaches the window's edge is arrested by the elastic far
    field, and what it dissipates after that is the window's, not the specimen's."""
    if "damage_at_zone_edge" not in qoi:
        return {}
    return {"damage_at_zone_edge": bound(qoi["damage_at_zone_edge"], 0.0, "the crack stays inside the DEM window "
                                         "(damage at the window's last column, 0: none)")}


def plot_crack_and_window(ax, along: np.ndarray, h: dict) -> None:
    """The crack tip against ``along`` (the loading's measure), and a growing window's end."""
    ax.plot(along, 1e3 * np.asarray(h["crack_tip"]), label="crack tip")
    if "zone_half_width" in h:  # zone.grow: the DEM window's end as it grew
        ax.step(along, 1e3 * np.asarray(h["zone_half_width"]), where="post", label="DEM window's end")
        ax.legend()


def peak_before_growth(P: np.ndarray, tip: np.ndarray, a0: float, run: float) -> int:
    """Index of the largest load before the crack has run ``run`` m beyond a0 (the dynamic
    ringing after an unstable jump is not a peak of the quasi-static response)."""
    grown = np.flatnonzero(np.nan_to_num(tip, nan=-np.inf) > a0 + run)
    end = grown[0] if grown.size else len(P)
    return int(np.argmax(P[: max(end, 1)]))


def initial_compliance(P: np.ndarray, delta: np.ndarray, k: int, upto: float) -> float:
    """m/N, slope of displacement against load from 10 % to ``upto`` of the peak P[k], before it."""
    early = (P > 0.1 * P[k]) & (P < upto * P[k]) & (np.arange(len(P)) < k)
    return float(np.polyfit(P[early], delta[early], 1)[0]) if early.sum() > 3 else float("nan")


def growth_and_dissipation(p: dict, tip: np.ndarray, D: np.ndarray, after: np.ndarray, Gc: float,
                           d: float) -> tuple[float, float]:
    """(crack growth m, dissipated energy per new crack area / Gc): the slope of the interface's
    dissipation against the debonded area b x tip over the samples ``after`` (bool) where the
    crack has run more than 4 bond spacings d (m; the process zone has formed)."""
    a0 = p["geometry.crack_length"]
    growth = float(np.nanmax(tip) - a0) if np.isfinite(tip).any() else 0.0
    grow = after & np.isfinite(tip) & (tip > a0 + 4 * d)
    if grow.sum() > 3 and np.ptp(tip[grow]) > 0:
        return growth, float(np.polyfit(p["geometry.width"] * tip[grow], D[grow], 1)[0] / Gc)
    return growth, float("nan")


def check_pace(p: dict, factor_key: str, periods: tuple[float, float]) -> None:
    """Refuse (CaseError) a loading whose peak load comes after fewer or more than ``periods``
    (low, high) periods of the specimen's mode: load.duration_periods / the final opening or
    deflection factor (``factor_key``), the periods spent before the closed form's peak."""
    n, f = p["load.duration_periods"], p[factor_key]
    if not periods[0] * (1 - 1e-9) <= n / f <= periods[1] * (1 + 1e-9):
        raise CaseError(f"load.duration_periods = {n:g}: with {factor_key} = {f:g} the peak load comes after "
                        f"{n / f:.3g} periods, outside the quasi-static {periods[0]:g} to {periods[1]:g}; allowed: "
                        f"load.duration_periods {periods[0] * f:.4g} to {periods[1] * f:.4g}")


def damping_alpha(p: dict, omega: float) -> float:
    """Mass-proportional damping coefficient (1/s) for the ratio damping.ratio at omega."""
    return 2.0 * p["damping.ratio"] * omega


def cantilever_omega(p: dict, a: float) -> float:
    """First bending frequency (rad/s) of one arm as a cantilever of length a."""
    h, E, rho = p["geometry.arm_thickness"], p["material.E11"], p["material.rho"]
    return 1.8751**2 * np.sqrt(E * h**2 / (12 * rho)) / a**2


def fem_factory(spec: Specimen, supports, alpha: float):
    def make(extra_mass):
        return ExplicitDynamics(spec.region, supports=supports, alpha=alpha, extra_mass=extra_mass)
    return make
