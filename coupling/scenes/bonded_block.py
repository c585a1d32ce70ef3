"""Bonded-particle verification on a DEM engine: calibrated modulus, bond strength, bending.

Each case builds a regular bonded layer (square lattice with diagonal bonds, or hexagonal),
calibrates its bond stiffness to ``material.E`` with a virtual tension test (cached per
packing), and then verifies the calibrated model:

- bonded_block_modulus: a fresh tension test on the calibrated block measures E within 5 %;
- bond_strength: bonds calibrated to the tensile strength sigma_t (F_b = k_axial d sigma_t / E
  for the axial bonds) break when the block carries sigma_t x area, within 5 %;
- bonded_beam_bending: a clamped bonded cantilever under a tip load deflects as a
  Timoshenko beam of the calibrated E and measured nu (kappa = 5/6), within 10 %.

The clock of these cases is the test procedure itself (one stage), so their summary.json has
no energy ledger of interest; the checks carry the result.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from dem_region import calibration, packing
from dem_region.backends import check_available, make_backend
from dem_region.scene import DemScene

from ..checks import check
from ..params import isotropic_material, Param, particle_size, positive
from ..simulation import Simulation, Stage

COMMON = {
    **isotropic_material(10e9, 2000.0),
    "zone.particle_size": particle_size(0.001, "particle size d (diameter; the lattice spacing)"),
    "packing.kind": Param("square", "regular layer", kind="str", choices=("square", "hexagonal")),
    "geometry.columns": Param(40, "particles along the block", kind="int", low=4),
    "geometry.rows": Param(10, "particles across the block", kind="int", low=3),
    "calibration.cache": Param(True, "reuse a cached calibration of the same packing", kind="bool"),
}


def layer(p: dict) -> DemScene:
    """The uncalibrated layer (bond stiffness from the closed form of its lattice)."""
    r, E = 0.5 * p["zone.particle_size"], p["material.E"]
    d = 2 * r
    if p["packing.kind"] == "square":
        x = packing.square_2d((0, 0), ((p["geometry.columns"] - 1) * d, (p["geometry.rows"] - 1) * d), r)
        bonds, fam = packing.square_bonds(x, r)
        k1, k2 = calibration.square_kn(E, r)
        kn, rho = np.where(fam, k2, k1), calibration.square_density(p["material.rho"])
    else:
        x = packing.hexagonal_2d((0, 0), ((p["geometry.columns"] - 1) * d, (p["geometry.rows"] - 1) * np.sqrt(3) * r), r)
        bonds, fam = packing.neighbour_bonds(x, r), None
        kn, rho = calibration.hexagonal_kn(E, r), calibration.hexagonal_density(p["material.rho"])
    return DemScene(x, r, rho, bonds, kn=kn, ks=0.0, bond_family=fam, plane=True, young=E)


def _axial_bonds(scene: DemScene) -> np.ndarray:
    """Bonds of nearest neighbours (length 2r) aligned within 1 degree of x."""
    dx = scene.x[scene.bonds[:, 1]] - scene.x[scene.bonds[:, 0]]
    n = np.linalg.norm(dx, axis=1)
    return (np.abs(dx[:, 0]) / n > np.cos(np.radians(1))) & (n < 2.01 * scene.radius[0])


def _procedure(p: dict, dem: str, run):
    """A Simulation whose single stage runs ``run(results)``; results become probes."""
    check_available(dem)
    results: dict[str, float] = {}
    zero = {"kinetic": 0.0, "internal": 0.0, "external_work": 0.0, "dissipated": 0.0}
    sim = Simulation(stages=[Stage("virtual test", "dem", lambda: run(results))], dt=1.0, n_steps=1,
                     history_every=1, probes={}, energies=lambda: zero, versions={})
    results["versions"] = sim.versions  # the engine's version, filled in by the test that builds it
    return sim, results


def _calibrated(p: dict, dem: str, results: dict) -> tuple[DemScene, calibration.BlockResponse]:
    raw = layer(p)
    scene, unit, hit = calibration.calibrate_modulus(raw, p["material.E"], dem, use_cache=p["calibration.cache"])
    results.update(uncalibrated_modulus=unit.E, poisson=unit.nu, calibration_cache_hit=float(hit))
    return scene, unit


def _build_modulus(p, mode, dem):
    def run(res):
        scene, _ = _calibrated(p, dem, res)
        test = calibration.virtual_tension(scene, dem)
        res["measured_modulus"], res["versions"][dem] = test.E, test.engine_version
    sim, res = _procedure(p, dem, run)
    sim.probes.update({k: (lambda k=k: res.get(k, 0.0)) for k in
                       ("measured_modulus", "uncalibrated_modulus", "poisson", "calibration_cache_hit")})
    sim.counts = {"particles": layer(p).n, "bonds": len(layer(p).bonds)}
    return sim


def _eval_modulus(p, h, mode):
    q = {k: float(h[k][-1]) for k in ("measured_modulus", "uncalibrated_modulus", "poisson")}
    return q, {"bonded_block_modulus": check(q["measured_modulus"], p["material.E"], 0.05, "calibration target E")}


def _build_strength(p, mode, dem):
    def run(res):
        scene, _ = _calibrated(p, dem, res)
        axial = _axial_bonds(scene)
        # every bond breaks at the force of an axial bond at sigma_t (force k d eps, eps = sigma_t / E):
        # in uniaxial tension along x the axial bonds carry the most and go first
        scene.bond_strength = np.full(len(scene.bonds), scene.kn[axial].max() * 2 * scene.radius[0]
                                      * p["material.tensile_strength"] / p["material.E"])
        test = calibration.virtual_tension(scene, dem, to_failure=True,
                                           strain=p["material.tensile_strength"] / p["material.E"])
        res["peak_stress"], res["versions"][dem] = test.peak_stress, test.engine_version
    sim, res = _procedure(p, dem, run)
    sim.probes.update({"peak_stress": lambda: res.get("peak_stress", 0.0)})
    return sim


def _eval_strength(p, h, mode):
    s = float(h["peak_stress"][-1])
    return ({"peak_stress": s},
            {"bond_strength": check(s, p["material.tensile_strength"], 0.05, "tensile strength x area")})


def _build_bending(p, mode, dem):
    def run(res):
        scene, unit = _calibrated(p, dem, res)
        res.update(beam_tip_deflection(scene, p, dem, res["versions"]))
    sim, res = _procedure(p, dem, run)
    sim.probes.update({k: (lambda k=k: res.get(k, 0.0)) for k in ("tip_deflection", "timoshenko", "poisson")})
    return sim


def beam_tip_deflection(scene: DemScene, p: dict, dem: str, versions: dict | None = None) -> dict:
    """Quasi-static cantilever: two columns clamped at x = 0, a downward tip force spread over
    the last column, Cundall damping until static."""
    from dataclasses import replace
    d = 2 * scene.radius[0]
    x = scene.x
    clamp = np.flatnonzero(x[:, 0] < 1.5 * d)
    tip = np.flatnonzero(x[:, 0] > x[:, 0].max() - 0.5 * d)
    P = p["load.tip_force"]
    eng = make_backend(dem)
    try:
        eng.build(replace(scene, local_damping=0.7))
        if versions is not None:
            versions[dem] = eng.version
        dt = 0.5 * eng.critical_dt()
        eng.prescribe(clamp)
        F = np.zeros((len(tip), 3))
        F[:, 1] = -P / len(tip)
        n = len(np.unique(np.round(x[:, 0] / d)))
        rows = len(np.unique(np.round(x[:, 1] / d)))
        block = int(20 * n * n / rows)  # about a first-mode period in steps

        def hook():
            eng.set_velocities(clamp, np.zeros((len(clamp), 3)))
            eng.add_forces(tip, F)
        eng.set_dt(dt)
        eng.start(hook)
        w_prev, w = np.inf, 0.0
        for _ in range(40):  # until the damped deflection settles to 1e-4
            for _ in range(block):
                eng.advance(hook)
            w_prev, w = w, -float((eng.positions_of(tip)[:, 1] - x[tip, 1]).mean())
            if abs(w - w_prev) < 1e-4 * abs(w):
                break
    finally:
        eng.finalize()
    E, nu = p["material.E"], 1.0 / 3.0
    t = d
    h = np.ptp(x[:, 1]) + d
    L = x[tip, 0].mean() - x[clamp, 0].max()
    I, A, G = t * h**3 / 12, t * h, E / (2 * (1 + nu))
    return {"tip_deflection": w, "timoshenko": P * L**3 / (3 * E * I) + P * L / (5 / 6 * G * A)}


def _eval_bending(p, h, mode):
    w, ref = float(h["tip_deflection"][-1]), float(h["timoshenko"][-1])
    return {"tip_deflection": w, "timoshenko": ref}, {"tip_deflection": check(w, ref, 0.10, "Timoshenko beam, calibrated E")}


def _plot_none(p, h, qoi, plots_dir):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5, 3))
    ax.bar(range(len(qoi)), list(qoi.values()))
    ax.set_xticks(range(len(qoi)), list(qoi), rotation=20, fontsize=7)
    ax.set_yscale("log")
    fig.tight_layout()
    fig.savefig(plots_dir / "qoi.png", dpi=110)
    plt.close(fig)


def _scene(name, desc, params, build, evaluate):
    return SimpleNamespace(NAME=name, DESCRIPTION=desc, MODES=("dem",), PARAMETERS=params, build=build,
                           evaluate=evaluate, plot=_plot_none)


BONDED_BLOCK_MODULUS = _scene("bonded_block_modulus", "DEM: calibrated bonded block, measured E vs target",
                              COMMON, _build_modulus, _eval_modulus)
BOND_STRENGTH = _scene("bond_strength", "DEM: bonded block pulled apart at strength x area",
                       {**COMMON, "material.tensile_strength": positive(20e6, "tensile strength", "Pa")},
                       _build_strength, _eval_strength)
BONDED_BEAM_BENDING = _scene("bonded_beam_bending", "DEM: bonded cantilever vs Timoshenko (calibrated E)",
                             {**COMMON, "geometry.columns": Param(60, "particles along the beam", kind="int", low=10),
                              "geometry.rows": Param(10, "particles through the depth", kind="int", low=3),
                              "load.tip_force": positive(2.0, "tip force over the layer thickness", "N")},
                             _build_bending, _eval_bending)
