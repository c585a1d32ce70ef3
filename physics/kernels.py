"""Per-step loops over bonds compiled with numba (the laws the coupling layer evaluates).

numpy's scatter (np.add.at) and small einsums cost more than the arithmetic at the bond
counts of a damage zone (10^2 .. 10^5 bonds, every engine step); these loops visit each bond
once. Each mirrors a vectorised reference in laws.py / law_bonds.py, and the tests compare them.
"""
from __future__ import annotations

import numpy as np

from .compiled import kernel


@kernel
def scatter_pairs(loc, F, n):
    """(n, 3) N: +F (nb, 3) on each bond's second end, -F on its first (loc (nb, 2) rows)."""
    f = np.zeros((n, 3))
    for b in range(loc.shape[0]):
        for k in range(3):
            f[loc[b, 1], k] += F[b, k]
            f[loc[b, 0], k] -= F[b, k]
    return f


@kernel
def add_rows(target, ids, F):
    """target[ids] += F for (k, 3) rows F, repeated ids summed (np.add.at, without its overhead)."""
    for r in range(ids.shape[0]):
        for k in range(3):
            target[ids[r], k] += F[r, k]


@kernel
def add_at(target, ids, values):
    """target[ids] += values for flat (k,) values, repeated ids summed in order (np.add.at,
    without its overhead and its temporaries)."""
    for r in range(ids.shape[0]):
        target[ids[r]] += values[r]


@kernel
def add_slope_forces(f, loc, normal, q, a, b):
    """The work-conjugate forces of an interface slip's slope term, into f (n, 3) N: each
    bond's q (nb,) N acts along the normal of its neighbour pairs, -q on both particles of
    the next pair b and +q on both of the previous pair a (a, b (nb,) bond rows)."""
    for m in range(loc.shape[0]):
        for c, s in ((b[m], -q[m]), (a[m], q[m])):
            for k in range(3):
                g = s * normal[c, k]
                f[loc[c, 0], k] += g
                f[loc[c, 1], k] += g


@kernel
def bond_stress(loc, force, d0, cell, n):
    """(nb, 6) Voigt Pa: mean of the end particles' Love-Weber stresses
    sigma_p = sum_b (f_b (x) l_b) / (2 V_p), f_b = A_b t_b (tension positive), symmetrised."""
    s = np.zeros((n, 3, 3))
    for b in range(loc.shape[0]):
        for i in range(3):
            for j in range(3):
                v = 0.5 * force[b, i] * d0[b, j]
                s[loc[b, 0], i, j] += v
                s[loc[b, 1], i, j] += v
    out = np.empty((loc.shape[0], 6))
    pairs = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))
    for b in range(loc.shape[0]):
        p, q = loc[b, 0], loc[b, 1]
        for k in range(6):
            i, j = pairs[k]
            a = 0.5 * (s[p, i, j] + s[p, j, i]) / cell[p]
            c = 0.5 * (s[q, i, j] + s[q, j, i]) / cell[q]
            out[b, k] = 0.5 * (a + c)
    return out


@kernel
def hoffman_coefficients(k):
    """The Hoffman index's nine coefficients from the strengths k = (Xt, Xc, Yt, Yc, Zt, Zc,
    S23, S13, S12) Pa: three quadratic, three linear, and the shear terms' 1 / S^2 (a product
    per shear term where a division was, in the initiation check of every intact ply bond at
    every step: the 925 ply bonds of the seed beam's 2-ply zone in a loop of their own, 67-73
    -> 50-52 us a step; in whole runs, where the pass waits on memory, no measurable change:
    docs/benchmarks.md session 45)."""
    Xt, Xc, Yt, Yc, Zt, Zc, S23, S13, S12 = k
    X, Y, Z = 1 / (Xt * Xc), 1 / (Yt * Yc), 1 / (Zt * Zc)
    return (0.5 * (Y + Z - X), 0.5 * (Z + X - Y), 0.5 * (X + Y - Z),
            1 / Xt - 1 / Xc, 1 / Yt - 1 / Yc, 1 / Zt - 1 / Zc, 1 / (S23 * S23), 1 / (S13 * S13), 1 / (S12 * S12))


