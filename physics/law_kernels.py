"""The law bonds' step fused into two compiled passes over all cores (numba prange).

Pass 1, over bonds: each bond reads the positions, forms its separation (fixed normal with the
interface's rotation-free slip terms, or a corotated frame), initiates (PlyBondLaw: Hoffman on
the Love-Weber stress of the last tractions), calls the law of one bond (laws.hashin_bond,
laws.ply_bond: the equations live there, once), adds friction on closed failed faces, and
writes only its own rows: separation, traction, damage, and the force vectors it exerts on
particles ("slots": F on its second end, which its first end takes with minus sign, and per
tangent the slope or spin forces on the particles of its neighbour pairs).
Pass 2, over particles: each particle sums the slots aimed at it from a precomputed incidence
list and adds the sum to the force array in place. No two threads write the same row, so the
scatter is race-free; the incidence lists are sorted in the order the serial reference
(LawBonds.apply_reference) adds the same terms, so the forces equal the reference's bit for
bit. Nothing is allocated per step: every buffer belongs to the bonds' plan.
"""
from __future__ import annotations

import os

import numba
import numpy as np
from numba import prange, types
from numba.experimental import structref

from .compiled import kernel
from .kernels import hoffman_bond, hoffman_bond_aligned
from .laws import hashin_bond, ply_bond

if "NUMBA_THREADING_LAYER" not in os.environ:
    # OpenMP: a parallel region wakes its threads in microseconds here; with TBB a pass over a
    # few hundred bonds on two threads took 0.5-1 ms (measured, 2-core VM). Chosen lazily: the
    # layer loads (and sets the OpenMP thread count) at the first parallel launch only.
    numba.config.THREADING_LAYER = "omp"

# families smaller than this run the serial build: below it a launch's thread wake-ups cost what
# the second thread saves. The kernels back to back pay from about 500 bonds (2 threads against
# 1, ns per bond-step: 441 interface bonds 71 / 76, 3,063 ply bonds 31 / 43); inside a coupled
# step, where the threads have slept through the engine's and the FEM's work, from about 1,500
# (beam_impact, the models bucket with the ply family parallel / serial: a 2.7 mm zone, 1,003 ply
# bonds, 4.31 / 4.11 s; 6 mm, about 2,200, 5.51 / 7.35 s; all-DEM, 9,198, 16.6 / 25.4 s;
# docs/benchmarks.md, session 35)
PARALLEL_BONDS = 1_500
# False where an engine owns the process's OpenMP runtime (YADE: numba's OpenMP layer would set
# its thread count at each launch, and a YADE step on more threads than asked sums its forces in
# another order from run to run), and on an engine's several MPI ranks (each rank a process of
# its own: threads in each would take more cores than the machine has)
THREADS_ALLOWED = True
HASHIN, PLY, ELASTIC = 0, 1, 2  # law families (ELASTIC: a PlyBondLaw that never initiates)
FIXED, CENTRAL, FRAME_2D = 0, 1, 2  # kinematics: fixed normal, corotated central, corotated 2D frame


