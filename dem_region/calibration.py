"""From continuum constants to bond parameters.

Closed forms for regular lattices (used directly and as starting values of the inverse
calibration): a triangular (hexagonal) lattice of spacing d = 2r joined by central springs
kn behaves, for uniform strain, as an isotropic plane-stress solid with
E = 2 kn / (sqrt(3) t) and nu = 1/3 (t: layer thickness, here t = 2r), and carries
mass rho * (sqrt(3) / 2) d^2 t per particle. A square lattice with axial springs k1 and
diagonal springs k2 = k1 / 2 is isotropic too: C11 = (k1 + k2) / t, C12 = C66 = k2 / t, so
nu = 1/3 and E = 4 k1 / (3 t).
"""
from __future__ import annotations

import numpy as np


def hexagonal_kn(E: float, radius: float) -> float:
    """Normal bond stiffness (N/m) of a quasi-2D hexagonal layer (t = 2r) with modulus E (Pa)."""
    return np.sqrt(3.0) * radius * E


def hexagonal_modulus(kn: float, radius: float) -> float:
    """Plane-stress modulus (Pa) of a hexagonal layer of bonds kn (N/m), thickness 2r."""
    return 2.0 * kn / (np.sqrt(3.0) * 2.0 * radius)


def hexagonal_density(rho: float) -> float:
    """Sphere density (kg/m^3) that gives a hexagonal layer (t = 2r) the continuum density rho."""
    return rho * 3.0 * np.sqrt(3.0) / np.pi


def square_kn(E: float, radius: float) -> tuple[float, float]:
    """(axial, diagonal) bond stiffness (N/m) of an isotropic square layer (t = 2r) of modulus E."""
    k1 = 0.75 * E * 2.0 * radius
    return k1, 0.5 * k1


def square_density(rho: float) -> float:
    """Sphere density giving a square layer (t = 2r, area (2r)^2 per particle) density rho."""
    return rho * 8.0 / (4.0 / 3.0 * np.pi)


# -- virtual tests on a bonded block (any engine) ----------------------------------------------

import hashlib
import json
import os
from dataclasses import dataclass, replace
from pathlib import Path


@dataclass(frozen=True)
class BlockResponse:
    """Measured homogenised response of a bonded block: E (Pa), nu (-), and for a pull to
    failure the peak stress (Pa); scale: the bond stiffness scale (-) it was measured at."""

    E: float
    nu: float
    peak_stress: float = float("nan")
    scale: float = 1.0
    engine_version: str = ""


def faces(scene, axis: int, tol: float = 0.5):
    """(low, high) particle indices within tol * r of the block's two faces normal to ``axis``."""
    x = scene.x[:, axis]
    r = scene.radius
    return np.flatnonzero(x <= x.min() + tol * r), np.flatnonzero(x >= x.max() - tol * r)


def cross_section(scene, axis: int) -> float:
    """Area (m^2) normal to ``axis`` covered by the packing (layer thickness 2r in 2D)."""
    others = [a for a in range(3) if a != axis and (a != 2 or not scene.plane)]
    d = 2 * float(np.median(scene.radius))
    area = np.prod([np.ptp(scene.x[:, a]) + d for a in others])
    return float(area * (d if scene.plane else 1.0))