@kernel
def hoffman_bond(stress, scale, R, c):
    """Hoffman index of one global Voigt stress (6,) Pa / scale, in the ply axes R (3, 3)
    (columns); c = hoffman_coefficients(strengths)."""
    q23, q31, q12, l1, l2, l3, i23, i13, i12 = c
    xx, yy, zz, yz, xz, xy = (stress[0] / scale, stress[1] / scale, stress[2] / scale,
                              stress[3] / scale, stress[4] / scale, stress[5] / scale)
    s1, s2, s3 = _turned(R, xx, yy, zz, yz, xz, xy, 0, 0), _turned(R, xx, yy, zz, yz, xz, xy, 1, 1), \
        _turned(R, xx, yy, zz, yz, xz, xy, 2, 2)
    t23, t13, t12 = _turned(R, xx, yy, zz, yz, xz, xy, 1, 2), _turned(R, xx, yy, zz, yz, xz, xy, 0, 2), \
        _turned(R, xx, yy, zz, yz, xz, xy, 0, 1)
    return (q23 * (s2 - s3) ** 2 + q31 * (s3 - s1) ** 2 + q12 * (s1 - s2) ** 2
            + l1 * s1 + l2 * s2 + l3 * s3 + t23 * t23 * i23 + t13 * t13 * i13 + t12 * t12 * i12)


@kernel
def hoffman_bond_aligned(stress, scale, sel, c):
    """The same index where the ply axes are a signed permutation of x, y, z (0 and 90 plies):
    the ply-axes components are global ones, sel (6,) their Voigt positions (bit-identical to
    the turned form: every other product is an exact zero)."""
    q23, q31, q12, l1, l2, l3, i23, i13, i12 = c
    s1, s2, s3, t23, t13, t12 = (stress[sel[0]], stress[sel[1]], stress[sel[2]], stress[sel[3]], stress[sel[4]],
                                 stress[sel[5]])
    if scale != 1.0:
        s1, s2, s3, t23, t13, t12 = s1 / scale, s2 / scale, s3 / scale, t23 / scale, t13 / scale, t12 / scale
    return (q23 * (s2 - s3) ** 2 + q31 * (s3 - s1) ** 2 + q12 * (s1 - s2) ** 2
            + l1 * s1 + l2 * s2 + l3 * s3 + t23 * t23 * i23 + t13 * t13 * i13 + t12 * t12 * i12)


def aligned_voigt(R: np.ndarray) -> np.ndarray | None:
    """(6,) Voigt positions of the ply-axes stresses (11, 22, 33, 23, 13, 12) when the axes R
    (3, 3) (columns) are a signed permutation of x, y, z to 1e-12 (a 90 degree turn by cos / sin
    leaves 6e-17: its products are below half an ulp of the terms they join); None otherwise."""
    snapped = np.round(R)
    if not (np.all(np.abs(R - snapped) < 1e-12) and np.all(np.abs(snapped).sum(axis=0) == 1)):
        return None
    R = snapped
    g = np.abs(R).argmax(axis=0)  # ply axis a is global axis g[a]
    voigt = {(0, 0): 0, (1, 1): 1, (2, 2): 2, (1, 2): 3, (0, 2): 4, (0, 1): 5}
    key = lambda i, j: voigt[(min(i, j), max(i, j))]
    return np.array([key(g[0], g[0]), key(g[1], g[1]), key(g[2], g[2]), key(g[1], g[2]), key(g[0], g[2]),
                     key(g[0], g[1])], np.int64)