def _bonds_pass(x, end, loc, d0, normal, area, Kb,
               kin, X_mid, dir_a, dir_b, dir_e, dir_h, un, s0, L0, axis, local, rot, chord,
               law, hp, pstress, inc_ptr, inc_bond, cell, axes, aligned, ply_axes, scale, hk, Gf, m0, mf, index, crushed,
               friction, v_reg, visc, dt, time, damage, delta, traction, t_failed, slots, active):
    """One step of the bonds ``active`` (indices into nb bonds: all of them, or the share one
    MPI rank evaluates; the others' rows are left as they are). x (N, 3) m positions; end (nb, 2) rows of the bond ends in x;
    loc (nb, 2) the same ends as rows of the bonds' own particle list (pstress, cell);
    d0 (nb, 3) m reference branch vectors; normal (nb, 3); area (nb,) m^2; Kb (nb,) Pa/m.
    Kinematics ``kin``: FIXED (with ndir = len(dir_a) tangents: neighbour bonds dir_a, dir_b
    (ndir, nb), unit tangents dir_e (ndir, nb, 3), h / span dir_h (ndir, nb), scratch un (nb,),
    reference midpoints X_mid (nb, 3)); CENTRAL (L0 (nb,) m, axis (nb, 3) out); FRAME_2D
    (reference chord s0 (nb, 3), out: local (nb, 3), rot (nb, 2), chord (nb, 3)).
    Law ``law``: HASHIN with hp = (K, Z0, R0, GIc, GIIc, eta, bk); ELASTIC (K dn, no state);
    PLY with pstress (np, 6)
    scratch (Love-Weber stress, Voigt Pa), each particle's bonds inc_bond[inc_ptr[p]:inc_ptr[p + 1]] in bond order, cell (np,) m^3, distinct ply axes (a, 3, 3) and each bond's ply_axes (nb,), scale (nb,),
    hk = kernels.hoffman_coefficients(strengths),
    Gf (nb, c) J/m^2, state m0, mf, index (nb,) (of the bonds not yet initiated), crushed (nb,)
    bool updated. visc (nb,) Pa s/m: each bond's damper (LawBonds.damping).
    State updated in place: damage (nb,), delta, traction (nb, 3), t_failed (nb,) s; slots
    (nb, S, 3) N: 0 the force on the second end (its first end takes minus it), then per tangent
    the vector on each particle of the next pair b and of the previous pair a. Returns (work of
    this step J, the friction's share of it J, the dampers' J, new snapbacks): the friction's, the
    work of the tangential tractions of failed bonds (their normal one is the contact's penalty);
    the dampers', their traction times the separation's increment."""
    nb = end.shape[0]
    ndir = dir_a.shape[0]
    if kin == FIXED and ndir > 0:  # the pairs' mean normal displacement, for the slope terms
        for m in prange(nb):
            i, j = end[m, 0], end[m, 1]
            u = 0.0
            for k in range(3):
                u += (0.5 * (x[i, k] + x[j, k]) - X_mid[m, k]) * normal[m, k]
            un[m] = u
    if law == PLY:  # Love-Weber stress of each particle from the last tractions (its own bonds)
        for p in prange(pstress.shape[0]):
            s00 = s01 = s02 = s10 = s11 = s12 = s20 = s21 = s22 = 0.0
            for e in range(inc_ptr[p], inc_ptr[p + 1]):
                mb = inc_bond[e]
                f0, f1, f2 = 0.5 * (area[mb] * traction[mb, 0]), 0.5 * (area[mb] * traction[mb, 1]), \
                    0.5 * (area[mb] * traction[mb, 2])
                l0, l1, l2 = d0[mb, 0], d0[mb, 1], d0[mb, 2]
                s00 += f0 * l0
                s01 += f0 * l1
                s02 += f0 * l2
                s10 += f1 * l0
                s11 += f1 * l1
                s12 += f1 * l2
                s20 += f2 * l0
                s21 += f2 * l1
                s22 += f2 * l2
            # symmetrised, per unit volume (Voigt order xx, yy, zz, yz, xz, xy)
            v = cell[p]
            pstress[p, 0], pstress[p, 1], pstress[p, 2] = 0.5 * (s00 + s00) / v, 0.5 * (s11 + s11) / v, \
                0.5 * (s22 + s22) / v
            pstress[p, 3], pstress[p, 4], pstress[p, 5] = 0.5 * (s12 + s21) / v, 0.5 * (s02 + s20) / v, \
                0.5 * (s01 + s10) / v
    work = 0.0
    fwork = 0.0
    vwork = 0.0
    snapbacks = 0
    for a_ in prange(active.shape[0]):
        m = active[a_]
        i, j = end[m, 0], end[m, 1]
        n0, n1, n2 = normal[m, 0], normal[m, 1], normal[m, 2]
        o0, o1, o2 = delta[m, 0], delta[m, 1], delta[m, 2]  # separation and traction of the last step
        r0, r1, r2 = traction[m, 0], traction[m, 1], traction[m, 2]
        # -- kinematics: the separation delta (m) in the bond's frame
        if kin == CENTRAL:
            e0, e1, e2 = x[j, 0] - x[i, 0], x[j, 1] - x[i, 1], x[j, 2] - x[i, 2]
            L = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
            axis[m, 0], axis[m, 1], axis[m, 2] = e0 / L, e1 / L, e2 / L
            s = L - L0[m]
            g0, g1, g2 = s * n0, s * n1, s * n2
        elif kin == FRAME_2D:
            a, b = dir_a[0, m], dir_b[0, m]
            for k in range(2):
                chord[m, k] = 0.5 * (x[end[b, 0], k] + x[end[b, 1], k] - x[end[a, 0], k] - x[end[a, 1], k])
            chord[m, 2] = 0.0
            th = np.arctan2(s0[m, 0] * chord[m, 1] - s0[m, 1] * chord[m, 0],
                            s0[m, 0] * chord[m, 0] + s0[m, 1] * chord[m, 1])
            c, sn = np.cos(th), np.sin(th)
            dx, dy = x[j, 0] - x[i, 0], x[j, 1] - x[i, 1]
            local[m, 0] = c * dx + sn * dy
            local[m, 1] = -sn * dx + c * dy
            local[m, 2] = x[j, 2] - x[i, 2]
            rot[m, 0], rot[m, 1] = c, sn
            g0, g1, g2 = local[m, 0] - d0[m, 0], local[m, 1] - d0[m, 1], local[m, 2] - d0[m, 2]
        else:
            g0 = x[j, 0] - x[i, 0] - d0[m, 0]
            g1 = x[j, 1] - x[i, 1] - d0[m, 1]
            g2 = x[j, 2] - x[i, 2] - d0[m, 2]
            for t in range(ndir):  # rotation-free slip: + h d(u_n)/ds along each tangent
                w = dir_h[t, m] * (un[dir_b[t, m]] - un[dir_a[t, m]])
                g0, g1, g2 = g0 + w * dir_e[t, m, 0], g1 + w * dir_e[t, m, 1], g2 + w * dir_e[t, m, 2]
        dn = g0 * n0 + g1 * n1 + g2 * n2
        # -- the law
        d_old = damage[m]
        if law == PLY:
            if m0[m] == 0.0:  # not initiated: Hoffman on the mean of the end particles' stresses
                p, q = loc[m, 0], loc[m, 1]
                sv = _bond_voigt(pstress, p, q)
                if aligned[0, 0] >= 0:
                    index[m] = hoffman_bond_aligned(sv, scale[m], aligned[ply_axes[m]], hk)
                else:
                    index[m] = hoffman_bond(sv, scale[m], axes[ply_axes[m]], hk)
                if index[m] >= 1.0:
                    if dn <= 0:
                        crushed[m] = True
                    elif _crosses(sv, n0, n1, n2):
                        col = 0  # the crack runs normal to the largest normal stress
                        for k in range(1, Gf.shape[1]):
                            if abs(sv[k]) > abs(sv[col]):
                                col = k
                        f_ = 2 * Gf[m, col] / (Kb[m] * dn)
                        if f_ <= dn:
                            snapbacks += 1
                        m0[m] = dn
                        mf[m] = max(f_, dn * (1 + 1e-12))
            tn, d = ply_bond(dn, m0[m], mf[m], d_old, Kb[m])
            t0, t1, t2 = tn * n0, tn * n1, tn * n2
        elif law == ELASTIC:  # ply_bond before any initiation: K dn
            tn, d = Kb[m] * dn, d_old
            t0, t1, t2 = tn * n0, tn * n1, tn * n2
        else:
            t0, t1, t2, d = hashin_bond(g0, g1, g2, n0, n1, n2, d_old,
                                        hp[0], hp[1], hp[2], hp[3], hp[4], hp[5], hp[6] > 0)
        on = o0 * n0 + o1 * n1 + o2 * n2  # the last step's opening
        if friction > 0 and dt > 0 and d >= 1.0 and dn < 0:  # closed crack faces slide with friction
            v0 = ((g0 - dn * n0) - (o0 - on * n0)) / dt
            v1 = ((g1 - dn * n1) - (o1 - on * n1)) / dt
            v2 = ((g2 - dn * n2) - (o2 - on * n2)) / dt
            tn = dn * Kb[m]
            mu_p = friction * max(-tn, 0.0) / np.sqrt(v0 * v0 + v1 * v1 + v2 * v2 + v_reg * v_reg)
            t0, t1, t2 = tn * n0 + mu_p * v0, tn * n1 + mu_p * v1, tn * n2 + mu_p * v2
        if visc[m] > 0.0 and dt > 0 and 0.0 < d < 1.0 and (dn < 0 or on < 0):  # softened, at contact
            q = visc[m] / dt * (dn - on)  # the damper on the opening's rate
            t0, t1, t2 = t0 + q * n0, t1 + q * n1, t2 + q * n2
            vwork += area[m] * q * (dn - on)
        if d >= 1.0 and not d_old >= 1.0:
            t_failed[m] = time
        work += area[m] * ((r0 + t0) * (g0 - o0) + (r1 + t1) * (g1 - o1) + (r2 + t2) * (g2 - o2))
        if d >= 1.0:  # failed: its tangential traction is friction (before it failed, none)
            tt = t0 * n0 + t1 * n1 + t2 * n2
            f0, f1, f2 = t0 - tt * n0, t1 - tt * n1, t2 - tt * n2
            if d_old >= 1.0:
                rr = r0 * n0 + r1 * n1 + r2 * n2
                f0, f1, f2 = f0 + r0 - rr * n0, f1 + r1 - rr * n1, f2 + r2 - rr * n2
            fwork += area[m] * (f0 * (g0 - o0) + f1 * (g1 - o1) + f2 * (g2 - o2))
        delta[m, 0], delta[m, 1], delta[m, 2] = g0, g1, g2
        traction[m, 0], traction[m, 1], traction[m, 2] = t0, t1, t2
        damage[m] = d
        # -- forces: on the second end -A t (turned back to x, y, z in a corotated frame)
        if kin == CENTRAL:
            tp = t0 * n0 + t1 * n1 + t2 * n2
            F0, F1, F2 = -area[m] * (tp * axis[m, 0]), -area[m] * (tp * axis[m, 1]), -area[m] * (tp * axis[m, 2])
        elif kin == FRAME_2D:
            c, sn = rot[m, 0], rot[m, 1]
            F0, F1, F2 = -area[m] * (c * t0 - sn * t1), -area[m] * (sn * t0 + c * t1), -area[m] * t2
        else:
            F0, F1, F2 = -area[m] * t0, -area[m] * t1, -area[m] * t2
        slots[m, 0, 0], slots[m, 0, 1], slots[m, 0, 2] = F0, F1, F2  # = force[m] (a view)
        if kin == FRAME_2D:  # the frame's spin: A dPsi/dtheta dtheta/ds on the neighbour pairs
            M = area[m] * (t0 * local[m, 1] - t1 * local[m, 0])
            qs = 0.5 * M / (chord[m, 0] ** 2 + chord[m, 1] ** 2)
            gx, gy = -qs * chord[m, 1], qs * chord[m, 0]
            slots[m, 1, 0], slots[m, 1, 1], slots[m, 1, 2] = -gx, -gy, 0.0
            slots[m, 2, 0], slots[m, 2, 1], slots[m, 2, 2] = gx, gy, 0.0
        elif kin == FIXED:  # the slope terms' work-conjugate normal forces on the neighbour pairs
            for t in range(ndir):
                q = 0.5 * area[m] * dir_h[t, m] * (t0 * dir_e[t, m, 0] + t1 * dir_e[t, m, 1] + t2 * dir_e[t, m, 2])
                b, a = dir_b[t, m], dir_a[t, m]
                for k in range(3):
                    slots[m, 1 + 2 * t, k] = -q * normal[b, k]
                    slots[m, 2 + 2 * t, k] = q * normal[a, k]
    return 0.5 * work, 0.5 * fwork, vwork, snapbacks