def virtual_tension(scene, engine: str = "yade", axis: int = 0, strain: float = 2e-4, to_failure: bool = False,
                    damping: float = 0.6, periods: float = 12.0) -> BlockResponse:
    """Quasi-static uniaxial tension of a bonded block in a DEM engine.

    The face particles normal to ``axis`` are driven along ``axis`` only (free laterally, so
    the block contracts as it likes); the far face moves by ``strain`` times the block length
    on a smooth ramp and is then held, with Cundall damping ``damping``, until static.
    E = (reaction / area) / strain; nu from the mid-length lateral contraction. With
    to_failure, the pull continues to 2 x strain and peak_stress is the largest stress before
    the first failure (the stress falling below 80 % of its running maximum): a perfectly
    regular lattice fails everywhere at once and what is left could carry load again later.
    """
    from .backends import make_backend

    lo, hi = faces(scene, axis)
    test = replace(scene, local_damping=damping, velocity=np.zeros_like(scene.x), groups={})
    eng = make_backend(engine)
    try:
        eng.build(test)
        dt = 0.5 * eng.critical_dt()
        L = float(np.ptp(scene.x[:, axis]))
        n_along = max(2, int(round(L / (2 * float(np.median(scene.radius))))))
        # the block's axial period is about 2 n_along stable steps (times pi): ramp over a few
        ramp = int(periods * np.pi * n_along * 2)
        total = strain * L * (2.0 if to_failure else 1.0)  # to failure: twice the expected strain
        steps = ramp * (2 if to_failure else 1)
        speed = total / (steps * dt)
        eng.prescribe(lo, "xyz"[axis])
        eng.prescribe(hi, "xyz"[axis])
        v_hi = np.zeros((len(hi), 3))
        state = {"k": 0, "peak": 0.0, "failed": False}
        area = cross_section(scene, axis)

        def drive():
            k = state["k"]
            s = np.sin(np.pi * min(k, steps) / steps) ** 2 if k < steps else 0.0
            v_hi[:, axis] = 2 * speed * s  # sin^2 ramp: mean speed over the ramp is `speed`
            eng.set_velocities(lo, np.zeros((len(lo), 3)))
            eng.set_velocities(hi, v_hi)
            sigma = -float(eng.forces(hi)[:, axis].sum()) / area
            if not state["failed"]:
                state["failed"] = state["peak"] > 0 and sigma < 0.8 * state["peak"]
                state["peak"] = max(state["peak"], sigma) if not state["failed"] else state["peak"]
            state["k"] += 1

        eng.set_dt(dt)
        eng.start(drive)
        for _ in range(steps + (0 if to_failure else ramp)):
            eng.advance(drive)
        x = eng.positions()
        eps = (x[hi, axis].mean() - x[lo, axis].mean()) / (scene.x[hi, axis].mean() - scene.x[lo, axis].mean()) - 1
        sigma = -float(eng.forces(hi)[:, axis].sum()) / area
        lat = 1 if axis != 1 else 0
        mid = np.abs(scene.x[:, axis] - scene.x[:, axis].mean()) < 0.25 * L
        top = mid & (scene.x[:, lat] >= scene.x[mid, lat].max() - 0.5 * scene.radius)
        bot = mid & (scene.x[:, lat] <= scene.x[mid, lat].min() + 0.5 * scene.radius)
        h0 = scene.x[top, lat].mean() - scene.x[bot, lat].mean()
        eps_lat = (x[top, lat].mean() - x[bot, lat].mean()) / h0 - 1
        return BlockResponse(E=sigma / eps if not to_failure else float("nan"), nu=-eps_lat / eps,
                             peak_stress=state["peak"] if to_failure else float("nan"), engine_version=eng.version)
    finally:
        eng.finalize()


def cache_dir() -> Path:
    """The calibrations' cache: in the project's cache directory (FEMDEM_CACHE_DIR, which the
    orchestrator sets to one this user can write; a home that is not a directory failed here)."""
    base = os.environ.get("FEMDEM_CACHE_DIR")
    if base:
        return Path(base) / "calibration"
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "femdem" / "calibration"


def _key(scene, engine: str) -> str:
    h = hashlib.sha1()
    for a in (scene.x, scene.radius, scene.bonds, scene.kn / scene.kn.max(), scene.ks / scene.kn.max(), scene.density):
        h.update(np.ascontiguousarray(a).tobytes())
    h.update(f"{engine}|{scene.plane}".encode())
    return h.hexdigest()[:20]


def calibrate_modulus(scene, E_target: float, engine: str = "yade", use_cache: bool = True):
    """Scale every bond stiffness of ``scene`` so that its block modulus is E_target (Pa).

    The response of a bonded packing is linear in the bond stiffness scale, so one virtual
    tension test fixes the scale; the result (E per unit scale, nu) is cached per packing,
    bond pattern and engine under cache_dir(). Returns (calibrated scene, BlockResponse at
    unit scale, cache hit)."""
    path = cache_dir() / f"{_key(scene, engine)}.json"
    hit = use_cache and path.exists()
    if hit:
        d = json.loads(path.read_text())
        resp = BlockResponse(d["E"], d["nu"])
    else:
        resp = virtual_tension(scene, engine)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps({"E": resp.E, "nu": resp.nu, "engine": engine}))
        os.replace(tmp, path)
    s = E_target / resp.E
    return replace(scene, kn=scene.kn * s, ks=scene.ks * s), resp, hit