@kernel
def _turned(R, xx, yy, zz, yz, xz, xy, a, c):
    """(R^T S R)[a, c] of the symmetric S given by its six components, axes R (3, 3) (columns),
    summed over i, j in order (the association of the numpy form: its digits, not only its value)."""
    ra0, ra1, ra2, rc0, rc1, rc2 = R[0, a], R[1, a], R[2, a], R[0, c], R[1, c], R[2, c]
    acc = ra0 * xx * rc0
    acc += ra0 * xy * rc1
    acc += ra0 * xz * rc2
    acc += ra1 * xy * rc0
    acc += ra1 * yy * rc1
    acc += ra1 * yz * rc2
    acc += ra2 * xz * rc0
    acc += ra2 * yz * rc1
    acc += ra2 * zz * rc2
    return acc


@kernel
def hoffman_ply(stress, axes, scale, k):
    """(nb,) Hoffman index of global Voigt stresses (nb, 6) / scale (nb,) in the bonds' ply axes
    (nb, 3, 3) (columns); k = (Xt, Xc, Yt, Yc, Zt, Zc, S23, S13, S12)."""
    out = np.empty(stress.shape[0])
    c = hoffman_coefficients(k)
    for b in range(stress.shape[0]):
        out[b] = hoffman_bond(stress[b], scale[b], axes[b], c)
    return out


@kernel
def corotate_2d(x, loc, a, b, s0, d0, local, rot, chord):
    """Each bond's branch vector in the frame turned by the angle theta of the chord s from
    bond a's midpoint to bond b's (reference chord s0), into local (nb, 3) m; rot (nb, 2) the
    cos, sin of theta; chord (nb, 3) s. Returns delta = local - d0 (nb, 3) m."""
    nb = loc.shape[0]
    delta = np.empty((nb, 3))
    for m in range(nb):
        for k in range(2):
            chord[m, k] = 0.5 * (x[loc[b[m], 0], k] + x[loc[b[m], 1], k] - x[loc[a[m], 0], k] - x[loc[a[m], 1], k])
        chord[m, 2] = 0.0
        th = np.arctan2(s0[m, 0] * chord[m, 1] - s0[m, 1] * chord[m, 0], s0[m, 0] * chord[m, 0] + s0[m, 1] * chord[m, 1])
        c, s = np.cos(th), np.sin(th)
        dx = x[loc[m, 1], 0] - x[loc[m, 0], 0]
        dy = x[loc[m, 1], 1] - x[loc[m, 0], 1]
        local[m, 0] = c * dx + s * dy
        local[m, 1] = -s * dx + c * dy
        local[m, 2] = x[loc[m, 1], 2] - x[loc[m, 0], 2]
        rot[m, 0], rot[m, 1] = c, s
        for k in range(3):
            delta[m, k] = local[m, k] - d0[m, k]
    return delta


@kernel
def add_spin_forces(f, loc, a, b, t, local, chord, area):
    """The corotated frame's share of the forces into f (n, 3) N: A dPsi/dtheta dtheta/ds, half
    on each particle of the next pair b (minus) and of the previous pair a (plus)."""
    for m in range(loc.shape[0]):
        M = area[m] * (t[m, 0] * local[m, 1] - t[m, 1] * local[m, 0])
        q = 0.5 * M / (chord[m, 0] ** 2 + chord[m, 1] ** 2)
        gx, gy = -q * chord[m, 1], q * chord[m, 0]
        for k in range(2):
            f[loc[b[m], k], 0] -= gx
            f[loc[b[m], k], 1] -= gy
            f[loc[a[m], k], 0] += gx
            f[loc[a[m], k], 1] += gy


@kernel
def _einsum_dot(a, a0, b):
    """sum_i (a_i - a0_i) b_i in the order numpy's einsum adds three terms, (0 + 2) + 1 (its
    digits, not only its value)."""
    if a.shape[0] == 3:
        return ((a[0] - a0[0]) * b[0] + (a[2] - a0[2]) * b[2]) + (a[1] - a0[1]) * b[1]
    acc = 0.0
    for i in range(a.shape[0]):
        acc += (a[i] - a0[i]) * b[i]
    return acc


