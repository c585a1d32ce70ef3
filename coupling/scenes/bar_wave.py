"""bar_wave: a smooth velocity pulse travels along a free elastic bar (FEM far field check).

The bar speed sqrt(E / rho) holds for pulses much longer than the bar height, in plane
stress. Arrival times at two stations are the centroids of the axial-velocity signals.
"""
from __future__ import annotations

import numpy as np

from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion

from ..checks import check
from ..params import Param, isotropic_material, positive
from ..participants.fem import FEM_OPTIONS, fem_only, make_region

NAME = "bar_wave"
DESCRIPTION = "velocity pulse in a free bar; wave speed against sqrt(E/rho)"
MODES = ("fem",)
PARAMETERS = {
    **isotropic_material(200e9, 7800.0, 0.3),
    "geometry.length": positive(1.0, "bar length", "m"),
    "geometry.height": positive(0.02, "bar height (in plane)", "m"),
    "geometry.width": positive(0.02, "bar width (out of plane)", "m"),
    "mesh.elements_along": Param(400, "elements along the bar", kind="int", low=10),
    "mesh.elements_through": Param(2, "elements through the height", kind="int", low=1),
    "load.velocity": positive(0.1, "peak end velocity of the pulse", "m/s"),
    "load.pulse_length": Param(0.1, "pulse length as a fraction of the bar length", low=0.02, high=0.3),
    **FEM_OPTIONS,
}
STATIONS = (0.3, 0.7)  # fractions of the length where arrival times are measured


def bar_speed(p: dict) -> float:
    return float(np.sqrt(p["material.E"] / p["material.rho"]))


def build(p: dict, mode: str, dem: str):
    L, H = p["geometry.length"], p["geometry.height"]
    m = mesh.rectangle(np.linspace(0, L, p["mesh.elements_along"] + 1),
                       np.linspace(0, H, p["mesh.elements_through"] + 1), p["mesh.element"])
    C = materials.isotropic(p["material.E"], p["material.poisson"])
    region = make_region(m, p, materials.reduce(C, 2, p["fem.hypothesis"]), p["material.rho"], p["geometry.width"])
    T = p["load.pulse_length"] * L / bar_speed(p)
    v0 = p["load.velocity"]
    end = region.nodes_where(lambda x: x[0] < 1e-12 * L)
    pulse = lambda t: v0 * np.sin(np.pi * t / T) ** 2 if t < T else 0.0
    dyn = ExplicitDynamics(region, supports=[PrescribedMotion(end * 2, pulse)])
    probes = {}
    for s in STATIONS:
        nodes = region.nodes_where(lambda x, s=s: np.abs(x[0] - s * L) < 0.5 * L / p["mesh.elements_along"])
        probes[f"velocity_x_{s:g}L"] = lambda nodes=nodes: float(dyn.state.v[nodes, 0].mean())
    # stop before the pulse reflected at the free end comes back to the far station
    t_end = (STATIONS[1] * L + T * bar_speed(p)) / bar_speed(p) + 0.5 * T
    return fem_only(dyn, p, t_end, probes)


def evaluate(p: dict, h: dict, mode: str):
    L = p["geometry.length"]
    t = h["time"]
    arrivals = []
    for s in STATIONS:
        v = h[f"velocity_x_{s:g}L"]
        area = np.trapz(v, t)  # zero if the pulse never reached the station (t_end too short)
        arrivals.append(float(np.trapz(t * v, t) / area) if area > 0 else float("nan"))
    c = (STATIONS[1] - STATIONS[0]) * L / (arrivals[1] - arrivals[0])
    qoi = {"wave_speed": c, "arrival_time_near": arrivals[0], "arrival_time_far": arrivals[1]}
    checks = {"wave_speed": check(c, bar_speed(p), 0.01, "bar wave speed sqrt(E/rho)")}
    return qoi, checks


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for s in STATIONS:
        ax.plot(h["time"] * 1e6, h[f"velocity_x_{s:g}L"], label=f"x = {s:g} L")
    for s in STATIONS:
        ax.axvline((s * p["geometry.length"] / bar_speed(p) + 0.5 * p["load.pulse_length"] * p["geometry.length"] / bar_speed(p)) * 1e6,
                   color="k", lw=0.6, ls="--")
    ax.set(xlabel="time [us]", ylabel="axial velocity [m/s]",
           title=f"bar wave: c = {qoi['wave_speed']:.1f} m/s, sqrt(E/rho) = {bar_speed(p):.1f} m/s")
    ax.legend()
    fig.tight_layout()
    fig.savefig(plots_dir / "velocity_at_stations.png", dpi=120)
    plt.close(fig)
