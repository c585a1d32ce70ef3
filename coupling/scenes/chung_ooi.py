"""Chung & Ooi (2011) DEM benchmarks 1-3: elastic and damped normal impacts against Hertz.

1. two equal spheres, each moving towards the other at ``impact.velocity``;
2. a sphere onto a rigid plane at ``impact.velocity``;
3. a sphere onto a rigid plane with input restitution ``impact.restitution``: the output
   restitution (rebound / impact speed) must equal it.

The rigid plane is a fixed sphere of radius ``plane.radius_ratio`` x R with modulus
``plane.stiffness_ratio`` x E (YADE's wall contact uses R* = R/2 in its Hertz law, so a wall
would not be the benchmark's plane); the references use the same R* = R R2 / (R + R2) and
1/E* = (1 - nu^2)/E + (1 - nu^2)/E2, which differ from the ideal plane by about 1/ratio.
Hertz (VALIDATION.md): delta_max = (15 m* v^2 / (16 E* sqrt(R*)))^(2/5),
F_max = 4/3 E* sqrt(R*) delta_max^(3/2), t_c = 2.9432 delta_max / v (v relative).
The step resolves the contact: t_c / ``clock.steps_per_contact``.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from dem_region.scene import DemScene

from ..checks import check
from ..params import density, modulus, Param, particle_radius, positive
from ..participants.dem import dem_only

COMMON = {
    "material.E": modulus(48e9, "Young's modulus"),
    "material.poisson": Param(0.20, "Poisson ratio", low=0.0, high=0.49),
    "material.rho": density(2800.0),
    "sphere.radius": particle_radius(0.01, "sphere radius"),
    "impact.velocity": positive(10.0, "impact speed (each sphere in test 1)", "m/s"),
    "clock.steps_per_contact": Param(400, "time steps per Hertz contact duration", kind="int", low=20),
}
PLANE = {
    "plane.radius_ratio": Param(1e4, "radius of the sphere standing in for the plane / R", low=10.0),
    "plane.stiffness_ratio": Param(1e6, "its modulus / E", low=10.0),
}


def hertz(p: dict, test: int) -> dict:
    """Closed-form Hertz impact from the run's parameters."""
    E, nu, rho, R, v = (p["material.E"], p["material.poisson"], p["material.rho"], p["sphere.radius"],
                        p["impact.velocity"])
    m = rho * 4.0 / 3.0 * np.pi * R**3
    if test == 1:
        Es, Rs, ms, vr = 1.0 / (2 * (1 - nu**2) / E), R / 2, m / 2, 2 * v
    else:
        R2, E2 = p["plane.radius_ratio"] * R, p["plane.stiffness_ratio"] * E
        Es, Rs, ms, vr = 1.0 / ((1 - nu**2) / E + (1 - nu**2) / E2), R * R2 / (R + R2), m, v
    d = (15 * ms * vr**2 / (16 * Es * np.sqrt(Rs))) ** 0.4
    return {"max_overlap": d, "peak_force": 4.0 / 3.0 * Es * np.sqrt(Rs) * d**1.5, "contact_duration": 2.9432 * d / vr}


def _scene(p: dict, test: int) -> DemScene:
    E, nu, rho, R, v = (p["material.E"], p["material.poisson"], p["material.rho"], p["sphere.radius"],
                        p["impact.velocity"])
    gap = 1e-6 * R
    if test == 1:
        x = np.array([[-R - gap, 0, 0], [R + gap, 0, 0]])
        return DemScene(x, R, rho, np.zeros((0, 2)), 0.0, 0.0, young=E, poisson=nu, contact="hertz_mindlin",
                        velocity=[[v, 0, 0], [-v, 0, 0]])
    R2 = p["plane.radius_ratio"] * R
    x = np.array([[0, 0, R + gap], [0, 0, -R2]])
    e = p.get("impact.restitution", 1.0)
    return DemScene(x, [R, R2], rho, np.zeros((0, 2)), 0.0, 0.0, young=[E, p["plane.stiffness_ratio"] * E],
                    poisson=nu, contact="hertz_mindlin", restitution=e, velocity=[[0, 0, -v], [0, 0, 0]],
                    groups={"fixed": np.array([1])})