@kernel
def _friction(f, p, v, velocity, n, vt, still, fn, friction, slip2):
    """f[p] -= mu fn v_t / sqrt(|v_t|^2 + slip2): Coulomb friction of point p against its slip
    v_t, its velocity v[p] less the impactor's, without the part along the normal n (dim,);
    vt, still (dim,) scratch and zeros (the contacts' common tail, in the numpy form's order)."""
    vn = _einsum_dot(v[p], velocity, n)
    for i in range(n.shape[0]):
        vt[i] = (v[p, i] - velocity[i]) - vn * n[i]
    c = friction * fn / np.sqrt(_einsum_dot(vt, still, vt) + slip2)
    for i in range(n.shape[0]):
        f[p, i] -= c * vt[i]


@kernel
def ball_contact(x, v, centre, axis, velocity, radius, penalty, friction, slip2, f):
    """Penalty contact of a rigid ball (a disc in 2D) with points x (m, dim) m moving at v
    (m, dim) m/s: normal force penalty x penetration along the outward normal, Coulomb friction
    against the tangential slip regularised by slip2 (m/s)^2 (RigidImpactor.forces for the
    ball, each point once: the numpy form's digits). axis (dim,): a cylinder's unit axis (its
    cross-section is the ball: the distance is taken normal to it), zeros for a ball. f (m, dim)
    N out; returns the sum of the squared penetrations m^2."""
    m, dim = x.shape
    pen2 = 0.0
    d, vt, still = np.empty(dim), np.empty(dim), np.zeros(dim)  # normal, tangential slip rate
    for p in range(m):
        s = 0.0
        for i in range(dim):
            d[i] = x[p, i] - centre[i]
            s += d[i] * axis[i]
        r2 = 0.0
        for i in range(dim):
            d[i] -= s * axis[i]  # (a ball: s = 0, d as it was)
            r2 += d[i] * d[i]
        r = np.sqrt(r2)
        rr = max(r, 1e-300)
        pen = max(radius - r, 0.0)
        fn = penalty * pen
        for i in range(dim):
            d[i] = d[i] / rr  # the normal
            f[p, i] = fn * d[i]
        if friction > 0:
            _friction(f, p, v, velocity, d, vt, still, fn, friction, slip2)
        pen2 += pen * pen
    return pen2


@kernel
def flat_contact(x, v, centre, axis, velocity, radius, depth, k, penalty, friction, slip2, f):
    """Penalty contact of a rigid flat face (a punch's or a rod's, its normal into the target
    -axis) with points x (m, dim) m moving at v (m, dim) m/s: a point up to ``depth`` behind the
    face and within its half-width ``radius`` (or, with a footprint k (m,) N/m, where k > 0) is
    pushed out along -axis by penalty (or its k) x its depth, with Coulomb friction as
    ball_contact (RigidImpactor.forces for the sharp face, each point once). f (m, dim) N out;
    returns sum pen^2 m^2 (one penalty) or sum k pen^2 N m (a footprint)."""
    m, dim = x.shape
    pen2 = 0.0
    d, vt, still = np.empty(dim), np.empty(dim), np.zeros(dim)
    footprint = k.shape[0] > 0
    for i in range(dim):
        d[i] = -axis[i]  # the normal, at every point
    for p in range(m):
        s = 0.0
        for i in range(dim):
            s += (x[p, i] - centre[i]) * axis[i]
        lat2 = 0.0
        for i in range(dim):
            w = (x[p, i] - centre[i]) - s * axis[i]
            lat2 += w * w
        inside = s > 0 and s < depth and (k[p] > 0 if footprint else np.sqrt(lat2) <= radius)
        pen = s if inside else 0.0
        kp = k[p] if footprint else penalty
        fn = kp * pen
        for i in range(dim):
            f[p, i] = fn * d[i]
        if friction > 0:
            _friction(f, p, v, velocity, d, vt, still, fn, friction, slip2)
        pen2 += fn * pen if footprint else pen * pen
    return pen2


