"""interface_wave: a smooth pulse crosses FEM -> DEM -> FEM through two kinematic ties.

Left and right Q4 strips (one element through the height, element length 2r) and a bonded
sphere chain between them, calibrated as in chain_consistency (kn = E A / 2r, particle mass
= bar mass of 2r). The interface particles sit on the strips' end faces and carry half a
particle's mass (the half outside the FEM), so the discrete impedance is uniform and the only
reflections are those the coupling makes. A sin^2 velocity pulse of ``load.wavelength``
elements enters at the left end (held at rest afterwards). When the transmitted pulse is
inside the right strip, qoi reflected_energy_fraction = energy in the left strip / total and
transmitted_energy_fraction = energy in the right strip / total.
"""
from __future__ import annotations

import numpy as np
import skfem

from dem_region.scene import DemScene
from fem_region import mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from fem_region.loads import sine_squared

from ..checks import bound
from ..params import isotropic_material, Param, particle_size, positive
from ..participants.fem import make_region
from ..participants.coupled import COUPLING, coupled_simulation

NAME = "interface_wave"
DESCRIPTION = "coupled: pulse FEM -> DEM -> FEM, reflected < 2 %, transmitted > 95 %"
MODES = ("coupled",)
PARAMETERS = {
    **isotropic_material(1e9, 1000.0),
    "zone.particle_size": particle_size(0.01, "particle size d (diameter) = the FEM element length"),
    "chain.left_elements": Param(60, "elements in the left strip", kind="int", low=10),
    "chain.particles": Param(40, "chain particles between the strips", kind="int", low=2),
    "chain.right_elements": Param(80, "elements in the right strip", kind="int", low=10),
    "load.velocity": positive(1.0, "peak velocity of the pulse", "m/s"),
    "load.wavelength": Param(20.0, "pulse length in elements (>= 10 resolves it)", low=4.0),
    "mesh.element": Param("quad4", "2D element", kind="str", choices=("quad4",)),
    "fem.integration": Param("full", "FEM integration", kind="str", choices=("full",)),
    **COUPLING,
    "fem.formulation": Param("linear", "FEM path", kind="str", choices=("linear",)),
}


def _strips(p):
    r = 0.5 * p["zone.particle_size"]
    le = 2 * r
    n1, nd, n2 = p["chain.left_elements"], p["chain.particles"], p["chain.right_elements"]
    a = mesh.rectangle(np.linspace(0, n1 * le, n1 + 1), np.array([0.0, le]))
    x0 = (n1 + nd) * le
    b = mesh.rectangle(np.linspace(x0, x0 + n2 * le, n2 + 1), np.array([0.0, le]))
    m = skfem.MeshQuad(np.hstack([a.p, b.p]), np.hstack([a.t, b.t + a.p.shape[1]]))
    left_el = np.arange(a.t.shape[1])
    return m, le, left_el, x0


def build(p: dict, mode: str, dem: str):
    m, le, left_el, x0 = _strips(p)
    r, E, rho = 0.5 * p["zone.particle_size"], p["material.E"], p["material.rho"]
    c = np.sqrt(E / rho)
    A = le * le
    n1, nd = p["chain.left_elements"], p["chain.particles"]
    xs = n1 * le + le * np.arange(nd + 1)
    x = np.column_stack([xs, np.full(nd + 1, r), np.zeros(nd + 1)])
    m_p = rho * A * le
    density = np.full(nd + 1, m_p / (4.0 / 3.0 * np.pi * r**3))
    density[[0, nd]] *= 0.5  # interface particles: the half of their mass outside the FEM
    bonds = np.column_stack([np.arange(nd), np.arange(1, nd + 1)])
    k = E * A / le
    scene = DemScene(x, r, density, bonds, kn=k, ks=k, groups={"interface": np.array([0, nd])}, plane=True, young=E)
    T = p["load.wavelength"] * le / c
    D = np.diag([E, E, 0.5 * E])
    parts = {}

    def fem(extra_mass):
        region = make_region(m, p, D, rho, le)
        left = region.nodes_where(lambda X: X[0] < 1e-9 * le)
        parts["left_el"] = left_el
        parts["right_el"] = np.setdiff1d(np.arange(region.n_elements), left_el)
        parts["left_nodes"] = region.nodes_where(lambda X: X[0] < n1 * le + 1e-9 * le)
        parts["right_nodes"] = region.nodes_where(lambda X: X[0] > x0 - 1e-9 * le)
        return ExplicitDynamics(region, supports=[PrescribedMotion(left * 2, sine_squared(p["load.velocity"], T)),
                                                  PrescribedMotion(np.arange(region.n_nodes) * 2 + 1)],
                                extra_mass=extra_mass)

    t_end = (n1 + nd + 0.6 * p["chain.right_elements"]) * le / c + T
    sim, clock = coupled_simulation(p, fem, scene, dem, t_end)
    fem_ = clock.fem

    def energy(nodes, elements):
        def f():
            v, u = clock.v_snapshot, clock.u_snapshot
            return float(0.5 * fem_.m[nodes] @ np.sum(v[nodes] ** 2, axis=1)
                         + fem_.region.element_strain_energy(u)[elements].sum())
        return f

    sim.probes.update({"energy_left": energy(parts["left_nodes"], parts["left_el"]),
                       "energy_right": energy(parts["right_nodes"], parts["right_el"]),
                       "energy_total": lambda: float(clock.snapshot["kinetic"] + clock.snapshot["internal"])})
    return sim


def evaluate(p: dict, h: dict, mode: str):
    total = h["energy_total"][-1]
    refl, trans = h["energy_left"][-1] / total, h["energy_right"][-1] / total
    qoi = {"reflected_energy_fraction": float(refl), "transmitted_energy_fraction": float(trans)}
    return qoi, {"reflected_energy_fraction": bound(refl, 0.02, "energy left behind the first interface"),
                 "transmitted_energy_fraction": bound(trans, 0.95, "energy past the second interface", upper=False)}


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.5))
    t = h["time"] * 1e3
    ax.plot(t, h["energy_left"] / h["energy_total"][-1], label="left FEM strip")
    ax.plot(t, h["energy_right"] / h["energy_total"][-1], label="right FEM strip")
    ax.plot(t, (h["energy_total"] - h["energy_left"] - h["energy_right"]) / h["energy_total"][-1], label="DEM chain")
    ax.set(xlabel="time [ms]", ylabel="energy / final total",
           title=f"pulse FEM -> DEM -> FEM (substeps {p['clock.substeps'] or 'auto'}): "
                 f"R = {qoi['reflected_energy_fraction']:.1e}")
    ax.legend()
    fig.tight_layout()
    fig.savefig(plots_dir / "energy_by_region.png", dpi=120)
    plt.close(fig)