@kernel
def _bond_voigt(pstress, p, q):
    """(6,) Voigt Pa (a tuple): the mean of the particle stresses of p and q."""
    return (0.5 * (pstress[p, 0] + pstress[q, 0]), 0.5 * (pstress[p, 1] + pstress[q, 1]),
            0.5 * (pstress[p, 2] + pstress[q, 2]), 0.5 * (pstress[p, 3] + pstress[q, 3]),
            0.5 * (pstress[p, 4] + pstress[q, 4]), 0.5 * (pstress[p, 5] + pstress[q, 5]))


@kernel
def _crosses(sv, n0, n1, n2):
    """Does the bond axis (n0, n1, n2) lie within 45 degrees of the direction of the largest
    principal stress of sv (6,) Voigt (i.e. cross the crack plane)?"""
    S = np.empty((3, 3))  # only at initiation (rare): LAPACK's eigenvector, as the reference
    for k in range(6):
        a, c = _VOIGT[k]
        S[a, c] = S[c, a] = sv[k]
    e = np.linalg.eigh(S)[1][:, 2]
    return (e[0] * n0 + e[1] * n1 + e[2] * n2) ** 2 >= 0.5 - 1e-9


_VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


def _gather_pass(slots, ptr, entry, rows, f):
    """f[rows[p]] += sum of the slots aimed at particle p: slots (nb * S, 3) N flat, entries
    entry[ptr[p]:ptr[p + 1]] (2 x flat slot index, + 1 where the slot acts with minus sign), in
    the reference's order; rows (np,)."""
    for p in prange(rows.shape[0]):
        a0 = a1 = a2 = 0.0
        for e in range(ptr[p], ptr[p + 1]):
            s = entry[e] >> 1
            if entry[e] & 1:
                a0 -= slots[s, 0]
                a1 -= slots[s, 1]
                a2 -= slots[s, 2]
            else:
                a0 += slots[s, 0]
                a1 += slots[s, 1]
                a2 += slots[s, 2]
        r = rows[p]
        f[r, 0] += a0
        f[r, 1] += a1
        f[r, 2] += a2