@kernel
def impactor_on_nodes(X, u, v, du, S, xs, vs, centre, axis, velocity, radius, flat, depth, k, penalty, friction, slip2,
                      fc, fc_prev, f, F):
    """A rigid impactor on FEM surface nodes S (m,) in one pass: ball_contact (a ball, or a
    cylinder along ``axis``) or, ``flat``, flat_contact (depth m, footprint k) on the positions
    X + u (n, dim) m and velocities v (n, dim) m/s of the nodes S (gathered into the scratch
    xs, vs (m, dim)); its forces into fc (m, dim) N and added to f[S] (f (n, dim) N); F (dim,)
    N out, the force on the impactor (minus the sum of fc). Returns (the contact's sum of
    squared penetrations, as the contact returns it, sum over the nodes of (fc_prev + fc) . du[S]
    J, du (n, dim) m the nodes' motion)."""
    m, dim = xs.shape
    for r in range(m):
        p = S[r]
        for i in range(dim):
            xs[r, i] = X[p, i] + u[p, i]
            vs[r, i] = v[p, i]
    if flat:
        pen2 = flat_contact(xs, vs, centre, axis, velocity, radius, depth, k, penalty, friction, slip2, fc)
    else:
        pen2 = ball_contact(xs, vs, centre, axis, velocity, radius, penalty, friction, slip2, fc)
    work = 0.0
    for i in range(dim):
        F[i] = 0.0
    for r in range(m):
        p = S[r]
        for i in range(dim):
            f[p, i] += fc[r, i]
            work += (fc_prev[r, i] + fc[r, i]) * du[p, i]
            F[i] -= fc[r, i]
    return pen2, work


@kernel
def particle_gap(d0, d1, d2, axis, radius, flat, depth, rounding):
    """(penetration m, normal (3 floats) at the particle) of a particle centre at d = x - X from
    a rigid impactor (RigidImpactor.gap, one point). A ball of ``radius`` (a cylinder along
    ``axis``; zeros: a ball); ``flat``: a face of half-width ``radius`` whose normal into the
    target is -axis, counting centres up to ``depth`` behind it, grown by a ball of
    ``rounding`` (the particle radius: flat under the face, a torus round its edge)."""
    s = (d0 * axis[0] + d1 * axis[1]) + d2 * axis[2]  # along the axis (a ball: 0)
    l0, l1, l2 = d0 - s * axis[0], d1 - s * axis[1], d2 - s * axis[2]  # across it
    if not flat:
        dist = np.sqrt(0.0 + l0 * l0 + l1 * l1 + l2 * l2)
        rr = max(dist, 1e-300)
        return max(radius - dist, 0.0), l0 / rr, l1 / rr, l2 / rr
    lateral = np.sqrt(l0 * l0 + l1 * l1 + l2 * l2)
    if rounding <= 0:
        inside = s > 0 and s < depth and lateral <= radius
        return (s if inside else 0.0), -axis[0], -axis[1], -axis[2]
    out = lateral - radius  # > 0 beyond the edge
    if out <= 0:  # under the face
        pen = s + rounding
        return (pen if pen > 0 and s < depth else 0.0), -axis[0], -axis[1], -axis[2]
    lr = max(lateral, 1e-300)
    e0, e1, e2 = l0 / lr, l1 / lr, l2 / lr
    if s <= 0:  # round the edge
        dist = np.hypot(out, s)
        m = max(dist, 1e-300)
        n0, n1, n2 = (out * e0 + s * axis[0]) / m, (out * e1 + s * axis[1]) / m, (out * e2 + s * axis[2]) / m
    else:  # beside the side
        dist = out
        m = max(dist, 1e-300)
        n0, n1, n2 = e0 * dist / m, e1 * dist / m, e2 * dist / m
    pen = rounding - dist
    return (pen if pen > 0 and s < depth else 0.0), n0, n1, n2


