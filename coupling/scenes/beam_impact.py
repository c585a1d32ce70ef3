"""The base of beam_impact_3d (its parameters, laminate, evaluation and plots). The 2D case
itself is now a study, cases/seed/beam_impact.toml; this module goes when beam_impact_3d
becomes one (issue #23).

beam_impact: the seed paper's example 5.1, a clamped [0_6/90_4/0_6] graphite/epoxy beam
struck along its centre line by a rigid cylinder (2D plane strain, half model by symmetry;
the 3D variant is beam_impact_3d).

Dimensions are not in the paper (nor in the text of its reference, Geubelle & Baylor 1998);
the choices, fixed here and in cases/seed/beam_impact.toml: plies 0.15 mm (laminate 2.4 mm),
clamped span 50 mm (half model 25 mm), a steel cylinder of radius 5 mm (0.617 kg per metre of
width) at 10 m/s. Why: the paper's pictures end at 0.6 ms, which this beam's impact spans
(spring-mass contact time ~0.16 ms, then free vibration); a 5 m/s impact puts the peak
interlaminar shear near R0 = 20 MPa (marginal), 10 m/s well above it, so delaminations grow
at both 0/90 interfaces and the 90 plies crack, the two damage modes the paper shows.

Modes (the same beam, impactor and clamps):
- coupled: DEM zone |x| < dem.half_width through the whole thickness (ply lattice with the
  Hoffman intralaminar law, Hashin interlaminar bonds at the 0/90 interfaces, impactor on the
  particles), FEM laminate elsewhere, kinematic tie at x = dem.half_width;
- fem: all FEM, no damage (the cheap bound), impactor on the FEM surface nodes;
- dem: all particles (the expensive reference for the coupled model).

qoi: peak centre displacement (bottom face, x = 0) and its time, peak contact force (whole
width, whole beam), delamination length per 0/90 interface at the end (debonded, and damaged
d > 0; whole beam), matrix cracks in the 90 plies, model size against the reference study's
33,180 LST + 23,773 cohesive elements, and damage_at_zone_edge: the largest interlaminar
damage in the last columns before the tie. The FEM far field cannot delaminate, so a value
near 1 says the damage reached the zone's edge and the zone must widen. It does here: in
three-point bending the shear force is uniform along the span, and at 10 m/s the
interlaminar shear (~50 MPa at the 0/90 interfaces) exceeds R0 = 20 MPa all along it, so
the interfaces soften far from the impact (measured: damaged over 16 / 23 mm of the beam
with 8 / 12 mm half-widths). A narrower zone is cheaper and wrong. Checks (computed from the run's own parameters): the energy balance, and
the peak centre displacement against the spring-mass estimate delta = v sqrt(M / k) with the
clamped-clamped beam stiffness k = 192 D / L^3 and M the impactor mass plus 0.37 of the
beam's, within 30 % (an estimate: the contact is not quasi-static and damage softens the
beam; a broken model misses it by far more).
"""
from __future__ import annotations

import numpy as np

from dem_region import ply_lattice
from physics.law_bonds import LawBonds
from dem_region.particle_impactor import ParticleImpactor
from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from physics.impactor import RigidImpactor

from ..checks import check, energy_balance
from ..params import CaseError, Param, density, modulus, positive
from ..participants.fem import FEM_OPTIONS, fem_only, make_region
from ..participants.coupled import COUPLING, coupled_simulation
from .ply_fracture import PLY, ply_material
from ..participants.dem import dem_only

NAME = "beam_impact"
DESCRIPTION = "seed 5.1: clamped [0_6/90_4/0_6] beam, rigid cylinder impact, delamination + matrix cracks"
MODES = ("coupled", "fem", "dem")
REFERENCE_ELEMENTS = 33180 + 23773  # Geubelle & Baylor (1998): LST + cohesive elements

