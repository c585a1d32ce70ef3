"""coupled_vibration: an undamped cantilever, FEM at the clamp, bonded lattice at the free end.

FEM Q4 (plane stress, E, nu = 1/3) over [0, L/2], a square lattice with diagonal bonds
calibrated to the same E and nu over [L/2, L], tied at x = L/2; released with a velocity
field in the shape of the clamped beam's first mode (v_y ~ (x/L)^2). With no damping the
total energy may oscillate at O(dt^2) but must not drift: qoi energy_drift_rel =
max |E(t) - E(0)| / E(0) over ``run.steps`` FEM steps, for any substep count m.
"""
from __future__ import annotations

import numpy as np

from dem_region import calibration, packing
from dem_region.scene import DemScene
from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion

from ..checks import bound
from ..params import isotropic_material, Param, particle_size, positive
from ..participants.fem import make_region
from ..participants.coupled import COUPLING, coupled_simulation

NAME = "coupled_vibration"
DESCRIPTION = "coupled: undamped FEM + lattice cantilever, energy drift over 10^5 steps"
MODES = ("coupled",)
PARAMETERS = {
    **isotropic_material(10e9, 2000.0),
    "zone.particle_size": particle_size(0.001, "particle size d (diameter; the lattice spacing)"),
    "geometry.length": positive(0.04, "beam length (half FEM, half lattice)", "m"),
    "geometry.height": positive(0.004, "beam depth", "m"),
    "mesh.spacing_ratio": Param(2, "FEM element size / lattice spacing", kind="int", low=1, high=8),
    "load.tip_velocity": positive(0.5, "initial tip velocity", "m/s"),
    "run.steps": Param(100_000, "FEM steps", kind="int", low=10),
    "mesh.element": Param("quad4", "2D element", kind="str", choices=("quad4",)),
    "fem.integration": Param("selective", "FEM integration", kind="str", choices=("full", "selective")),
    **COUPLING,
    "fem.formulation": Param("linear", "FEM path", kind="str", choices=("linear",)),
}


def build(p: dict, mode: str, dem: str):
    r = 0.5 * p["zone.particle_size"]
    d = 2 * r
    h = p["mesh.spacing_ratio"] * d
    L, H = p["geometry.length"], p["geometry.height"]
    nx, ny = max(1, round(L / 2 / h)), max(1, round(H / h))
    Lf, H = nx * h, ny * h
    m = mesh.rectangle(np.linspace(0, Lf, nx + 1), np.linspace(0, H, ny + 1), p["mesh.element"])
    E = p["material.E"]
    D = materials.plane_stress(materials.isotropic(E, 1.0 / 3.0))
    x = packing.square_2d((Lf, 0.0), (Lf + round((L - Lf) / d) * d, H), r)
    bonds, family = packing.square_bonds(x, r)
    k1, k2 = calibration.square_kn(E, r)
    Ltot = x[:, 0].max()
    shape = lambda X: (X / Ltot) ** 2
    v = np.zeros((len(x), 3))
    v[:, 1] = p["load.tip_velocity"] * shape(x[:, 0])
    scene = DemScene(x, r, calibration.square_density(p["material.rho"]), bonds, kn=np.where(family, k2, k1), ks=0.0,
                     bond_family=family, groups={"interface": np.flatnonzero(x[:, 0] <= Lf + 1e-9 * d)},
                     plane=True, young=E, velocity=v)

    def fem(extra_mass):
        region = make_region(m, p, D, p["material.rho"], d)
        root = region.nodes_where(lambda X: X[0] < 1e-9 * h)
        dyn = ExplicitDynamics(region, supports=[PrescribedMotion(np.concatenate([root * 2, root * 2 + 1]))],
                               extra_mass=extra_mass)
        v0 = np.zeros((region.n_nodes, 2))
        v0[:, 1] = p["load.tip_velocity"] * shape(region.X[:, 0])
        v0[root] = 0.0
        dyn.set_initial_velocity(v0)
        return dyn

    steps = p["run.steps"]
    sim, clock = coupled_simulation(p, fem, scene, dem, 1.0, history_every=p["output.history_every"] or max(1, steps // 500),
                                  steps=steps)
    tip = np.argmax(x[:, 0] + x[:, 1] * 1e-6)
    sim.probes["tip_displacement"] = lambda: float(clock.dem.positions()[tip, 1] - x[tip, 1])
    return sim


def evaluate(p: dict, h: dict, mode: str):
    E = h["kinetic"] + h["internal"]
    drift = float(np.abs(E - E[0]).max() / E[0])
    return ({"energy_drift_rel": drift, "tip_amplitude": float(np.abs(h["tip_displacement"]).max())},
            {"energy_drift_rel": bound(drift, 0.01, "energy conservation of the coupled (subcycled) scheme")})


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(2, 1, figsize=(6, 5), sharex=True)
    t = h["time"] * 1e3
    E = h["kinetic"] + h["internal"]
    ax[0].plot(t, h["tip_displacement"] * 1e3)
    ax[0].set(ylabel="tip deflection [mm]")
    ax[1].plot(t, E / E[0] - 1)
    ax[1].set(xlabel="time [ms]", ylabel="E(t)/E(0) - 1",
              title=f"substeps {p['clock.substeps'] or 'auto'}: drift {qoi['energy_drift_rel']:.1e}")
    fig.tight_layout()
    fig.savefig(plots_dir / "vibration_energy.png", dpi=120)
    plt.close(fig)
