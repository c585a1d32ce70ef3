"""Linear stability of the subcycled coupled step, with and without the interface band.

Usage: .venv/bin/python benchmarks/subcycling_linear.py [--case panel_buckling_coarse]
           [--set key=value ...] [--substeps 2 3 4] [--steps 20000] [--scales 1.0 0.9]

Builds the case's coupled model (not run), then iterates the linearised coupled step: the
FEM's assembled stiffness K, the DEM bonds and the coupling layer's law bonds as springs
(normal kn, shear ks along each bond's reference direction, law bonds isotropic K x area),
slaved interface particles x_p = W x_nodes, in the clock's order (fast forces, slow kick at
the window's first substep, fast kick, drift; coupling/participants/clock.py). From a random state it
reports the growth of the energy over --steps FEM steps (the largest value in the last tenth
over the largest in the first tenth): about 1 is stable, growth is the impulse resonance.
--scales multiplies the DEM stiffnesses (a softened, damaged zone moves its spectrum). No
damping, no contact: the undamaged, undamped operator, the hardest case for resonance.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def build(case: str, sets: list[str], dem: str):
    """(simulation, CoupledClock) of a case in coupled mode (the clock taken as it is made)."""
    import coupling.participants.clock as cc
    from coupling.case import load_case
    from coupling.params import parse_set
    made = {}
    init = cc.CoupledClock.__init__

    def keep(self, *a, **k):
        init(self, *a, **k)
        made["clock"] = self
    cc.CoupledClock.__init__ = keep
    try:
        c = load_case(case, parse_set(sets))
        sim = c.scene.build(c.parameters, "coupled", dem)
    finally:
        cc.CoupledClock.__init__ = init
    return sim, made["clock"]


def operators(clock) -> dict:
    """Sparse operators of the linearised step: FEM K, particle springs Kp, the maps from
    node and free-particle displacements to every particle's, masses, prescribed FEM DOFs."""
    fem, sc, itf = clock.fem, clock.dem.scene, clock.tie.itf
    dim, n = fem.region.dim, sc.n
    pairs, kn, ks = [sc.bonds], [sc.kn * np.ones(len(sc.bonds))], [sc.ks * np.ones(len(sc.bonds))]
    for m in clock.models:
        if hasattr(m, "pairs"):
            k = np.broadcast_to(m.law.K, (len(m.pairs),)) * m.area
            pairs.append(m.pairs), kn.append(k), ks.append(k)
    pairs, kn, ks = np.vstack(pairs), np.concatenate(kn), np.concatenate(ks)
    d = sc.x[pairs[:, 1], :dim] - sc.x[pairs[:, 0], :dim]
    e = d / np.linalg.norm(d, axis=1)[:, None]
    nn_ = e[:, :, None] * e[:, None, :]
    blk = kn[:, None, None] * nn_ + ks[:, None, None] * (np.eye(dim) - nn_)
    I, J = pairs[:, :1] * dim + np.arange(dim), pairs[:, 1:] * dim + np.arange(dim)
    r, c, v = [], [], []
    for A, B, sign in ((I, I, 1), (J, J, 1), (I, J, -1), (J, I, -1)):
        r.append(np.repeat(A, dim, axis=1).ravel()), c.append(np.tile(B, (1, dim)).ravel()), v.append(sign * blk.ravel())
    Kp = sp.csr_matrix((np.concatenate(v), (np.concatenate(r), np.concatenate(c))), shape=(n * dim,) * 2)
    P = sp.coo_matrix((np.ones(len(itf.ids)), (itf.ids, np.arange(len(itf.ids)))), shape=(n, len(itf.ids)))
    Tn = (sp.kron(P, sp.eye(dim)) @ sp.kron(sp.csr_matrix(itf.W), sp.eye(dim))).tocsr()
    free = np.setdiff1d(np.arange(n), itf.ids)
    Tf = sp.kron(sp.coo_matrix((np.ones(len(free)), (free, np.arange(len(free)))), shape=(n, len(free))),
                 sp.eye(dim)).tocsr()
    return {"K": fem.region.K.tocsr(), "Kp": Kp, "Tn": Tn, "Tf": Tf, "M": np.repeat(fem.m, dim),
            "mf": np.repeat(sc.mass[free], dim), "fixed": fem._prescribed, "region": fem.region, "itf": itf}


def band_split(ops: dict, band: bool):
    """(K_fast, K_slow): the band's element stiffness and the rest (K_fast = 0 without band)."""
    from coupling.participants.clock import interface_band
    region = ops["region"]
    e = interface_band(region, ops["itf"].W) if band else np.zeros(0, int)
    ed, ke = region._edofs[e], region.ke[e]  # noqa: SLF001 (the assembled element data)
    rows, cols = np.repeat(ed, ed.shape[1], axis=1).ravel(), np.tile(ed, (1, ed.shape[1])).ravel()
    Kb = sp.csr_matrix((ke.ravel(), (rows, cols)), shape=ops["K"].shape)
    return Kb, (ops["K"] - Kb).tocsr()


def growth(ops: dict, Kb, Ks, dt: float, m: int, steps: int, scale: float, seed: int = 0) -> float:
    Kp, Tn, Tf, M, mf = ops["Kp"] * scale, ops["Tn"], ops["Tf"], ops["M"], ops["mf"]
    TnT, TfT, K = Tn.T.tocsr(), Tf.T.tocsr(), Kb + Ks
    rng = np.random.default_rng(seed)
    u = 1e-6 * rng.standard_normal(M.size)
    u[ops["fixed"]] = 0.0
    v, xf, vf = np.zeros_like(u), 1e-6 * rng.standard_normal(mf.size), np.zeros(mf.size)
    h, E = dt / m, []
    for _ in range(steps):
        for k in range(m):
            X = Tn @ u + Tf @ xf
            f = -(Kp @ X)
            if k == 0:
                v -= dt * (Ks @ u) / M
                E.append(0.5 * (v @ (M * v) + u @ (K @ u) + vf @ (mf * vf) - X @ f))
            v += h * (TnT @ f - Kb @ u) / M
            v[ops["fixed"]] = 0.0
            u += h * v
            vf += h * (TfT @ f) / mf
            xf += h * vf
    q = max(1, steps // 10)
    return max(E[-q:]) / max(E[:q])


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="panel_buckling_coarse")
    ap.add_argument("--set", action="append", default=[], dest="sets")
    ap.add_argument("--substeps", type=int, nargs="+", default=[2, 3, 4])
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--scales", type=float, nargs="+", default=[1.0, 0.9])
    ap.add_argument("--dem", default="liggghts")
    a = ap.parse_args()
    sim, clock = build(a.case, a.sets, a.dem)
    ci, ops = sim.clock_info, operators(clock)
    sim.close()
    print(f"{a.case}: {ops['M'].size} FEM DOFs, {ops['mf'].size} free particle DOFs, "
          f"dt_fem / dt_dem (stable) = {ci['dt_stable_fem'] / ci['dt_stable_dem']:.2f}")
    for band in (False, True):
        Kb, Ks = band_split(ops, band)
        for m in a.substeps:
            dt = 0.9 * min(ci["dt_stable_fem"], m * ci["dt_stable_dem"])
            t0 = time.perf_counter()
            g = [growth(ops, Kb, Ks, dt, m, a.steps, s) for s in a.scales]
            print(f"band {'on ' if band else 'off'} m = {m:2d} (dt = {dt:.3g} s): energy growth over {a.steps} steps "
                  + ", ".join(f"x {x:.3g} (stiffness x {s:g})" for x, s in zip(g, a.scales))
                  + f"  [{time.perf_counter() - t0:.1f} s]", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