PARAMETERS = {
    **PLY,  # Table 1 moduli and density below; strengths and fracture energies of PLY (not in Table 1)
    "material.nu12": Param(0.228, "major Poisson ratio (Table 1)", low=0.0, high=0.49),
    "material.nu23": Param(0.4, "transverse Poisson ratio (Table 1)", low=0.0, high=0.49),
    "interface.GIc": Param(147.0, "mode I toughness (Table 1)", unit="J/m^2", low=0.0, open_low=True),
    "interface.GIIc": Param(526.0, "mode II toughness (Table 1)", unit="J/m^2", low=0.0, open_low=True),
    "interface.Z0": positive(40e6, "interlaminar normal strength (Table 1)", "Pa"),
    "interface.R0": positive(20e6, "interlaminar shear strength (Table 1)", "Pa"),
    "interface.friction": Param(0.3, "Coulomb friction of delaminated faces", low=0.0, high=2.0),
    "laminate.layup": Param("[0_6/90_4/0_6]", "layup, bottom up: [ANGLE_COUNT/...] with an optional repeat "
                            "and s (symmetric), e.g. [0_6/90_4/0_6] or [0/90_2]2s; 0 and 90 plies", kind="str",
                            check=materials.parse_layup),
    "laminate.ply_thickness": positive(0.15e-3, "ply thickness", "m"),
    # geometry and impact: the ranges over which the checks are verified (tests/test_seed.py
    # samples them; a perforating impact, 16 m/s x 1.15 kg/m on a 32 mm half span, is outside)
    "geometry.half_span": Param(25e-3, "clamp to centre line", unit="m", low=20e-3, high=40e-3),
    "geometry.width": positive(25e-3, "beam width (out of plane), for forces of the whole beam", "m"),
    "impactor.radius": Param(5e-3, "cylinder radius", unit="m", low=3e-3, high=8e-3),
    "impactor.mass_per_width": Param(0.617, "cylinder mass per metre of width (steel, r = 5 mm)", unit="kg/m",
                                     low=0.3, high=1.2),
    "impactor.velocity": Param(10.0, "impact speed", unit="m/s", low=1.0, high=12.0),
    "impactor.penalty": Param(0.0, "contact penalty per particle / node; 0 = the lattice's transverse bond "
                              "stiffness E_y t", unit="N/m", low=0.0),
    "impactor.friction": Param(0.2, "impactor friction", low=0.0, high=2.0),
    "dem.half_width": positive(12e-3, "half width of the DEM zone around the centre line (the interfaces soften "
                               "wherever the shear exceeds R0: qoi damage_at_zone_edge tells if the zone is too narrow)",
                               "m"),
    "dem.plies_per_row": Param(1, "plies per particle row (the particle size is this x ply thickness)",
                               kind="int", low=1, high=8),
    "mesh.element_ratio": Param(6.0, "largest / smallest FEM element length (graded from the DEM zone)",
                                low=1.0, high=100.0),
    "mesh.elements_along": Param(30, "FEM elements along the half span outside the DEM zone", kind="int", low=2),
    **{k: v for k, v in FEM_OPTIONS.items() if k not in ("mesh.element", "fem.hypothesis")},
    **COUPLING,
}
PARAMETERS["material.E11"] = modulus(156e9, "ply modulus along the fibres (Table 1)")
PARAMETERS["material.E22"] = modulus(9.09e9, "transverse ply modulus (Table 1)")
PARAMETERS["material.rho"] = density(1540.0, "ply density (Table 1)")


# -- laminate ---------------------------------------------------------------------------------
def blocks(p: dict) -> tuple[list[float], list[int]]:
    """(angle, plies) of each run of equal plies, bottom up: [0_6/90_4/0_6] -> [0, 90, 0], [6, 4, 6]."""
    try:
        angles = materials.parse_layup(p["laminate.layup"])
    except ValueError as exc:
        raise CaseError(f"laminate.layup = {p['laminate.layup']!r}: {exc}") from None
    if any(a not in (0.0, 90.0) for a in angles):
        raise CaseError(f"laminate.layup = {p['laminate.layup']!r}: a beam slice takes 0 and 90 plies only")
    out_a, out_n = [], []
    for a in angles:
        if out_a and out_a[-1] == a:
            out_n[-1] += 1
        else:
            out_a.append(a)
            out_n.append(1)
    k = p["dem.plies_per_row"]
    if any(n % k for n in out_n):
        raise CaseError(f"dem.plies_per_row = {k}: must divide every ply block of {p['laminate.layup']} ({out_n})")
    return out_a, out_n