def _build(test: int):
    def build(p: dict, mode: str, dem: str):
        ref = hertz(p, test)
        scene = _scene(p, test)
        v = p["impact.velocity"] * (2 if test == 1 else 1)
        t_end = 1.3 * ref["contact_duration"] + 1e-6 * p["sphere.radius"] / v
        sim, backend, _ = dem_only(p, scene, dem, t_end, history_every=1,
                                   dt=ref["contact_duration"] / p["clock.steps_per_contact"])
        axis, sign = (0, -1.0) if test == 1 else (2, 1.0)
        R = scene.radius

        def overlap():
            x = backend.positions()
            return float(R[0] + R[1] - np.linalg.norm(x[0] - x[1]))

        sim.probes.update({"contact_force": lambda: sign * float(backend.forces([0])[0, axis]),
                           "overlap": overlap,
                           "velocity": lambda: sign * float(backend.velocities()[0, axis])})
        return sim
    return build


def _evaluate(test: int):
    def evaluate(p: dict, h: dict, mode: str):
        ref = hertz(p, test)
        t, F = h["time"], h["contact_force"]
        dt = t[1] - t[0]
        on = F[-1] > 0  # the contact had not ended when the run did: its duration was not reached
        qoi = {"peak_force": float(F.max()), "contact_duration": float("nan") if on else float((F > 0).sum() * dt),
               "max_overlap": float(h["overlap"].max())}
        src = "Hertz impact (Chung & Ooi 2011 test %d)" % test
        checks = {k: check(qoi[k], ref[k], 0.03, src) for k in ("peak_force", "contact_duration", "max_overlap")}
        if test == 3:
            v_in = p["impact.velocity"]
            e_out = float("nan") if on else float(abs(h["velocity"][-1]) / v_in)  # (no rebound yet)
            qoi = {"output_restitution": e_out, **qoi}
            checks = {"output_restitution": check(e_out, p["impact.restitution"], 0.02, "input restitution")}
        return qoi, checks
    return evaluate


def _plot(test: int):
    def plot(p: dict, h: dict, qoi: dict, plots_dir):
        import matplotlib.pyplot as plt
        ref = hertz(p, test)
        fig, ax = plt.subplots(figsize=(6, 3.5))
        ax.plot(h["overlap"] * 1e6, h["contact_force"] / 1e3, label="YADE Hertz-Mindlin")
        d = np.linspace(0, ref["max_overlap"], 100)
        Fh = ref["peak_force"] * (d / ref["max_overlap"]) ** 1.5
        ax.plot(d * 1e6, Fh / 1e3, "k--", label="Hertz F(delta)")
        ax.set(xlabel="overlap [um]", ylabel="contact force [kN]", title=f"Chung & Ooi test {test}")
        ax.legend()
        fig.tight_layout()
        fig.savefig(plots_dir / "force_overlap.png", dpi=120)
        plt.close(fig)
    return plot


def _scene_module(test: int, name: str, description: str, params: dict) -> SimpleNamespace:
    return SimpleNamespace(NAME=name, DESCRIPTION=description, MODES=("dem",), PARAMETERS=params,
                           build=_build(test), evaluate=_evaluate(test), plot=_plot(test))


CHUNG_OOI_1 = _scene_module(1, "chung_ooi_1", "DEM: two equal spheres head on vs Hertz (Chung & Ooi test 1)", COMMON)
CHUNG_OOI_2 = _scene_module(2, "chung_ooi_2", "DEM: sphere on a rigid plane vs Hertz (Chung & Ooi test 2)",
                            {**COMMON, **PLANE})
CHUNG_OOI_3 = _scene_module(3, "chung_ooi_3", "DEM: restitution out = in (Chung & Ooi test 3)",
                            {**COMMON, **PLANE, "impact.restitution": Param(0.5, "input coefficient of restitution",
                                                                             low=0.05, high=1.0)})