# each pass twice: on all cores, and serial for the small families
bonds_pass, bonds_pass_serial = kernel(parallel=True)(_bonds_pass), kernel(_bonds_pass)
gather_pass, gather_pass_serial = kernel(parallel=True)(_gather_pass), kernel(_gather_pass)


# -- a small family's step as one call ------------------------------------------------------------
# A family's two passes take 52 arguments, and numba's dispatcher checks and unboxes each at every
# call: 3.5 us a call (this VM), as long as the serial passes themselves on the seed beam's 20- and
# 54-bond families. Held in one structref (FamilyPlan), the arrays cross into compiled code as one
# pointer: 0.5 us. Only the serial build: a cached function that calls a parallel one crashes when
# numba loads it from its cache (numba 0.60, measured), and a family big enough for the parallel
# build does not notice 3 us.
PLAN_FIELDS = ("loc", "d0", "normal", "area", "Kb", "kin", "X_mid", "dir_a", "dir_b", "dir_e", "dir_h", "un",
               "s0", "L0", "axis", "local", "rot", "chord", "law", "hp", "pstress", "inc_ptr", "inc_bond", "cell",
               "axes", "aligned", "ply_axes", "scale", "hk", "Gf", "m0", "mf", "index", "crushed", "friction",
               "v_reg", "visc", "damage", "delta", "traction", "t_failed", "slots", "active", "slots_flat", "ptr",
               "entry")