def ply_D(p: dict, angle: float) -> np.ndarray:
    """(3, 3) plane-strain stiffness Pa of a ply at ``angle`` in the beam slice."""
    C = materials.orthotropic(p["material.E11"], p["material.E22"], p["material.E22"], p["material.nu12"],
                              p["material.nu12"], p["material.nu23"], p["material.G12"], p["material.G12"],
                              p["material.G23"])
    return materials.plane_strain(materials.rotate(C, materials.ply_axes(angle, 2)))


def thickness(p: dict) -> float:
    return sum(blocks(p)[1]) * p["laminate.ply_thickness"]


def fem_region(p: dict, x0: float, t: float):
    """FEM laminate on [x0, half_span] x [0, H], one element row per particle row."""
    angles, plies = blocks(p)
    k, tp = p["dem.plies_per_row"], p["laminate.ply_thickness"]
    H, L = thickness(p), p["geometry.half_span"]
    n = p["mesh.elements_along"]
    ratio = p["mesh.element_ratio"] ** (1.0 / max(n - 1, 1))
    xs = mesh.graded(x0, L, n, ratio, x0)
    ys = np.linspace(0.0, H, sum(plies) // k + 1)
    m = mesh.rectangle(xs, ys, "quad4")
    cy = m.p[1, m.t].mean(axis=0)
    bounds = np.cumsum(plies) * tp
    block = np.searchsorted(bounds, cy)
    D = np.array([ply_D(p, angles[b]) for b in block])
    return make_region(m, p, D, p["material.rho"], t)


def bending_stiffness(p: dict) -> float:
    """D (N m) of the laminate per unit width, plane strain: sum E_x,b z^2 dz about the centroid."""
    angles, plies = blocks(p)
    tp, H = p["laminate.ply_thickness"], thickness(p)
    z = np.cumsum([0] + plies) * tp - H / 2
    D = 0.0
    for a, z0, z1 in zip(angles, z[:-1], z[1:]):
        Ex = ply_lattice.slice_moduli(ply_D(p, a))[0]
        D += Ex * (z1**3 - z0**3) / 3
    return D


def spring_mass_estimate(p: dict) -> float:
    """Peak centre deflection (m) of a clamped-clamped beam hit by a rigid mass, quasi-static
    stiffness 192 D / L^3 (L the span), effective beam mass 0.37 of the beam's."""
    span = 2 * p["geometry.half_span"]
    k = 192 * bending_stiffness(p) / span**3
    M = p["impactor.mass_per_width"] + 0.37 * p["material.rho"] * thickness(p) * span
    return p["impactor.velocity"] * np.sqrt(M / k)


# -- the particle zone ------------------------------------------------------------------------
def lattice(p: dict, x_end: float):
    """Ply lattice on [0, x_end] (the last column at x_end) x [0, H]."""
    angles, plies = blocks(p)
    k = p["dem.plies_per_row"]
    d = k * p["laminate.ply_thickness"]
    mat = ply_material(p)
    mat = ply_lattice.PlyMaterial(mat.E11, mat.E22, mat.G12, mat.G23, mat.rho, mat.strengths, mat.Gf_fibre,
                                  mat.Gf_matrix, moduli={a: ply_lattice.slice_moduli(ply_D(p, a)) for a in set(angles)})
    n_col = int(round(x_end / d)) + 1
    lat = ply_lattice.build(0.0, n_col, 0.0, [n // k for n in plies], angles, d, mat)
    return lat, d


def particle_zone(p: dict, x_end: float, clamp_last: bool):
    """(lattice, scene, intralaminar LawBonds, interlaminar LawBonds, impactor): half model.
    Column 0 lies on the symmetry plane and the last column on the FEM face (coupled): half
    of their cells are outside the zone, so they carry half the mass and their vertical
    bonds half the area."""
    lat, d = lattice(p, x_end)
    t = d
    on_axis = (lat.column == 0) | ((lat.column == lat.column.max()) & (not clamp_last))
    both = on_axis[lat.intra_pairs].all(axis=1)
    intra_area = np.where(both, 0.5, 1.0) * d * t
    l = lat.x[lat.intra_pairs[:, 1]] - lat.x[lat.intra_pairs[:, 0]]
    vol = lat.cell_volume() * np.where(on_axis, 0.5, 1.0)
    intra = LawBonds(lat.intra_pairs, lat.x, l, intra_area, lat.intra_law, volume=vol, label="intralaminar")
    Z0, R0 = p["interface.Z0"], p["interface.R0"]
    law = ply_lattice.interlaminar_law(lat, Z0, R0, p["interface.GIc"], p["interface.GIIc"])
    inter_area = np.where(on_axis[lat.inter_pairs].all(axis=1), 0.5, 1.0) * d * t
    inter = LawBonds(lat.inter_pairs, lat.x, np.tile([0.0, 1.0, 0.0], (len(lat.inter_pairs), 1)), inter_area, law,
                     friction=p["interface.friction"], label="interlaminar", along=lat.inter_along)
    density_ = lat.density * np.where(on_axis, 0.5, 1.0)
    groups = {}
    last = np.flatnonzero(lat.column == lat.column.max())
    if clamp_last:
        groups["fixed"] = last
    else:
        groups["interface"] = last
    from .ply_fracture import engine_scene
    lat.density = density_
    scene = engine_scene(lat, groups=groups)
    # the impactor: half of it (the symmetry plane cuts it), its x motion held
    H = thickness(p)
    R, r = p["impactor.radius"], lat.radius
    E_y = min(ply_lattice.slice_moduli(ply_D(p, a))[1] for a in blocks(p)[0])
    k_pen = p["impactor.penalty"] or E_y * t
    top = np.flatnonzero(lat.row >= lat.row.max() - 1)
    imp = RigidImpactor("sphere", np.array([0.0, H - d / 2 + R + r + 1e-9, 0.0]), R + r,
                        0.5 * p["impactor.mass_per_width"] * t, np.array([0.0, -p["impactor.velocity"], 0.0]), k_pen,
                        friction=p["impactor.friction"])
    impactor = ParticleImpactor(imp, top, fixed=(True, False, True))
    return lat, scene, intra, inter, impactor


def _damage_probes(p, lat, intra, inter):
    angles, _ = blocks(p)
    ply_angle = np.array(angles)[lat.ply]
    in_90 = (ply_angle[lat.intra_pairs] == 90).all(axis=1)
    # interlaminar pairs grouped by interface (the row below the interface)
    iface_row = lat.row[lat.inter_pairs[:, 0]]
    rows = np.unique(iface_row)
    d = lat.d
    weight = np.where(lat.column[lat.inter_pairs[:, 0]] == 0, 0.5, 1.0) * d * 2  # whole beam (both halves)
    weight[lat.column[lat.inter_pairs[:, 0]] == lat.column.max()] = 0.0  # the tied column: on the FEM face
    probes = {f"delamination_length_{k}": (lambda sel=(iface_row == r): float(weight[sel] @ inter.failed()[sel]))
              for k, r in enumerate(rows)}
    probes.update({f"damaged_interface_length_{k}": (lambda sel=(iface_row == r): float(weight[sel] @ (inter.damage[sel] > 0)))
                   for k, r in enumerate(rows)})
    probes["matrix_cracks"] = lambda: float(np.sum(intra.failed() & in_90))
    # damage must stay inside the particle zone: the last columns before the tie (or clamp)
    edge = lat.column[lat.inter_pairs[:, 0]] >= lat.column.max() - 2
    probes["damage_at_zone_edge"] = lambda: float(inter.damage[edge].max()) if edge.any() else 0.0
    probes["failed_intralaminar"] = lambda: float(np.sum(intra.failed()))
    return probes


def build(p: dict, mode: str, dem: str):
    H, L = thickness(p), p["geometry.half_span"]
    t = p["dem.plies_per_row"] * p["laminate.ply_thickness"]
    width_factor = 2 * p["geometry.width"] / t  # whole width, whole beam
    t_end = 0.6e-3
    if mode == "fem":
        return _build_fem(p, t, width_factor, t_end)
    w = L if mode == "dem" else p["dem.half_width"]
    if mode == "coupled" and not 2 * t < w < 0.8 * L:
        raise CaseError(f"dem.half_width = {w:g}: allowed between two particle sizes ({2 * t:g} m) and 0.8 x half span")
    lat, scene, intra, inter, impactor = particle_zone(p, w, clamp_last=(mode == "dem"))
    models = (intra, inter, impactor)
    axis = np.flatnonzero(lat.column == 0)
    if mode == "dem":
        sim, backend, _ = dem_only(p, scene, dem, t_end, models=models)
        fem_count = (0, 0)
    else:
        def make(extra_mass):
            region = fem_region(p, lat.x[:, 0].max(), t)
            clamp = np.flatnonzero(np.abs(region.X[:, 0] - L) < 1e-9 * L)
            return ExplicitDynamics(region, supports=[PrescribedMotion(np.concatenate([2 * clamp, 2 * clamp + 1]))],
                                    extra_mass=extra_mass)
        sim, clock = coupled_simulation(p, make, scene, dem, t_end, models=models)
        backend = clock.dem
        fem_count = (clock.fem.region.n_elements, clock.fem.region.n_nodes)
    backend.prescribe(axis, "x")  # the symmetry plane
    backend.set_velocities(axis, np.zeros((len(axis), 3)))
    bottom = axis[np.argmin(lat.x[axis, 1])]
    sim.probes.update({
        "centre_displacement": lambda: -float(backend.positions_of(np.array([bottom]))[0, 1] - lat.x[bottom, 1]),
        "contact_force": lambda: float(impactor.force[1] * width_factor),
        "impactor_velocity": lambda: float(impactor.imp.v[1]),
        "model_size": lambda: float(fem_count[0] + lat.n),  # elements + particles
        **_damage_probes(p, lat, intra, inter),
    })
    sim.counts.update({"law_bonds": len(intra.pairs) + len(inter.pairs)})
    for t_snap in (0.1e-3, 0.6e-3):
        sim.snapshots[f"damage_{round(t_snap * 1e6)}us"] = (t_snap, lambda: {
            "x": backend.positions(), "intra_failed": intra.failed().astype(float),
            "inter_failed": inter.failed().astype(float), "inter_damage": inter.damage.copy(),
            "intra_damage": intra.damage.copy(), "intra_pairs": intra.pairs.astype(float),
            "inter_pairs": inter.pairs.astype(float), "in_90": (np.array(blocks(p)[0])[lat.ply] == 90).astype(float)})
    return sim


def _build_fem(p, t, width_factor, t_end):
    L = p["geometry.half_span"]
    H = thickness(p)
    region = fem_region(p, 0.0, t)
    X = region.X
    clamp = np.flatnonzero(np.abs(X[:, 0] - L) < 1e-9 * L)
    axis = np.flatnonzero(X[:, 0] < 1e-9 * L)
    R = p["impactor.radius"]
    top = X[:, 1] > H - 1e-9 * H
    h_node = np.diff(np.unique(X[top, 0])).min()
    E_y = min(ply_lattice.slice_moduli(ply_D(p, a))[1] for a in blocks(p)[0])
    k_pen = (p["impactor.penalty"] or E_y * t) * max(1.0, h_node / t)
    imp = RigidImpactor("cylinder", np.array([0.0, H + R + 1e-9]), R, 0.5 * p["impactor.mass_per_width"] * t,
                        np.array([0.0, -p["impactor.velocity"]]), k_pen, friction=p["impactor.friction"])
    dyn = ExplicitDynamics(region, supports=[PrescribedMotion(np.concatenate([2 * clamp, 2 * clamp + 1])),
                                             PrescribedMotion(2 * axis)], impactors=[imp])
    bottom = axis[np.argmin(X[axis, 1])]
    probes = {"centre_displacement": lambda: -float(dyn.state.u[bottom, 1]),
              "model_size": lambda: float(region.n_elements),
              "contact_force": lambda: float(imp.a[1] * imp.mass * width_factor),
              "impactor_velocity": lambda: float(imp.v[1])}
    return fem_only(dyn, p, t_end, probes)


def evaluate(p: dict, h: dict, mode: str):
    u, F, time = np.asarray(h["centre_displacement"]), np.asarray(h["contact_force"]), np.asarray(h["time"])
    k = int(np.argmax(u))
    qoi = {"peak_centre_displacement": float(u[k]), "time_of_peak_displacement": float(time[k]),
           "peak_contact_force": float(F.max()), "spring_mass_estimate": spring_mass_estimate(p)}
    for key in h:
        if key.startswith(("delamination_length_", "damaged_interface_length_")) or key in ("matrix_cracks",
                                                                                           "failed_intralaminar"):
            qoi[key] = float(np.asarray(h[key])[-1])
    qoi["model_size"] = float(h["model_size"][-1])
    if "damage_at_zone_edge" in h:
        qoi["damage_at_zone_edge"] = float(np.max(h["damage_at_zone_edge"]))
    qoi["model_size_vs_reference"] = qoi["model_size"] / REFERENCE_ELEMENTS
    checks = {
        "peak_centre_displacement": check(qoi["peak_centre_displacement"], qoi["spring_mass_estimate"], 0.30,
                                          "spring-mass estimate v sqrt(M / k), k = 192 D / L^3 (an estimate)"),
        "energy_balance": energy_balance(h),
    }
    return qoi, checks


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    time = 1e3 * np.asarray(h["time"])
    fig, ax = plt.subplots(1, 3, figsize=(14, 4))
    ax[0].plot(time, 1e3 * np.asarray(h["centre_displacement"]))
    ax[0].axhline(1e3 * qoi["spring_mass_estimate"], color="k", ls=":", label="spring-mass estimate")
    ax[0].set(xlabel="time (ms)", ylabel="centre displacement (mm)")
    ax[0].legend()
    ax[1].plot(time, 1e-3 * np.asarray(h["contact_force"]))
    ax[1].set(xlabel="time (ms)", ylabel="contact force (kN, whole beam)")
    for key in sorted(k for k in h if k.startswith("delamination_length_")):
        ax[2].plot(time, 1e3 * np.asarray(h[key]), label=f"interface {key.rsplit('_', 1)[1]}")
    ax[2].set(xlabel="time (ms)", ylabel="delamination length (mm)")
    if any(k.startswith("delamination_length_") for k in h):
        ax[2].legend()
    fig.tight_layout()
    fig.savefig(plots_dir / "histories.png", dpi=120)
    plt.close(fig)
    for name in sorted({k.split(".")[0] for k in h if k.startswith("damage_") and "." in k}):
        _damage_picture(h, name, plots_dir)


def _damage_picture(h: dict, name: str, plots_dir):
    """Particles (deformed), intralaminar bonds by damage (reds: 90 plies, oranges: 0 plies)
    and interlaminar bonds by damage (blues; full colour = debonded)."""
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    x = 1e3 * np.asarray(h[f"{name}.x"])
    in_90 = np.asarray(h[f"{name}.in_90"]) > 0
    fig, ax = plt.subplots(figsize=(12, 3.2))
    ax.plot(x[:, 0], x[:, 1], ".", ms=1.5, color="0.7")
    for kind in ("intra", "inter"):
        pairs = np.asarray(h[f"{name}.{kind}_pairs"]).astype(int)
        dmg = np.asarray(h[f"{name}.{kind}_damage"])
        hit = dmg > 0.05
        if not hit.any():
            continue
        segs = x[pairs[hit]][:, :, :2]
        if kind == "inter":
            colors = plt.cm.Blues(0.3 + 0.7 * dmg[hit])
        else:
            ninety = in_90[pairs[hit]].all(axis=1)
            colors = np.where(ninety[:, None], plt.cm.Reds(0.3 + 0.7 * dmg[hit]), plt.cm.Oranges(0.3 + 0.7 * dmg[hit]))
        ax.add_collection(LineCollection(segs, colors=colors, linewidths=1.5))
    ax.set(xlabel="x (mm)", ylabel="y (mm)", title=f"damage at {name.split('_')[1]}: interlaminar (blue) and "
           "intralaminar (red: 90 plies, orange: 0 plies), darker = more damaged")
    ax.set_aspect("equal")
    fig.tight_layout()
    fig.savefig(plots_dir / f"{name}.png", dpi=120)
    plt.close(fig)