def virtual_shear(scene, engine: str = "yade", gamma: float = 2e-4, damping: float = 0.6,
                  periods: float = 12.0) -> float:
    """Shear modulus G (Pa) of a bonded layer from a quasi-static simple shear test: every
    boundary particle follows the affine field u_x = gamma (y - y0), the interior relaxes
    with Cundall damping; G = (force on the top face along x / its area) / gamma."""
    from .backends import make_backend

    x = scene.x
    r = float(np.median(scene.radius))
    y0, y1 = x[:, 1].min(), x[:, 1].max()
    x0, x1 = x[:, 0].min(), x[:, 0].max()
    edge = (x[:, 1] < y0 + 0.5 * r) | (x[:, 1] > y1 - 0.5 * r) | (x[:, 0] < x0 + 0.5 * r) | (x[:, 0] > x1 - 0.5 * r)
    boundary, top = np.flatnonzero(edge), np.flatnonzero(x[:, 1] > y1 - 0.5 * r)
    eng = make_backend(engine)
    try:
        eng.build(replace(scene, local_damping=damping, velocity=np.zeros_like(x), groups={}))
        dt = 0.5 * eng.critical_dt()
        n = max(2, int(round(max(x1 - x0, y1 - y0) / (2 * r))))
        ramp = int(periods * np.pi * n * 2)
        eng.prescribe(boundary)
        v = np.zeros((len(boundary), 3))
        k = [0]

        def drive():
            s = 2 * np.sin(np.pi * min(k[0], ramp) / ramp) ** 2 if k[0] < ramp else 0.0
            v[:, 0] = gamma / (ramp * dt) * s * (x[boundary, 1] - y0)
            eng.set_velocities(boundary, v)
            k[0] += 1

        eng.set_dt(dt)
        eng.start(drive)
        for _ in range(2 * ramp):
            eng.advance(drive)
        xs = eng.positions()
        g = (xs[top, 0] - x[top, 0]).mean() / (y1 - y0)
        area = (x1 - x0 + 2 * r) * (2 * r if scene.plane else np.ptp(x[:, 2]) + 2 * r)
        return -float(eng.forces(top)[:, 0].sum()) / area / g
    finally:
        eng.finalize()


def calibrate_orthotropic(scene, E1: float, E2: float, engine: str = "yade", axis1: int = 0):
    """Direction-dependent bond stiffness for a ply layer: bonds along ``axis1`` (the fibre)
    and across it are scaled separately so that tension tests give E1 along the fibre and E2
    across it; diagonal bonds keep the scale of an isotropic calibration to E2.

    For a lattice the modulus along a direction is linear in the scale of the bonds along it
    when the other scale is held (E1 = C11 - C12^2 / C22, only C11 depends on them), so two
    tests per direction fix each scale; the two directions are coupled through C12^2 / C22,
    so the pair is iterated (three rounds: the coupling is weak). Returns (scene, measured
    (E1, E2) after calibration)."""
    base, _, _ = calibrate_modulus(scene, E2, engine)
    dx = base.x[base.bonds[:, 1]] - base.x[base.bonds[:, 0]]
    u = np.abs(dx) / np.linalg.norm(dx, axis=1)[:, None]
    along = u[:, axis1] > 1 - 1e-9
    across = (u.max(axis=1) > 1 - 1e-9) & ~along
    axis2 = [a for a in (0, 1) if a != axis1][0]

    def with_scales(s1, s2):
        f = np.where(along, s1, np.where(across, s2, 1.0))
        return replace(base, kn=base.kn * f, ks=base.ks * f)

    scales = [1.0, 1.0]
    for _ in range(3):
        for axis, target, sel in ((axis1, E1, 0), (axis2, E2, 1)):
            trial = list(scales)
            trial[sel] = 1.0
            E_a = virtual_tension(with_scales(*trial), engine, axis).E
            trial[sel] = 2.0
            slope = virtual_tension(with_scales(*trial), engine, axis).E - E_a
            scales[sel] = 1.0 + (target - E_a) / slope
    out = with_scales(*scales)
    return out, (virtual_tension(out, engine, axis1).E, virtual_tension(out, engine, axis2).E)
