"""coupled_free_flight: a free FEM block tied to a free bonded lattice, flying and vibrating.

No supports, no loads: total momentum (FEM nodes + free particles + the impulse of the open
subcycling window) must stay what it was, to round-off, for any substep count m.
"""
from __future__ import annotations

import numpy as np

from dem_region import calibration, packing
from dem_region.scene import DemScene
from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics

from ..checks import bound
from ..params import isotropic_material, Param, particle_size, positive
from ..participants.fem import make_region
from ..participants.coupled import COUPLING, coupled_simulation

NAME = "coupled_free_flight"
DESCRIPTION = "coupled: free FEM block + bonded lattice, momentum conserved to 1e-12"
MODES = ("coupled",)
PARAMETERS = {
    **isotropic_material(10e9, 2000.0),
    "geometry.fem_length": positive(0.04, "FEM block length", "m"),
    "geometry.dem_length": positive(0.04, "lattice length", "m"),
    "geometry.height": positive(0.02, "height", "m"),
    "zone.particle_size": particle_size(0.002, "particle size d (diameter; the lattice spacing)"),
    "mesh.element_size": positive(0.004, "FEM element size", "m"),
    "motion.velocity_x": Param(1.0, "initial drift velocity x", unit="m/s"),
    "motion.velocity_y": Param(0.5, "initial drift velocity y", unit="m/s"),
    "motion.perturbation": Param(0.2, "random initial velocity amplitude", unit="m/s", low=0.0),
    "run.steps": Param(400, "FEM steps", kind="int", low=1),
    "mesh.element": Param("quad4", "2D element", kind="str", choices=("quad4", "tri3")),
    "fem.integration": Param("full", "FEM integration", kind="str", choices=("full", "selective", "reduced")),
    **COUPLING,
    "fem.formulation": Param("linear", "FEM path", kind="str", choices=("linear", "total_lagrangian")),
}


def lattice_block(p: dict, x0: float, x1: float, height: float, interface_x: float):
    """Hexagonal layer over [x0, x1] x [0, height] calibrated to material.E / material.rho;
    particles at x <= interface_x form the interface band."""
    r = 0.5 * p["zone.particle_size"]
    x = packing.hexagonal_2d((x0, 0.0), (x1, height), r)
    bonds = packing.neighbour_bonds(x, r)
    kn = calibration.hexagonal_kn(p["material.E"], r)
    band = np.flatnonzero(x[:, 0] <= interface_x + 1e-9 * r)
    return x, bonds, kn, band


def build(p: dict, mode: str, dem: str):
    Lf, Ld, H, h = p["geometry.fem_length"], p["geometry.dem_length"], p["geometry.height"], p["mesh.element_size"]
    r = 0.5 * p["zone.particle_size"]
    m = mesh.rectangle(np.linspace(0, Lf, max(1, round(Lf / h)) + 1), np.linspace(0, H, max(1, round(H / h)) + 1),
                       p["mesh.element"])
    D = materials.plane_stress(materials.isotropic(p["material.E"], 1 / 3))
    x, bonds, kn, band = lattice_block(p, Lf - 2 * r, Lf + Ld, H, Lf)
    rng = np.random.default_rng(7)
    drift = np.array([p["motion.velocity_x"], p["motion.velocity_y"], 0.0])
    v = drift + p["motion.perturbation"] * rng.uniform(-1, 1, (len(x), 3)) * [1, 1, 0]
    scene = DemScene(x, r, calibration.hexagonal_density(p["material.rho"]), bonds, kn=kn, ks=0.0,
                     groups={"interface": band}, plane=True, young=p["material.E"], velocity=v)

    def fem(extra_mass):
        region = make_region(m, p, D, p["material.rho"], 2 * r)
        dyn = ExplicitDynamics(region, extra_mass=extra_mass)
        dyn.set_initial_velocity(drift[:2] + p["motion.perturbation"] * rng.uniform(-1, 1, (region.n_nodes, 2)))
        return dyn

    sim, clock = coupled_simulation(p, fem, scene, dem, 1.0, history_every=p["output.history_every"] or 1,
                                  steps=p["run.steps"])
    return sim


def evaluate(p: dict, h: dict, mode: str):
    P = np.column_stack([h["momentum_x"], h["momentum_y"]])
    drift = float(np.abs(P - P[0]).max() / np.linalg.norm(P[0]))
    return ({"momentum_drift_rel": drift},
            {"momentum_drift_rel": bound(drift, 1e-12, "momentum conservation of the coupled step")})


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for c in "xy":
        ax.plot(h["time"] * 1e3, h[f"momentum_{c}"] - h[f"momentum_{c}"][0], label=f"P_{c}(t) - P_{c}(0)")
    ax.set(xlabel="time [ms]", ylabel="momentum change [kg m/s]",
           title=f"coupled free flight: drift {qoi['momentum_drift_rel']:.1e}")
    ax.legend()
    fig.tight_layout()
    fig.savefig(plots_dir / "momentum.png", dpi=120)
    plt.close(fig)
