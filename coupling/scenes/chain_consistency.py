"""chain_consistency: an elastic bar, the left part FEM (Q4), the right part a bonded DEM chain.

The FEM bar has one element through its height and element length 2r; the DEM chain has
spheres of radius r on the bar axis with bond stiffness kn = E A / (2 r) and a particle mass
equal to the bar mass of one element length, so both halves are the same mass-spring chain.
The first particle sits on the FEM end face (the interface particle, weights 1/2, 1/2).
A velocity pulse enters at the left end. Reference: the same discrete chain (masses and
springs assembled in one array) integrated by one central-difference solver here, so the
coupled run must agree with it to round-off (qoi max_rel_diff_vs_monolithic, m = 1).
"""
from __future__ import annotations

import numpy as np

from dem_region.scene import DemScene
from fem_region import mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion

from ..checks import bound
from ..params import Param, positive
from .common import make_region
from .coupled_common import COUPLING, coupled_simulation

NAME = "chain_consistency"
DESCRIPTION = "coupled: FEM bar + DEM chain vs the monolithic chain, to round-off"
MODES = ("coupled",)
PARAMETERS = {
    "material.E": positive(1e9, "Young's modulus of the bar", "Pa"),
    "material.rho": positive(1000.0, "density of the bar", "kg/m^3"),
    "particle.radius": positive(0.005, "sphere radius = half the FEM element length", "m"),
    "chain.fem_elements": Param(20, "FEM elements along the left part", kind="int", low=1),
    "chain.particles": Param(20, "free DEM particles in the right part", kind="int", low=1),
    "load.velocity": positive(1.0, "peak velocity of the pulse at the left end", "m/s"),
    "load.duration": positive(2e-4, "pulse duration", "s"),
    "mesh.element": Param("quad4", "2D element", kind="str", choices=("quad4",)),
    "fem.integration": Param("full", "FEM integration", kind="str", choices=("full", "selective")),
    **COUPLING,
    "fem.formulation": Param("linear", "FEM internal force path", kind="str", choices=("linear",)),
}


def _chain(p: dict):
    """Geometry shared by the coupled model and its monolithic reference."""
    r, E, rho = p["particle.radius"], p["material.E"], p["material.rho"]
    le, A = 2 * r, (2 * r) ** 2  # element length; cross-section (height x width)
    k = E * A / le
    m_node = rho * A * le  # bar mass of one element length = one particle's mass
    return r, le, A, k, m_node


def _pulse(p: dict):
    v0, T = p["load.velocity"], p["load.duration"]
    return lambda t: v0 * np.sin(np.pi * t / T) ** 2 if 0 <= t < T else 0.0


def build(p: dict, mode: str, dem: str):
    r, le, A, k, m_node = _chain(p)
    nf, nd = p["chain.fem_elements"], p["chain.particles"]
    m = mesh.rectangle(np.linspace(0, nf * le, nf + 1), np.array([0.0, 2 * r]), "quad4")
    E = p["material.E"]
    D = np.diag([E, E, 0.5 * E])  # nu = 0: axial motion stays one-dimensional
    region = make_region(m, p, D, p["material.rho"], 2 * r)
    left = region.nodes_where(lambda x: x[0] < 1e-12)
    xs = nf * le + le * np.arange(nd + 1)
    x = np.column_stack([xs, np.full(nd + 1, r), np.zeros(nd + 1)])
    rho_p = m_node / (4.0 / 3.0 * np.pi * r**3)
    bonds = np.column_stack([np.arange(nd), np.arange(1, nd + 1)])
    scene = DemScene(x, r, rho_p, bonds, kn=k, ks=k, groups={"interface": np.array([0])}, plane=True,
                     young=E)
    fem = lambda extra_mass: ExplicitDynamics(region, supports=[PrescribedMotion(left * 2, _pulse(p)),
                                                                PrescribedMotion(np.arange(region.n_nodes) * 2 + 1)],
                                              extra_mass=extra_mass)
    t_end_default = 1.5 * (nf + nd) * le / np.sqrt(E / p["material.rho"])
    sim, clock = coupled_simulation(p, fem, scene, dem, t_end_default, history_every=1)
    free = np.arange(1, nd + 1)
    xp0 = scene.x[:, 0]
    fem_nodes = np.array([region.nodes_where(lambda X, xx=xx: (np.abs(X[0] - xx) < 1e-12) & (X[1] < 1e-12))[0]
                          for xx in le * np.arange(nf + 1)])
    probes = {}
    for j, a in enumerate(fem_nodes):
        probes[f"u_fem_{j}"] = lambda a=a: float(clock.u_snapshot[a, 0])
    for j in free:
        probes[f"u_dem_{j}"] = lambda j=j: float(clock.dem.positions()[j, 0] - xp0[j])
    sim.probes.update(probes)
    return sim


def monolithic(p: dict, dt: float, steps: int) -> np.ndarray:
    """(steps + 1, nf + 1 + nd) displacement history of the same chain in one solver."""
    r, le, A, k, m_node = _chain(p)
    nf, nd = p["chain.fem_elements"], p["chain.particles"]
    n = nf + 1 + nd
    m = np.full(n, m_node)
    m[0] = m[nf] = 0.5 * m_node  # FEM end stations: half an element each ...
    m[nf] += m_node  # ... plus the interface particle
    u, v = np.zeros(n), np.zeros(n)
    pulse = _pulse(p)
    out = [u.copy()]
    f = np.zeros(n)
    for s in range(steps):  # leapfrog from rest: v_{s+1/2} = v_{s-1/2} + dt f(u_s) / m
        v += dt * f / m
        v[0] = pulse((s + 0.5) * dt)
        u += dt * v
        e = k * np.diff(u)
        f = np.zeros(n)
        f[:-1] += e
        f[1:] -= e
        out.append(u.copy())
    return np.array(out)


def evaluate(p: dict, h: dict):
    nf, nd = p["chain.fem_elements"], p["chain.particles"]
    t = h["time"]
    dt = t[1] - t[0]
    ref = monolithic(p, dt, len(t) - 1)
    ours = np.column_stack([h[f"u_fem_{j}"] for j in range(nf + 1)] + [h[f"u_dem_{j}"] for j in range(1, nd + 1)])
    diff = float(np.abs(ours - ref).max() / np.abs(ref).max())
    qoi = {"max_rel_diff_vs_monolithic": diff, "max_displacement": float(np.abs(ref).max())}
    return qoi, {"max_rel_diff_vs_monolithic": bound(diff, 1e-10, "monolithic central-difference chain, same masses and springs")}


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    nf, nd = p["chain.fem_elements"], p["chain.particles"]
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for j in (nf // 2, nf):
        ax.plot(h["time"] * 1e3, h[f"u_fem_{j}"] * 1e3, label=f"FEM node {j}")
    for j in (nd // 2, nd):
        ax.plot(h["time"] * 1e3, h[f"u_dem_{j}"] * 1e3, "--", label=f"DEM particle {j}")
    ax.set(xlabel="time [ms]", ylabel="displacement [mm]",
           title=f"FEM + DEM chain: max rel. diff vs monolithic {qoi['max_rel_diff_vs_monolithic']:.1e}")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(plots_dir / "chain_displacements.png", dpi=120)
    plt.close(fig)
