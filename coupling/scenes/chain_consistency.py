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
from ..params import isotropic_material, Param, particle_size, positive
from ..participants.fem import fem_only, make_region
from ..participants.coupled import COUPLING, coupled_simulation
from ..participants.dem import dem_only

NAME = "chain_consistency"
DESCRIPTION = "coupled: FEM bar + DEM chain vs the monolithic chain, to round-off"
MODES = ("coupled", "fem", "dem")
PARAMETERS = {
    **isotropic_material(1e9, 1000.0),
    "zone.particle_size": particle_size(0.01, "particle size d (diameter) = the FEM element length"),
    "chain.fem_elements": Param(20, "FEM elements along the left part", kind="int", low=1, high=100_000),
    "chain.particles": Param(20, "free DEM particles in the right part", kind="int", low=1, high=100_000),
    "chain.stiffness_ratio": Param(1.0, "DEM bond stiffness / FEM element stiffness (a hard case at 1000)",
                                   low=1e-3, high=1e6),
    "load.velocity": positive(1.0, "peak velocity of the pulse at the left end", "m/s"),
    "load.duration": positive(2e-4, "pulse duration", "s"),
    "mesh.element": Param("quad4", "2D element", kind="str", choices=("quad4",)),
    "fem.integration": Param("full", "FEM integration", kind="str", choices=("full", "selective")),
    **COUPLING,
    "fem.formulation": Param("linear", "FEM internal force path", kind="str", choices=("linear",)),
}


def _chain(p: dict):
    """Geometry shared by the coupled model and its monolithic reference."""
    r, E, rho = 0.5 * p["zone.particle_size"], p["material.E"], p["material.rho"]
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
    E = p["material.E"]
    t_end_default = 1.5 * (nf + nd) * le / np.sqrt(E / p["material.rho"])
    rho_p = m_node / (4.0 / 3.0 * np.pi * r**3)
    D = np.diag([E, E, 0.5 * E])  # nu = 0: axial motion stays one-dimensional
    n_fem = {"coupled": nf, "fem": nf + nd, "dem": 0}[mode]

    def strip():
        m = mesh.rectangle(np.linspace(0, n_fem * le, n_fem + 1), np.array([0.0, 2 * r]), "quad4")
        region = make_region(m, p, D, p["material.rho"], 2 * r)
        left = region.nodes_where(lambda x: x[0] < 1e-12)
        stations = np.array([region.nodes_where(lambda X, xx=xx: (np.abs(X[0] - xx) < 1e-12) & (X[1] < 1e-12))[0]
                             for xx in le * np.arange(n_fem + 1)])
        return region, left, stations

    def chain(first: int, interface: bool):
        count = nf + nd + 1 - first
        x = np.column_stack([le * (first + np.arange(count)), np.full(count, r), np.zeros(count)])
        bonds = np.column_stack([np.arange(count - 1), np.arange(1, count)])
        groups = {"interface": np.array([0])} if interface else {}
        kd = k * p["chain.stiffness_ratio"]
        return DemScene(x, r, rho_p, bonds, kn=kd, ks=kd, groups=groups, plane=True, young=E)

    if mode == "fem":
        region, left, stations = strip()
        dyn = ExplicitDynamics(region, supports=[PrescribedMotion(left * 2, _pulse(p)),
                                                 PrescribedMotion(np.arange(region.n_nodes) * 2 + 1)])
        sim = fem_only(dyn, p, t_end_default, {})
        sim.history_every = 1
        sim.probes.update({f"u_station_{s}": (lambda a=a: float(dyn.state.u[a, 0])) for s, a in enumerate(stations)})
        return sim
    if mode == "dem":
        scene = chain(0, False)
        sim, backend, _ = dem_only(p, scene, dem, t_end_default,
                                   (np.array([0]), lambda t: np.array([_pulse(p)(t), 0.0, 0.0])), history_every=1)
        x0 = scene.x[:, 0]
        sim.probes.update({f"u_station_{s}": (lambda s=s: float(backend.positions_of([s])[0, 0] - x0[s]))
                           for s in range(nf + nd + 1)})
        return sim
    region, left, stations = strip()
    scene = chain(nf, True)
    fem = lambda extra_mass: ExplicitDynamics(region, supports=[PrescribedMotion(left * 2, _pulse(p)),
                                                                PrescribedMotion(np.arange(region.n_nodes) * 2 + 1)],
                                              extra_mass=extra_mass)
    sim, clock = coupled_simulation(p, fem, scene, dem, t_end_default, history_every=1)
    xp0 = scene.x[:, 0]
    probes = {f"u_station_{s}": (lambda a=a: float(clock.u_snapshot[a, 0])) for s, a in enumerate(stations)}
    probes["substeps"] = lambda: float(clock.m)
    probes.update({f"u_station_{nf + j}": (lambda j=j: float(clock.dem.positions_of([j])[0, 0] - xp0[j]))
                   for j in range(1, nd + 1)})
    sim.probes.update(probes)
    return sim


