"""column_buckling: clamped-clamped column under slow end shortening, Total Lagrangian path.

A small imperfection in the shape of the first clamped-clamped buckling mode,
w0 = delta (1 - cos(2 pi x / L)) / 2, lets the column buckle; the axial reaction levels off
at the Euler load P = 4 pi^2 E I / L^2, I = b h^3 / 12 (plane stress, width b out of plane).
The end is shortened with a smooth ramp to ``load.shortening_factor`` times the critical
shortening P L / (E A) over ``load.duration_periods`` periods of the first bending mode,
with mass damping at 2 omega_1, then held for ``load.hold_periods`` periods. Beyond the
critical shortening the column carries the post-buckled equilibrium force, which for the
elastica exceeds the Euler load only by O((w/L)^2) (0.1 % here): qoi buckling_load = the
axial force on that plateau (mean over the last quarter of the hold). The damped lateral
response lags the load, so the force overshoots while loading (qoi peak_axial_force).
"""
from __future__ import annotations

import numpy as np

from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from fem_region.modal import lowest_modes

from ..checks import check
from ..params import Param, isotropic_material, positive
from ..participants.fem import FEM_OPTIONS, fem_only, make_region

NAME = "column_buckling"
DESCRIPTION = "FEM (TL): clamped-clamped column, buckling load vs 4 pi^2 E I / L^2"
MODES = ("fem",)
PARAMETERS = {
    **isotropic_material(200e9, 7800.0, 0.3),
    "geometry.length": positive(0.4, "length between the clamps", "m"),
    "geometry.thickness": positive(0.01, "depth in the buckling plane", "m"),
    "geometry.width": positive(0.01, "width out of plane", "m"),
    "geometry.imperfection": Param(0.01, "imperfection amplitude / thickness", low=1e-4, high=0.5),
    "load.shortening_factor": Param(2.0, "final shortening / critical shortening", low=1.1, high=10.0),
    "load.duration_periods": Param(12.0, "loading time in first-mode periods", low=2.0),
    "load.hold_periods": Param(6.0, "hold time after loading, in first-mode periods", low=1.0),
    "mesh.elements_along": Param(80, "elements along", kind="int", low=8),
    "mesh.elements_through": Param(2, "elements through the depth", kind="int", low=1),
    **{**FEM_OPTIONS, "fem.formulation": Param("total_lagrangian", "internal force path", kind="str",
                                               choices=("total_lagrangian", "linear"))},
}


def euler_load(p: dict) -> float:
    I = p["geometry.width"] * p["geometry.thickness"] ** 3 / 12
    return 4 * np.pi**2 * p["material.E"] * I / p["geometry.length"] ** 2


def build(p: dict, mode: str, dem: str):
    L, h = p["geometry.length"], p["geometry.thickness"]
    m = mesh.rectangle(np.linspace(0, L, p["mesh.elements_along"] + 1),
                       np.linspace(-h / 2, h / 2, p["mesh.elements_through"] + 1), p["mesh.element"])
    x = m.p[0]
    pts = m.p.copy()
    pts[1] += p["geometry.imperfection"] * h * 0.5 * (1 - np.cos(2 * np.pi * x / L))
    m = type(m)(pts, m.t)
    D = materials.reduce(materials.isotropic(p["material.E"], p["material.poisson"]), 2, p["fem.hypothesis"])
    region = make_region(m, p, D, p["material.rho"], p["geometry.width"])
    left = region.nodes_where(lambda X: X[0] < 1e-9 * L)
    right = region.nodes_where(lambda X: X[0] > L * (1 - 1e-9))
    clamp = np.concatenate([left * 2, left * 2 + 1, right * 2 + 1])
    omega1 = lowest_modes(region, np.concatenate([clamp, right * 2]), region.mass)[0][0]
    T = p["load.duration_periods"] * 2 * np.pi / omega1
    A = p["geometry.width"] * h
    total = p["load.shortening_factor"] * euler_load(p) * L / (p["material.E"] * A)
    speed = lambda t: -2 * total / T * np.sin(np.pi * t / T) ** 2 if t < T else 0.0  # integrates to -total
    dyn = ExplicitDynamics(region, supports=[PrescribedMotion(clamp), PrescribedMotion(right * 2, speed)],
                           alpha=2 * omega1)
    mid = region.nodes_where(lambda X: np.abs(X[0] - L / 2) < 0.5 * L / p["mesh.elements_along"])
    # compressive axial force = minus the internal force on the shortened end
    probes = {"axial_force": lambda: -float(dyn.f_int[right, 0].sum()) if hasattr(dyn, "f_int") else 0.0,
              "end_shortening": lambda: -float(dyn.state.u[right, 0].mean()),
              "mid_deflection": lambda: float(dyn.state.u[mid, 1].mean())}
    return fem_only(dyn, p, T + p["load.hold_periods"] * 2 * np.pi / omega1, probes)


def evaluate(p: dict, h: dict, mode: str):
    t = h["time"]
    hold = p["load.hold_periods"] / (p["load.duration_periods"] + p["load.hold_periods"])
    plateau = t >= t[-1] * (1 - 0.25 * hold)
    P = float(np.mean(h["axial_force"][plateau]))
    qoi = {"buckling_load": P, "peak_axial_force": float(np.max(h["axial_force"])),
           "max_mid_deflection": float(np.abs(h["mid_deflection"]).max())}
    return qoi, {"buckling_load": check(P, euler_load(p), 0.05, "Euler, clamped-clamped: 4 pi^2 E I / L^2")}


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(1, 2, figsize=(9, 3.5))
    ax[0].plot(h["end_shortening"] * 1e3, h["axial_force"] / 1e3, label="FEM (TL)")
    ax[0].axhline(euler_load(p) / 1e3, color="k", ls="--", label="Euler")
    ax[0].set(xlabel="end shortening [mm]", ylabel="axial force [kN]")
    ax[0].legend()
    ax[1].plot(h["mid_deflection"] * 1e3, h["axial_force"] / 1e3)
    ax[1].set(xlabel="mid-span deflection [mm]", ylabel="axial force [kN]")
    fig.suptitle("clamped-clamped column buckling")
    fig.tight_layout()
    fig.savefig(plots_dir / "buckling.png", dpi=120)
    plt.close(fig)