@kernel
def impactor_on_particles(X, Fout, rows, x, f, x_prev, f_prev, started, dt, centre, axis, velocity, radius,
                          flat, depth, rounding, penalty, friction, slip2, F):
    """One step of a rigid impactor (particle_gap: a ball, a cylinder along ``axis``, a flat face)
    on particles, in place on an engine's arrays: penalty contact with regularised Coulomb
    friction (RigidImpactor.forces) on the candidates' positions X[rows] (X (N, 3) m, rows (k,)),
    velocities from the last step ((x - x_prev) / dt once ``started``), their forces added to
    Fout[rows] (N) where non-zero.
    Out: x, f (k, 3) this step's positions and forces; F (3,) N the force on the impactor (minus
    the sum of f, row by row as numpy's sum over axis 0); f_prev is used as scratch. Returns
    (sum of squared penetrations m^2, sum of (f_prev + f) . (x - x_prev) J in numpy's pairwise
    order)."""
    k = rows.shape[0]
    pen2 = 0.0
    moving = started and dt != 0
    for r in range(k):
        p = rows[r]
        x0, x1, x2 = X[p, 0], X[p, 1], X[p, 2]
        x[r, 0], x[r, 1], x[r, 2] = x0, x1, x2
        pen, d0, d1, d2 = particle_gap(x0 - centre[0], x1 - centre[1], x2 - centre[2], axis, radius, flat, depth,
                                       rounding)
        fn = penalty * pen
        g0, g1, g2 = fn * d0, fn * d1, fn * d2
        if friction > 0:
            if moving:
                v0, v1, v2 = (x0 - x_prev[r, 0]) / dt, (x1 - x_prev[r, 1]) / dt, (x2 - x_prev[r, 2]) / dt
            else:
                v0 = v1 = v2 = 0.0
            vn = ((v0 - velocity[0]) * d0 + (v2 - velocity[2]) * d2) + (v1 - velocity[1]) * d1
            t0, t1, t2 = (v0 - velocity[0]) - vn * d0, (v1 - velocity[1]) - vn * d1, (v2 - velocity[2]) - vn * d2
            c = friction * fn / np.sqrt(((t0 - 0.0) * t0 + (t2 - 0.0) * t2) + (t1 - 0.0) * t1 + slip2)
            g0, g1, g2 = g0 - c * t0, g1 - c * t1, g2 - c * t2
        f[r, 0], f[r, 1], f[r, 2] = g0, g1, g2
        pen2 += pen * pen
    for i in range(3):
        acc = f[0, i] if k else 0.0
        for r in range(1, k):
            acc += f[r, i]
        F[i] = -acc
    for r in range(k):
        if f[r, 0] != 0.0 or f[r, 1] != 0.0 or f[r, 2] != 0.0:
            for i in range(3):
                Fout[rows[r], i] += f[r, i]
    if not started:
        return pen2, 0.0
    w = f_prev.reshape(3 * k)
    for r in range(k):
        for i in range(3):
            w[3 * r + i] = (f_prev[r, i] + f[r, i]) * (x[r, i] - x_prev[r, i])
    return pen2, numpy_sum(w)


@kernel
def ball_leapfrog(X, V, F, X_prev, F_prev, mass, free, dt, started):
    """The rest of a ball's step after its contact forces F (3,) N, in place: the work of its
    own force over its last move, (F_prev + F) . (X - X_prev) / 2 (returned, J; 0 before it
    started), X_prev <- X, F_prev <- F, then the leapfrog V += dt F / M (the components
    ``free`` (3,) 1.0, the held ones 0.0), X += dt V when dt > 0. The operations of the numpy
    form, in its order (the dot product summed from the first component)."""
    w = 0.0
    if started:
        for i in range(3):
            w += (F_prev[i] + F[i]) * (X[i] - X_prev[i])
    for i in range(3):
        X_prev[i] = X[i]
        F_prev[i] = F[i]
    if dt > 0:
        for i in range(3):
            V[i] = V[i] + dt * F[i] / mass * free[i]
            X[i] = X[i] + dt * V[i]
    return w


