"""interface_patch: a uniform strain field across the transition interface.

FEM block (plane stress, E, nu = 1/3) on the left, a square bonded lattice calibrated to the
same E and nu (axial k1 = 3 E t / 4, diagonal k1 / 2) on the right; the lattice's first
column lies on the FEM's right face and is tied to it. Both sides start with the velocity
field G X / dt, so after one step every node and particle sits on the affine map X + G X.
Under a uniform strain the interface must be in equilibrium: at every FEM node that is not
on the outer boundary the FEM internal force and the force returned from the lattice cancel,
and every interior free particle carries no net force. qoi: the largest residuals, relative
to the nodal force of the uniform stress on one element edge.

The lattice bonds measure exact bond lengths while the far field is small-strain linear, so
the two sides differ by O(strain) (the geometric nonlinearity, measured 0.42 x |strain|);
the interface check is |residual| <= 2 max|strain| + 1e-9, and the test suite verifies that
the residual scales linearly with the strain (no spurious force at the linear level). Free
particles must balance to the round-off of absolute coordinates, 50 eps |x| / (strain d).
"""
from __future__ import annotations

import numpy as np

from dem_region import calibration, packing
from dem_region.scene import DemScene
from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics

from ..checks import bound
from ..params import CaseError, isotropic_material, Param, particle_size
from ..participants.fem import make_region
from ..participants.coupled import COUPLING, coupled_simulation

NAME = "interface_patch"
DESCRIPTION = "coupled: uniform strain across the interface, no spurious interface force"
MODES = ("coupled",)
PARAMETERS = {
    **isotropic_material(10e9, 2000.0),
    "zone.particle_size": particle_size(0.001, "particle size d (diameter; the lattice spacing)"),
    "geometry.fem_columns": Param(4, "FEM elements along x", kind="int", low=1),
    "geometry.rows": Param(5, "FEM elements along y", kind="int", low=2),
    "geometry.lattice_columns": Param(8, "free lattice columns", kind="int", low=3),
    "mesh.spacing_ratio": Param(2, "FEM element size / lattice spacing", kind="int", low=1, high=8),
    "strain.xx": Param(1e-4, "uniform strain component", low=-1e-2, high=1e-2),
    "strain.yy": Param(-3e-5, "uniform strain component", low=-1e-2, high=1e-2),
    "strain.xy": Param(5e-5, "uniform (tensor) shear strain component", low=-1e-2, high=1e-2),
    "mesh.element": Param("quad4", "2D element", kind="str", choices=("quad4", "tri3")),
    "fem.integration": Param("full", "FEM integration", kind="str", choices=("full", "selective", "reduced")),
    **COUPLING,
    "fem.formulation": Param("linear", "FEM path", kind="str", choices=("linear",)),
}


def refuse_no_strain(p: dict) -> None:
    """CaseError (exit 2) for an all-zero strain: no stress, nothing to test (the residuals are
    relative to the uniform stress's edge force, which would be 0)."""
    keys = ("strain.xx", "strain.yy", "strain.xy")
    if all(p[k] == 0.0 for k in keys):
        raise CaseError(f"{', '.join(f'{k} = 0' for k in keys)}: no strain, nothing to test (the residuals are "
                        "relative to its stress); allowed: at least one component nonzero, each in [-0.01, 0.01]")


