"""block_impact: a rigid cylinder (2D) strikes a free elastic block: penalty contact, friction.

A free block and a rigid impactor exchange momentum only through the contact, so the total
momentum must stay what it was (qoi momentum_drift_rel, to round-off). The impact speed and
the normal penalty are parameters: a fast impact with a soft penalty lets the cylinder sink
into the mesh, which the penetration guard stops with exit code 3 and the remedy (the
seed paper's rod study in miniature).
"""
from __future__ import annotations

import numpy as np

from fem_region import materials, mesh
from fem_region.explicit import ExplicitDynamics
from physics.impactor import RigidImpactor

from ..checks import bound
from ..params import Param, isotropic_material, positive
from ..participants.fem import FEM_OPTIONS, fem_only, make_region

NAME = "block_impact"
DESCRIPTION = "FEM: rigid cylinder on a free block, momentum conserved; penetration guard"
MODES = ("fem",)
PARAMETERS = {
    **isotropic_material(70e9, 2700.0, 0.3),
    "geometry.length": positive(0.1, "block length", "m"),
    "geometry.height": positive(0.04, "block height", "m"),
    "geometry.width": positive(0.01, "out-of-plane width", "m"),
    "mesh.elements_along": Param(40, "elements along", kind="int", low=2),
    "mesh.elements_through": Param(16, "elements through the height", kind="int", low=1),
    "impactor.radius": positive(0.01, "cylinder radius", "m"),
    "impactor.mass": positive(0.5, "cylinder mass", "kg"),
    "impactor.penalty": positive(1e9, "normal penalty per contact node", "N/m"),
    "impactor.friction": Param(0.2, "Coulomb friction coefficient", low=0.0, high=2.0),
    "impact.velocity": positive(20.0, "impact speed", "m/s"),
    "impact.angle_deg": Param(20.0, "angle from the surface normal", low=0.0, high=80.0),
    "run.duration": positive(2e-4, "simulated time", "s"),
    **FEM_OPTIONS,
    "fem.hypothesis": Param("plane_strain", "2D hypothesis", kind="str", choices=("plane_stress", "plane_strain")),
}


def build(p: dict, mode: str, dem: str):
    L, H, R = p["geometry.length"], p["geometry.height"], p["impactor.radius"]
    m = mesh.rectangle(np.linspace(0, L, p["mesh.elements_along"] + 1),
                       np.linspace(0, H, p["mesh.elements_through"] + 1), p["mesh.element"])
    D = materials.reduce(materials.isotropic(p["material.E"], p["material.poisson"]), 2, p["fem.hypothesis"])
    region = make_region(m, p, D, p["material.rho"], p["geometry.width"])
    a = np.radians(p["impact.angle_deg"])
    v = p["impact.velocity"] * np.array([np.sin(a), -np.cos(a)])
    imp = RigidImpactor("cylinder", [L / 2, H + R * (1 + 1e-3)], R, p["impactor.mass"], v,
                        penalty=p["impactor.penalty"], friction=p["impactor.friction"])
    dyn = ExplicitDynamics(region, impactors=[imp])
    p0 = dyn.momentum()
    sim = fem_only(dyn, p, p["run.duration"], {
        "momentum_x": lambda: float(dyn.momentum()[0]), "momentum_y": lambda: float(dyn.momentum()[1]),
        "impactor_velocity_y": lambda: float(imp.v[1]), "contact_force": lambda: float(imp.mass * np.linalg.norm(imp.a))})
    sim.probes["momentum_scale"] = lambda: float(np.linalg.norm(p0))
    return sim


def evaluate(p: dict, h: dict, mode: str):
    P = np.column_stack([h["momentum_x"], h["momentum_y"]])
    drift = float(np.abs(P - P[0]).max() / h["momentum_scale"][0])
    qoi = {"momentum_drift_rel": drift, "peak_contact_force": float(h["contact_force"].max()),
           "rebound_velocity_y": float(h["impactor_velocity_y"][-1])}
    return qoi, {"momentum_drift_rel": bound(drift, 1e-10, "momentum of a free block and a rigid impactor")}


def plot(p: dict, h: dict, qoi: dict, plots_dir):
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6, 3.5))
    ax.plot(h["time"] * 1e6, h["contact_force"] / 1e3)
    ax.set(xlabel="time [us]", ylabel="contact force [kN]", title="rigid cylinder on a free block")
    fig.tight_layout()
    fig.savefig(plots_dir / "contact_force.png", dpi=120)
    plt.close(fig)