@kernel
def impactor_step(X, Fout, rows, x, f, x_prev, f_prev, started, dt, centre, axis, velocity, radius, flat, depth,
                  rounding, penalty, friction, slip2, F, X_prev, F_prev, mass, free):
    """One engine step of a rigid impactor on particles: impactor_on_particles, then
    ball_leapfrog of the impactor (centre, velocity: its X, V) under the force F it found.
    Returns (sum of squared penetrations m^2, the particles' contact work J, the impactor's own
    J), as the two return."""
    pen2, dwork = impactor_on_particles(X, Fout, rows, x, f, x_prev, f_prev, started, dt, centre, axis, velocity,
                                        radius, flat, depth, rounding, penalty, friction, slip2, F)
    work = ball_leapfrog(centre, velocity, F, X_prev, F_prev, mass, free, dt if dt > 0 else 0.0, started)
    return pen2, dwork, work


@kernel
def numpy_sum(a):
    """np.sum of a contiguous (n,) array with numpy's digits: its reduction takes runs of 8192
    (the ufunc buffer) in turn, each summed pairwise."""
    acc = 0.0
    for lo in range(0, a.shape[0], 8192):
        acc += pairwise_sum(a, lo, min(8192, a.shape[0] - lo))
    return acc


@kernel
def pairwise_sum(a, lo, n):
    """sum of a[lo:lo + n] in the order numpy's add.reduce takes a contiguous run of up to
    8192: eight partial sums over blocks up to 128, halves (multiples of 8) above."""
    if n < 8:
        acc = -0.0
        for i in range(lo, lo + n):
            acc += a[i]
        return acc
    if n <= 128:
        r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
        r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
        i = 8
        while i < n - n % 8:
            r0, r1, r2, r3 = r0 + a[lo + i], r1 + a[lo + i + 1], r2 + a[lo + i + 2], r3 + a[lo + i + 3]
            r4, r5, r6, r7 = r4 + a[lo + i + 4], r5 + a[lo + i + 5], r6 + a[lo + i + 6], r7 + a[lo + i + 7]
            i += 8
        acc = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while i < n:
            acc += a[lo + i]
            i += 1
        return acc
    half = n // 2
    half -= half % 8
    return pairwise_sum(a, lo, half) + pairwise_sum(a, lo + half, n - half)


@kernel
def element_failure_index(u, edofs, L, c, hoffman_on, Z0, R0, hashin_on, elements, out):
    """out[e] <- for each e in ``elements`` (k,), the larger of the element's Hoffman index
    (where hoffman_on) and Hashin's interlaminar index (where hashin_on), and 0, of its ply
    stress s = L[e] @ u[edofs[e]] (Pa; L (nel, 6, nd) Pa / m, rows 11 22 33 23 13 12 in ply
    axes; u (ndof,) m flat); c = hoffman_coefficients(strengths); out (nel,) elsewhere as it
    was. The growth check's criterion, at up to every FEM step."""
    q23, q31, q12, l1, l2, l3, i23, i13, i12 = c
    for k in range(elements.shape[0]):
        e = elements[k]
        if not (hoffman_on[e] or hashin_on[e]):  # (a window's elements off its band)
            out[e] = 0.0
            continue
        s1 = s2 = s3 = t23 = t13 = t12 = 0.0
        for j in range(L.shape[2]):
            x = u[edofs[e, j]]
            s1 += L[e, 0, j] * x
            s2 += L[e, 1, j] * x
            s3 += L[e, 2, j] * x
            t23 += L[e, 3, j] * x
            t13 += L[e, 4, j] * x
            t12 += L[e, 5, j] * x
        best = 0.0
        if hoffman_on[e]:
            h = (q23 * (s2 - s3) ** 2 + q31 * (s3 - s1) ** 2 + q12 * (s1 - s2) ** 2
                 + l1 * s1 + l2 * s2 + l3 * s3 + t23 * t23 * i23 + t13 * t13 * i13 + t12 * t12 * i12)
            if not h <= best:  # (a nan kept, as numpy's maximum keeps it)
                best = h
        if hashin_on[e] and best == best:
            n = s3 if s3 > 0.0 or s3 != s3 else 0.0  # max(s3, 0), a nan kept
            g = (n / Z0) ** 2 + (t13 ** 2 + t23 ** 2) / R0 ** 2
            if not g <= best:
                best = g
        out[e] = best