def build(p: dict, mode: str, dem: str):
    refuse_no_strain(p)  # (before the engine starts)
    r = 0.5 * p["zone.particle_size"]
    d = 2 * r
    h = p["mesh.spacing_ratio"] * d
    nx, ny = p["geometry.fem_columns"], p["geometry.rows"]
    Lf, H = nx * h, ny * h
    m = mesh.rectangle(np.linspace(0, Lf, nx + 1), np.linspace(0, H, ny + 1), p["mesh.element"])
    E = p["material.E"]
    D = materials.plane_stress(materials.isotropic(E, 1.0 / 3.0))
    x = packing.square_2d((Lf, 0.0), (Lf + p["geometry.lattice_columns"] * d, H), r)
    bonds, family = packing.square_bonds(x, r)
    k1, k2 = calibration.square_kn(E, r)
    band = np.flatnonzero(x[:, 0] <= Lf + 1e-9 * d)
    G = np.array([[p["strain.xx"], p["strain.xy"]], [p["strain.xy"], p["strain.yy"]]])
    scene = DemScene(x, r, calibration.square_density(p["material.rho"]), bonds, kn=np.where(family, k2, k1), ks=0.0,
                     bond_family=family, groups={"interface": band}, plane=True, young=E)
    # one step of length dt with the velocity field G X / dt puts both sides on X + G X
    dt = p["clock.safety"] * min(make_region(m, p, D, p["material.rho"], d).critical_dt(), scene.critical_dt())
    scene.velocity[:, :2] = x[:, :2] @ G.T / dt

    def fem(extra_mass):
        dyn = ExplicitDynamics(make_region(m, p, D, p["material.rho"], d), extra_mass=extra_mass)
        dyn.set_initial_velocity(dyn.region.X @ G.T / dt)
        return dyn

    sim, clock = coupled_simulation({**p, "clock.dt": dt, "clock.substeps": 1}, fem, scene, dem, dt, history_every=1, steps=1)
    dyn = clock.fem

    X = dyn.region.X
    edge = (X[:, 1] < 1e-9 * h) | (X[:, 1] > H - 1e-9 * h) | (X[:, 0] < 1e-9 * h)
    inner_nodes = np.flatnonzero(~edge)
    xs = clock.dem.scene.x
    free_inner = np.flatnonzero((xs[:, 0] > Lf + 0.5 * d) & (xs[:, 0] < xs[:, 0].max() - 0.5 * d)
                                & (xs[:, 1] > 0.5 * d) & (xs[:, 1] < H - 0.5 * d))
    sigma = D @ np.array([G[0, 0], G[1, 1], 2 * G[0, 1]])
    scale = np.abs(sigma).max() * h * d  # nodal force of the uniform stress on one edge

    def residual_nodes():
        return float(np.abs(clock.f_tie[inner_nodes] - dyn.f_int[inner_nodes]).max() / scale)

    def residual_particles():
        return float(np.abs(clock.dem.forces(free_inner)).max() / scale)

    def interface_force():  # the force the lattice returns to the interface nodes is real
        return float(np.abs(clock.f_tie).max() / scale)

    sim.probes.update({"max_interface_residual_rel": residual_nodes, "max_free_particle_force_rel": residual_particles,
                       "interface_force_rel": interface_force})
    return sim


def evaluate(p: dict, h: dict, mode: str):
    qoi = {k: float(h[k][-1]) for k in ("max_interface_residual_rel", "max_free_particle_force_rel", "interface_force_rel")}
    src = "uniform strain is an equilibrium state of both sides"
    strain = max(abs(p["strain.xx"]), abs(p["strain.yy"]), abs(p["strain.xy"]))
    d = p["zone.particle_size"]
    extent = (p["geometry.fem_columns"] * p["mesh.spacing_ratio"] + p["geometry.lattice_columns"]) * d
    roundoff = 50 * np.finfo(float).eps * extent / (strain * d)
    return qoi, {"max_interface_residual_rel": bound(qoi["max_interface_residual_rel"], 2 * strain + 1e-9,
                                                     src + " (up to the O(strain) geometric nonlinearity of bonds)"),
                 "max_free_particle_force_rel": bound(qoi["max_free_particle_force_rel"], roundoff,
                                                      src + " (round-off of absolute coordinates)")}


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(5, 3))
    names = ["max_interface_residual_rel", "max_free_particle_force_rel", "interface_force_rel"]
    ax.bar(range(3), [max(qoi[n], 1e-18) for n in names])
    ax.set_yscale("log")
    ax.set_xticks(range(3), ["interface residual", "free particle force", "interface force"], fontsize=8)
    ax.set(title="uniform strain across the interface", ylabel="relative to sigma h t")
    fig.tight_layout()
    fig.savefig(plots_dir / "patch_residuals.png", dpi=120)
    plt.close(fig)