def monolithic(p: dict, dt: float, steps: int, mode: str = "coupled", sub: int = 1) -> np.ndarray:
    """(steps + 1, nf + nd + 1) displacement history of the same discrete chain in one solver,
    stepping dt / sub (the DEM step of a subcycled run, so the stiff part stays stable).

    Station masses: FEM ends carry half an element, particles a whole one; in the coupled
    model the interface station carries half an element plus the interface particle.
    """
    r, le, A, k, m_node = _chain(p)
    nf, nd = p["chain.fem_elements"], p["chain.particles"]
    n = nf + 1 + nd
    m = np.full(n, m_node)
    if mode == "fem":
        m[0] = m[-1] = 0.5 * m_node
    elif mode == "coupled":
        m[0] = 0.5 * m_node
        m[nf] = 1.5 * m_node  # half an element plus the interface particle
    springs = np.full(n - 1, k)
    springs[{"coupled": nf, "fem": n - 1, "dem": 0}[mode]:] *= p["chain.stiffness_ratio"]  # DEM bonds
    u, v = np.zeros(n), np.zeros(n)
    pulse = _pulse(p)
    out = [u.copy()]
    f = np.zeros(n)
    h = dt / sub
    for s in range(steps * sub):  # leapfrog from rest: v_{s+1/2} = v_{s-1/2} + h f(u_s) / m
        v += h * f / m
        v[0] = pulse((s + 0.5) * h)
        u += h * v
        e = springs * np.diff(u)
        f = np.zeros(n)
        f[:-1] += e
        f[1:] -= e
        if (s + 1) % sub == 0:
            out.append(u.copy())
    return np.array(out)


def evaluate(p: dict, h: dict, mode: str):
    nf, nd = p["chain.fem_elements"], p["chain.particles"]
    t = h["time"]
    sub = int(h["substeps"][0]) if "substeps" in h else 1
    ref = monolithic(p, t[1] - t[0], len(t) - 1, mode, sub)
    ours = np.column_stack([h[f"u_station_{s}"] for s in range(nf + nd + 1)])
    diff = float(np.abs(ours - ref).max() / np.abs(ref).max())
    qoi = {"max_rel_diff_vs_monolithic": diff, "max_displacement": float(np.abs(ref).max()),
           "tip_displacement_max": float(np.abs(ours[:, -1]).max())}
    return qoi, {"max_rel_diff_vs_monolithic": bound(diff, 1e-10, f"the same chain in one central-difference "
                                                     f"solver ({mode} masses)")}


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    nf, nd = p["chain.fem_elements"], p["chain.particles"]
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for s in (nf // 2, nf, nf + nd // 2, nf + nd):
        ax.plot(h["time"] * 1e3, h[f"u_station_{s}"] * 1e3, "-" if s <= nf else "--", label=f"station {s}")
    ax.set(xlabel="time [ms]", ylabel="displacement [mm]",
           title=f"chain (stations > {nf} are DEM when coupled): diff vs monolithic {qoi['max_rel_diff_vs_monolithic']:.1e}")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(plots_dir / "chain_displacements.png", dpi=120)
    plt.close(fig)