@structref.register
class FamilyPlanType(types.StructRef):
    def preprocess_fields(self, fields):
        return tuple((name, types.unliteral(t)) for name, t in fields)


class FamilyPlan(structref.StructRefProxy):
    """The arrays and codes of one family's two passes (PLAN_FIELDS: bonds_pass's arguments
    but the positions, the ends, dt and the time; gather_pass's but the rows and the forces),
    bound once. It holds the arrays, not copies: whoever replaces one of them (a restore, the
    numpy reference) must build a new plan (LawBonds._compiled)."""


structref.define_proxy(FamilyPlan, FamilyPlanType, PLAN_FIELDS)


@kernel
def _new_family_plan(fields):
    return FamilyPlan(*fields)


def family_plan(**fields) -> FamilyPlan:
    """A FamilyPlan of the PLAN_FIELDS given by name (compiled and cached: one type for every
    family, its index arrays INDEX, its floats float64)."""
    return _new_family_plan(tuple(fields[k] for k in PLAN_FIELDS))


@kernel
def family_step(p, x, end, rows, f, dt, time):
    """bonds_pass_serial then gather_pass_serial on the plan p (FamilyPlan): positions x (N, 3)
    m, bond ends end (nb, 2) and the family's particles rows (np,) as rows of x and f (N, 3) N,
    into which the forces are added; returns what bonds_pass returns."""
    r = bonds_pass_serial(x, end, p.loc, p.d0, p.normal, p.area, p.Kb, p.kin, p.X_mid, p.dir_a, p.dir_b, p.dir_e,
                          p.dir_h, p.un, p.s0, p.L0, p.axis, p.local, p.rot, p.chord, p.law, p.hp, p.pstress,
                          p.inc_ptr, p.inc_bond, p.cell, p.axes, p.aligned, p.ply_axes, p.scale, p.hk, p.Gf, p.m0,
                          p.mf, p.index, p.crushed, p.friction, p.v_reg, p.visc, dt, time, p.damage, p.delta,
                          p.traction, p.t_failed, p.slots, p.active)
    gather_pass_serial(p.slots_flat, p.ptr, p.entry, rows, f)
    return r


@kernel
def stored_energy(area, delta, normal, damage, K, slip):
    """J, the elastic energy of bonds at separations delta (nb, 3) m: area (nb,) m^2 times
    K / 2 ((1 - d) (<dn>^2 + |ds|^2) + <-dn>^2) per area, the slip's term only with ``slip``
    (the cohesive law's; a ply bond stores none in shear): the laws' stored_density summed."""
    e = 0.0
    for b in range(area.shape[0]):
        n0, n1, n2 = normal[b, 0], normal[b, 1], normal[b, 2]
        dn = delta[b, 0] * n0 + delta[b, 1] * n1 + delta[b, 2] * n2
        opening = max(dn, 0.0) ** 2
        if slip:
            s0, s1, s2 = delta[b, 0] - dn * n0, delta[b, 1] - dn * n1, delta[b, 2] - dn * n2
            opening += s0 * s0 + s1 * s1 + s2 * s2
        e += area[b] * (0.5 * K[b] * ((1.0 - damage[b]) * opening + min(dn, 0.0) ** 2))
    return e
