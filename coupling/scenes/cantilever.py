"""cantilever: orthotropic ply cantilever under a tip load, solved by dynamic relaxation.

Reference (Timoshenko beam, plane stress, width b out of plane, shear correction 5/6):
delta = P L^3 / (3 E11 I) + P L / (kappa G13 A), I = b h^3 / 12, A = b h.
Dynamic relaxation: mass-proportional damping at the critical value of the first mode, so
every mode decays at the rate omega_1; the run lasts 14 / omega_1.
"""
from __future__ import annotations

import numpy as np

from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics, NodalLoad, PrescribedMotion
from fem_region.modal import lowest_modes

from ..checks import check
from ..params import Param, density, modulus, positive
from ..participants.fem import FEM_OPTIONS, fem_only, make_region

NAME = "cantilever"
DESCRIPTION = "FEM: orthotropic cantilever, tip load, dynamic relaxation vs Timoshenko"
MODES = ("fem",)
KAPPA = 5.0 / 6.0
PARAMETERS = {
    # graphite/epoxy of the seed paper's Table 1; G13 is not in the table (typical value)
    "material.E11": modulus(156e9, "fibre-direction modulus"),
    "material.E22": modulus(9.09e9, "transverse modulus"),
    "material.nu12": Param(0.228, "major Poisson ratio", low=0.0, high=0.49),
    "material.nu23": Param(0.4, "transverse Poisson ratio", low=0.0, high=0.49),
    "material.G13": modulus(6.9e9, "transverse shear modulus (x-thickness plane)"),
    "material.rho": density(1540.0),
    "geometry.length": positive(0.1, "free length", "m"),
    "geometry.thickness": positive(0.005, "beam depth (in plane)", "m"),
    "geometry.width": positive(0.01, "beam width (out of plane)", "m"),
    "load.tip_force": positive(10.0, "tip force over the whole width (downwards)", "N"),
    "mesh.elements_along": Param(80, "elements along the beam", kind="int", low=4),
    "mesh.elements_through": Param(4, "elements through the depth", kind="int", low=1),
    **FEM_OPTIONS,
}


def timoshenko(p: dict) -> float:
    L, h, b, P = p["geometry.length"], p["geometry.thickness"], p["geometry.width"], p["load.tip_force"]
    return P * L**3 / (3 * p["material.E11"] * b * h**3 / 12) + P * L / (KAPPA * p["material.G13"] * b * h)


def ply(p: dict) -> np.ndarray:
    """(6, 6) ply stiffness, transversely isotropic about the fibre with G12 = G13."""
    return materials.orthotropic(p["material.E11"], p["material.E22"], p["material.E22"],
                                 p["material.nu12"], p["material.nu12"], p["material.nu23"],
                                 p["material.G13"], p["material.G13"],
                                 p["material.E22"] / (2 * (1 + p["material.nu23"])))


def build(p: dict, mode: str, dem: str):
    L, h = p["geometry.length"], p["geometry.thickness"]
    m = mesh.rectangle(np.linspace(0, L, p["mesh.elements_along"] + 1),
                       np.linspace(-h / 2, h / 2, p["mesh.elements_through"] + 1), p["mesh.element"])
    D = materials.reduce(materials.rotate(ply(p), materials.ply_axes(0.0, 2)), 2, p["fem.hypothesis"])
    region = make_region(m, p, D, p["material.rho"], p["geometry.width"])
    root = region.nodes_where(lambda x: x[0] < 1e-9 * L)
    tip = region.nodes_where(lambda x: x[0] > L * (1 - 1e-9))
    ys = region.X[tip, 1]
    # consistent nodal forces of a uniform shear traction on the tip edge
    order = np.argsort(ys)
    share = np.zeros(len(tip))
    seg = np.diff(ys[order])
    share[order[:-1]] += seg / 2
    share[order[1:]] += seg / 2
    load = NodalLoad(tip * 2 + 1, -p["load.tip_force"] * share / share.sum())
    fixed = np.concatenate([root * 2, root * 2 + 1])
    omega1 = lowest_modes(region, fixed, region.mass)[0][0]
    dyn = ExplicitDynamics(region, supports=[PrescribedMotion(fixed)], loads=[load], alpha=2 * omega1)
    mid = tip[np.argmin(np.abs(ys))]
    probes = {"tip_deflection": lambda: -float(dyn.state.u[tip, 1].mean()),
              "tip_velocity": lambda: float(dyn.state.v[mid, 1])}
    return fem_only(dyn, p, 14.0 / omega1, probes)


def evaluate(p: dict, h: dict, mode: str):
    d = float(h["tip_deflection"][-1])
    qoi = {"tip_deflection": d, "residual_tip_velocity": float(abs(h["tip_velocity"][-1]))}
    return qoi, {"tip_deflection": check(d, timoshenko(p), 0.02, "Timoshenko beam, kappa = 5/6")}


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot(h["time"] * 1e3, h["tip_deflection"] * 1e3, label="FEM, dynamic relaxation")
    ax.axhline(timoshenko(p) * 1e3, color="k", ls="--", label="Timoshenko")
    ax.set(xlabel="time [ms]", ylabel="tip deflection [mm]", title="orthotropic cantilever")
    ax.legend()
    fig.tight_layout()
    fig.savefig(plots_dir / "tip_deflection.png", dpi=120)
    plt.close(fig)
