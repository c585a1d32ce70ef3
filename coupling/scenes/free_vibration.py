"""free_vibration: an undamped clamped elastic beam released with its first-mode velocity.

Central differences conserve a shadow energy: K + U oscillates by O((omega dt)^2) but must
not drift. qoi energy_drift_rel = max |E(t) - E(0)| / E(0) over the run.
"""
from __future__ import annotations

import numpy as np

from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics, PrescribedMotion
from fem_region.modal import lowest_modes

from ..checks import bound
from ..params import Param, isotropic_material, positive
from ..participants.fem import FEM_OPTIONS, fem_only, make_region

NAME = "free_vibration"
DESCRIPTION = "FEM: undamped clamped beam in its first mode, energy drift over 10^4 steps"
MODES = ("fem",)
PARAMETERS = {
    **isotropic_material(70e9, 2700.0, 0.3),
    "geometry.length": positive(0.2, "free length", "m"),
    "geometry.thickness": positive(0.01, "depth (in plane)", "m"),
    "geometry.width": positive(0.01, "width (out of plane)", "m"),
    "load.tip_velocity": positive(1.0, "peak velocity of the initial mode shape", "m/s"),
    "mesh.elements_along": Param(40, "elements along", kind="int", low=2),
    "mesh.elements_through": Param(4, "elements through the depth", kind="int", low=1),
    "run.steps": Param(10000, "clock steps", kind="int", low=10),
    **FEM_OPTIONS,
}


def build(p: dict, mode: str, dem: str):
    L, h = p["geometry.length"], p["geometry.thickness"]
    m = mesh.rectangle(np.linspace(0, L, p["mesh.elements_along"] + 1),
                       np.linspace(-h / 2, h / 2, p["mesh.elements_through"] + 1), p["mesh.element"])
    D = materials.reduce(materials.isotropic(p["material.E"], p["material.poisson"]), 2, p["fem.hypothesis"])
    region = make_region(m, p, D, p["material.rho"], p["geometry.width"])
    root = region.nodes_where(lambda x: x[0] < 1e-9 * L)
    fixed = np.concatenate([root * 2, root * 2 + 1])
    _, shapes = lowest_modes(region, fixed, region.mass)
    dyn = ExplicitDynamics(region, supports=[PrescribedMotion(fixed)])
    dyn.set_initial_velocity(shapes[0] * p["load.tip_velocity"] / np.abs(shapes[0]).max())
    sim = fem_only(dyn, {**p, "clock.t_end": 1.0}, 1.0, {})  # dt from the stable step ...
    steps = p["run.steps"]  # ... and the run length in steps, as the verification asks
    sim.n_steps, sim.history_every = steps, p["output.history_every"] or max(1, steps // 1000)
    return sim


def evaluate(p: dict, h: dict, mode: str):
    E = h["kinetic"] + h["internal"]
    drift = float(np.abs(E - E[0]).max() / E[0])
    return {"energy_drift_rel": drift}, {"energy_drift_rel": bound(drift, 1e-3, "energy conservation of central differences")}


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.5))
    for k in ("kinetic", "internal"):
        ax.plot(h["time"] * 1e3, h[k], label=k)
    ax.plot(h["time"] * 1e3, h["kinetic"] + h["internal"], "k", label="total")
    ax.set(xlabel="time [ms]", ylabel="energy [J]", title=f"free vibration: drift {qoi['energy_drift_rel']:.2e}")
    ax.legend()
    fig.tight_layout()
    fig.savefig(plots_dir / "energy.png", dpi=120)
    plt.close(fig)
