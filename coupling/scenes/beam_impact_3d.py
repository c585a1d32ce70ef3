"""beam_impact_3d: the seed paper's example 5.1 in 3D, the variant of beam_impact.

The same clamped [0_6/90_4/0_6] beam, cylinder, materials and laws as beam_impact (its
docstring has the dimensions and why), in 3D: a quarter of the beam (symmetry planes at the
centre line x = 0 and at mid-width y = 0), free edges at y = W / 2, the thickness along z.
The 0 plies have their fibres along the span (x), the 90 plies across the width (y): in the
plane-strain slice they point out of its plane. What 3D adds: the free edges (the slice is an
infinitely wide beam) and delaminations that may grow unevenly across the width.

Width: 24 mm (the 2D case's 25 mm rounded so that the half width is a whole number of
particles at one and two plies per row); the model's half width must be a whole number of
particle spacings.

Modes (the same beam, cylinder and clamps):
- coupled: a 3D ply lattice (dem_region/ply_block.py) for |x| < dem.half_width through the
  thickness and the whole width: Hoffman intralaminar bonds, Hashin interlaminar bonds at
  the 0/90 interfaces with rotation-free slip along x and y, the cylinder on the particles;
  Hex8 laminate elsewhere, kinematic tie at x = dem.half_width;
- fem: all Hex8, no damage, the cylinder on the FEM surface nodes;
- dem: all particles.

qoi: as beam_impact; delamination_length_k is the debonded area of interface k (whole beam)
over the beam width, a mean length, with delamination_area_k beside it; matrix_cracks counts
failed bonds in the 90 plies of the modelled quarter. Checks: the energy balance and the peak
centre displacement against beam_impact's spring-mass estimate (the plane-strain bending
stiffness is within 0.3 % of the uniaxial one for these plies), within 30 %.
"""
from __future__ import annotations

import numpy as np

from dem_region import ply_block
from physics.law_bonds import LawBonds
from dem_region.particle_impactor import ParticleImpactor
from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from physics.impactor import RigidImpactor

from ..params import CaseError, Param, positive
from . import beam_impact
from .beam_impact import blocks, thickness
from ..participants.dem import hold_symmetry_planes
from ..participants.fem import fem_only, make_region
from ..participants.coupled import coupled_simulation
from .ply_fracture import ply_material
from ..participants.dem import dem_only

NAME = "beam_impact_3d"
DESCRIPTION = "seed 5.1 in 3D: a quarter of the clamped beam, free edges, cylinder impact"
MODES = ("coupled", "fem", "dem")
T_END = 0.6e-3

PARAMETERS = {
    **beam_impact.PARAMETERS,
    "geometry.width": positive(24e-3, "beam width; the model is half of it (symmetry at mid-width), free edges",
                               "m"),
    "mesh.elements_width": Param(4, "Hex8 elements across the modelled half width", kind="int", low=1, high=200),
    # the 3D beam's span is the size knob of the scaling benchmarks (benchmarks/coupled_step.py):
    # open, as its checks are not sampled over it (the 2D beam's are, 20 to 40 mm)
    "geometry.half_span": positive(25e-3, "clamp to centre line", "m"),
}


def ply_C(p: dict, angle: float) -> np.ndarray:
    """(6, 6) Pa of a ply in the beam's axes (x span, y width, z thickness): fibres along x
    (0) or y (90)."""
    C = materials.orthotropic(p["material.E11"], p["material.E22"], p["material.E22"], p["material.nu12"],
                              p["material.nu12"], p["material.nu23"], p["material.G12"], p["material.G12"],
                              p["material.G23"])
    return materials.rotate(C, materials.ply_axes(angle, 3))


def spacing(p: dict) -> tuple[float, int]:
    """(particle spacing d m, particle columns across the modelled half width)."""
    d = p["dem.plies_per_row"] * p["laminate.ply_thickness"]
    half = 0.5 * p["geometry.width"]
    m = half / d
    if abs(m - round(m)) > 1e-6 or round(m) < 1:
        raise CaseError(f"geometry.width = {p['geometry.width']:g}: half of it must be a whole number of particle "
                        f"spacings ({d:g} m); allowed e.g. {2 * max(1, round(m)) * d:g} m")
    return d, int(round(m)) + 1