@kernel
def damaged_reach(reach, damage):
    """m: the largest reach (nb,) of the bonds whose damage (nb,) is above 0; -1 if none."""
    out = -1.0
    for b in range(damage.shape[0]):
        if damage[b] > 0.0 and reach[b] > out:
            out = reach[b]
    return out


@kernel
def touched_reach(x, centre, axis, radius, ncols):
    """m: the largest |x[i, c]|, c < ncols, over the points x (k, 3) closer than radius to
    ``centre`` (3,), or to the axis (3,) through it when the axis is not zero; -1 if none."""
    aa = axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]
    out = -1.0
    for i in range(x.shape[0]):
        r0, r1, r2 = x[i, 0] - centre[0], x[i, 1] - centre[1], x[i, 2] - centre[2]
        if aa > 0.0:  # the distance from the axis
            s = r0 * axis[0] + r1 * axis[1] + r2 * axis[2]
            r0, r1, r2 = r0 - s * axis[0] / aa, r1 - s * axis[1] / aa, r2 - s * axis[2] / aa
        if np.sqrt(r0 * r0 + r1 * r1 + r2 * r2) < radius:
            for c in range(ncols):
                out = max(out, abs(x[i, c]))
    return out


@kernel
def cohesive_reach(traction, normal, damage, x, Z0, R0, at):
    """m: the largest x (nb,) of the cohesive bonds whose Hashin index on their last traction
    (nb, 3) Pa, across their normal (nb, 3), reached ``at``, or that are damaged but not yet
    failed (the cohesive zone and what is about to join it); -1 if none."""
    out = -1.0
    for b in range(damage.shape[0]):
        if not damage[b] < 1.0:  # (the crack's faces in contact: not a process zone; a nan: neither)
            continue
        tn = traction[b, 0] * normal[b, 0] + traction[b, 1] * normal[b, 1] + traction[b, 2] * normal[b, 2]
        s0, s1, s2 = (traction[b, 0] - tn * normal[b, 0], traction[b, 1] - tn * normal[b, 1],
                      traction[b, 2] - tn * normal[b, 2])
        n = max(tn, 0.0)
        if damage[b] > 0.0 or (n / Z0) ** 2 + (s0 * s0 + s1 * s1 + s2 * s2) / R0 ** 2 >= at:
            out = max(out, x[b])
    return out


@kernel
def flagged_reach(index, order, x0, x1, at, start, margin):
    """m: the reach from x = 0 of a zone ``start`` wide grown over every element whose index
    (nel,) reached ``at`` and that begins (x0 (nel,) m) within ``margin`` of the reach so far, up
    to its end (x1); order: the elements by x0 (placement.grown_reach over the flagged ones)."""
    r = start
    for k in range(order.shape[0]):
        e = order[k]
        if not index[e] >= at:  # (a nan flags nothing, as numpy's >= did)
            continue
        if x0[e] > r + margin:
            break
        r = max(r, x1[e])
    return r