def fem_region(p: dict, x0: float):
    """Hex8 laminate on [x0, half_span] x [0, W / 2] x [0, H], one element layer per particle row."""
    angles, plies = blocks(p)
    k, tp = p["dem.plies_per_row"], p["laminate.ply_thickness"]
    H, L, n = thickness(p), p["geometry.half_span"], p["mesh.elements_along"]
    ratio = p["mesh.element_ratio"] ** (1.0 / max(n - 1, 1))
    m = mesh.box(mesh.graded(x0, L, n, ratio, x0), np.linspace(0.0, 0.5 * p["geometry.width"],
                                                               p["mesh.elements_width"] + 1),
                 np.linspace(0.0, H, sum(plies) // k + 1), "hex8")
    block = np.searchsorted(np.cumsum(plies) * tp, m.p[2, m.t].mean(axis=0))
    C = np.array([ply_C(p, angles[b]) for b in block])
    return make_region(m, p, C, p["material.rho"], 1.0)


def supports(region, p: dict, symmetry_x: bool) -> list[PrescribedMotion]:
    """Clamp at x = half span, symmetry at mid-width (and at the centre line when the FEM reaches it)."""
    X, L = region.X, p["geometry.half_span"]
    clamp = np.flatnonzero(np.abs(X[:, 0] - L) < 1e-9 * L)
    out = [PrescribedMotion(np.concatenate([3 * clamp + c for c in range(3)])),
           PrescribedMotion(3 * np.flatnonzero(np.abs(X[:, 1]) < 1e-9 * L) + 1)]
    if symmetry_x:
        out.append(PrescribedMotion(3 * np.flatnonzero(np.abs(X[:, 0]) < 1e-9 * L)))
    return out


def particle_zone(p: dict, x_end: float, clamp_last: bool):
    """(block, scene, intralaminar LawBonds, interlaminar LawBonds, cylinder on the particles)
    on [0, x_end] x [0, W / 2] x [0, H]; half cells on the symmetry planes, the free edge and
    (coupled) the tied face."""
    angles, plies = blocks(p)
    k = p["dem.plies_per_row"]
    d, M = spacing(p)
    N = int(round(x_end / d)) + 1
    half = [(0, 0), (1, 0), (1, M - 1)] + ([] if clamp_last else [(0, N - 1)])
    try:
        block = ply_block.build((0.0, 0.0, 0.0), (N, M), [n // k for n in plies], angles, d, ply_material(p),
                                half_planes=half)
    except ValueError as exc:
        raise CaseError(f"material.G12 = {p['material.G12']:g}: {exc}") from None
    l = block.x[block.intra_pairs[:, 1]] - block.x[block.intra_pairs[:, 0]]
    intra = LawBonds(block.intra_pairs, block.x, l, block.intra_area, block.intra_law, volume=block.volume,
                     label="intralaminar")
    law = ply_block.interlaminar_law(block, p["interface.Z0"], p["interface.R0"], p["interface.GIc"],
                                     p["interface.GIIc"])
    inter = LawBonds(block.inter_pairs, block.x, np.tile([0.0, 0.0, 1.0], (len(block.inter_pairs), 1)),
                     block.inter_area, law, friction=p["interface.friction"], along=block.inter_along,
                     label="interlaminar")
    last = np.flatnonzero(block.index[:, 0] == N - 1)
    scene = ply_block.engine_scene(block, groups={("fixed" if clamp_last else "interface"): last})
    H, R, r = thickness(p), p["impactor.radius"], block.radius
    k_pen = p["impactor.penalty"] or p["material.E22"] * d
    top = np.flatnonzero(block.index[:, 2] >= block.index[:, 2].max() - 1)
    cyl = RigidImpactor("cylinder", np.array([0.0, 0.0, H - d / 2 + R + r + 1e-9]), R + r,
                        0.25 * p["impactor.mass_per_width"] * p["geometry.width"],
                        np.array([0.0, 0.0, -p["impactor.velocity"]]), k_pen, friction=p["impactor.friction"],
                        axis=np.array([0.0, 1.0, 0.0]))
    return block, scene, intra, inter, ParticleImpactor(cyl, top, fixed=(True, True, False))


def build(p: dict, mode: str, dem: str):
    if mode == "fem":
        return _build_fem(p)
    L = p["geometry.half_span"]
    d, _ = spacing(p)
    w = L if mode == "dem" else p["dem.half_width"]
    if mode == "coupled" and not 2 * d < w < 0.8 * L:
        raise CaseError(f"dem.half_width = {w:g}: allowed between two particle sizes ({2 * d:g} m) and 0.8 x half span")
    block, scene, intra, inter, impactor = particle_zone(p, w, clamp_last=(mode == "dem"))
    models = (intra, inter, impactor)
    if mode == "dem":
        sim, backend, _ = dem_only(p, scene, dem, T_END, models=models)
        n_elements = 0
    else:
        x_end = float(block.x[:, 0].max())

        def make(extra_mass):
            region = fem_region(p, x_end)
            return ExplicitDynamics(region, supports=supports(region, p, symmetry_x=False), extra_mass=extra_mass)
        sim, clock = coupled_simulation(p, make, scene, dem, T_END, models=models)
        backend, n_elements = clock.dem, clock.fem.region.n_elements
    i, j, k = block.index.T
    held = np.concatenate([scene.groups.get("interface", []), scene.groups.get("fixed", [])]).astype(int)
    hold_symmetry_planes(backend, i, j, held)
    bottom = np.flatnonzero((i == 0) & (j == 0) & (k == 0))[0]
    z0 = block.x[bottom, 2]
    sim.probes.update({
        "centre_displacement": lambda: -float(backend.positions_of(np.array([bottom]))[0, 2] - z0),
        "contact_force": lambda: float(4 * impactor.force[2]),  # whole beam
        "impactor_velocity": lambda: float(impactor.imp.v[2]),
        "model_size": lambda: float(n_elements + block.n),
        **_damage_probes(p, block, intra, inter),
    })
    sim.counts.update({"law_bonds": len(intra.pairs) + len(inter.pairs)})
    in_90 = (np.array(blocks(p)[0])[block.ply] == 90).astype(float)
    for t_snap in (0.1e-3, 0.6e-3):
        sim.snapshots[f"damage_{round(t_snap * 1e6)}us"] = (t_snap, lambda: {
            "x": backend.positions(), "width_index": j.astype(float), "in_90": in_90,
            "intra_damage": intra.softened(), "inter_damage": inter.damage.copy(),
            "intra_pairs": intra.pairs.astype(float), "inter_pairs": inter.pairs.astype(float)})
    return sim


def _damage_probes(p, block, intra, inter):
    """Delamination per interface (whole beam: areas x 4, lengths = area / width), matrix
    cracks in the 90 plies, interlaminar damage near the zone's edge."""
    i, k = block.index[:, 0], block.index[:, 2]
    iface = k[inter.pairs[:, 0]]
    last = block.index[inter.pairs[:, 0], 0] == i.max()
    area = np.where(last & (i.max() > 0), 0.0, 4 * inter.area)  # the tied face lies on the FEM: not counted
    W = p["geometry.width"]
    probes = {}
    for n, row in enumerate(np.unique(iface)):
        sel = iface == row
        probes[f"delamination_area_{n}"] = lambda sel=sel: float(area[sel] @ inter.failed()[sel])
        probes[f"delamination_length_{n}"] = lambda sel=sel: float(area[sel] @ inter.failed()[sel]) / W
        probes[f"damaged_interface_length_{n}"] = lambda sel=sel: float(area[sel] @ (inter.damage[sel] > 0)) / W
    in_90 = (np.array(blocks(p)[0])[block.ply[intra.pairs]] == 90).all(axis=1)
    probes["matrix_cracks"] = lambda: float(np.sum(intra.failed() & in_90))
    probes["failed_intralaminar"] = lambda: float(np.sum(intra.failed()))
    edge = block.index[inter.pairs[:, 0], 0] >= i.max() - 2
    probes["damage_at_zone_edge"] = lambda: float(inter.damage[edge].max()) if edge.any() else 0.0
    return probes


def _build_fem(p: dict):
    region = fem_region(p, 0.0)
    X, H = region.X, thickness(p)
    d, _ = spacing(p)
    top = np.flatnonzero(X[:, 2] > H - 1e-9 * H)
    hx = np.diff(np.unique(X[top, 0])).min()
    hy = 0.5 * p["geometry.width"] / p["mesh.elements_width"]
    # the particles' penalty per d^2 of surface, times a node's share of the surface
    k_pen = (p["impactor.penalty"] or p["material.E22"] * d) * max(1.0, hx / d) * max(1.0, hy / d)
    R = p["impactor.radius"]
    imp = RigidImpactor("cylinder", np.array([0.0, 0.0, H + R + 1e-9]), R,
                        0.25 * p["impactor.mass_per_width"] * p["geometry.width"],
                        np.array([0.0, 0.0, -p["impactor.velocity"]]), k_pen, friction=p["impactor.friction"],
                        axis=np.array([0.0, 1.0, 0.0]))
    dyn = ExplicitDynamics(region, supports=supports(region, p, symmetry_x=True), impactors=[imp])
    bottom = np.flatnonzero((np.abs(X[:, 0]) < 1e-12) & (np.abs(X[:, 1]) < 1e-12) & (X[:, 2] < 1e-12))[0]
    probes = {"centre_displacement": lambda: -float(dyn.state.u[bottom, 2]),
              "model_size": lambda: float(region.n_elements),
              "contact_force": lambda: float(4 * imp.a[2] * imp.mass),
              "impactor_velocity": lambda: float(imp.v[2])}
    return fem_only(dyn, p, T_END, probes)


def evaluate(p: dict, h: dict, mode: str):
    qoi, checks = beam_impact.evaluate(p, h, mode)
    for key in h:
        if key.startswith("delamination_area_"):
            qoi[key] = float(np.asarray(h[key])[-1])
    return qoi, checks


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    beam_impact.plot(p, {k: v for k, v in h.items() if not k.startswith("damage_")}, qoi, plots_dir)
    for name in sorted({k.split(".")[0] for k in h if k.startswith("damage_") and "." in k}):
        _damage_picture(h, name, plots_dir)


def _damage_picture(h: dict, name: str, plots_dir):
    """Two x-z sections of the deformed lattice, mid-width (symmetry plane) and free edge:
    intralaminar bonds by damage (reds: 90 plies, oranges: 0 plies), interlaminar (blues)."""
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection
    x = 1e3 * np.asarray(h[f"{name}.x"])
    j = np.asarray(h[f"{name}.width_index"]).astype(int)
    in_90 = np.asarray(h[f"{name}.in_90"]) > 0
    fig, axes = plt.subplots(2, 1, figsize=(12, 5.5))
    for ax, at, label in zip(axes, (0, j.max()), ("mid-width (symmetry plane)", "free edge")):
        on = j == at
        ax.plot(x[on, 0], x[on, 2], ".", ms=1.5, color="0.7")
        for kind in ("intra", "inter"):
            pairs = np.asarray(h[f"{name}.{kind}_pairs"]).astype(int)
            dmg = np.asarray(h[f"{name}.{kind}_damage"])
            hit = (dmg > 0.05) & on[pairs].all(axis=1)
            if not hit.any():
                continue
            segs = x[pairs[hit]][:, :, [0, 2]]
            if kind == "inter":
                colors = plt.cm.Blues(0.3 + 0.7 * dmg[hit])
            else:
                ninety = in_90[pairs[hit]].all(axis=1)
                colors = np.where(ninety[:, None], plt.cm.Reds(0.3 + 0.7 * dmg[hit]),
                                  plt.cm.Oranges(0.3 + 0.7 * dmg[hit]))
            ax.add_collection(LineCollection(segs, colors=colors, linewidths=1.5))
        ax.set(xlabel="x (mm)", ylabel="z (mm)", title=f"damage at {name.split('_')[1]}, {label}")
        ax.set_aspect("equal")
    fig.tight_layout()
    fig.savefig(plots_dir / f"{name}.png", dpi=120)
    plt.close(fig)
