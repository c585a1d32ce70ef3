"""Per-step loops compiled with numba (the Total Lagrangian internal force, the kinetic energy).

numpy einsum on (nel, nqp, nloc, dim) arrays spends most of its time in temporaries; this
loop visits each quadrature point once and accumulates nodal forces in place.
"""
from __future__ import annotations

import numpy as np

from physics.compiled import kernel

VOIGT_2D = np.array([[0, 0], [1, 1], [0, 1]])
VOIGT_3D = np.array([[0, 0], [1, 1], [2, 2], [1, 2], [0, 2], [0, 1]])


@kernel
def total_lagrangian_force(u, conn, dN, dx, D, voigt, out):
    """Add the St Venant-Kirchhoff internal force of one quadrature rule to ``out``.

    u: (n, dim) m; conn: (nel, nloc) int; dN: (nel, nqp, nloc, dim) 1/m; dx: (nel, nqp) m^3;
    D: (nel, ns, ns) Pa (already masked to this rule's Voigt components); voigt: (ns, 2) index
    pairs; out: (n, dim) N, accumulated.

    The element families are compiled with their sizes as constants (Hex8, Tet4: unrolled
    loops), the plane ones (Q4, T3) written out in scalars (_tl_force_plane: 3.5 x faster
    than the generic loops on 444 Q4); every form does the same operations in the same order
    (tests/test_fem_elements.py holds them to the generic kernel, bit for bit).
    """
    nloc, dim = dN.shape[2], dN.shape[3]
    if dim == 2 and nloc == 4:
        _tl_force_plane(u, conn, dN, dx, D, out, 4)
    elif dim == 2 and nloc == 3:
        _tl_force_plane(u, conn, dN, dx, D, out, 3)
    elif dim == 3 and nloc == 8:
        _tl_force(u, conn, dN, dx, D, voigt, out, 3, 8, 6)
    elif dim == 3 and nloc == 4:
        _tl_force(u, conn, dN, dx, D, voigt, out, 3, 4, 6)
    else:
        total_lagrangian_force_generic(u, conn, dN, dx, D, voigt, out)


@kernel
def total_lagrangian_force_generic(u, conn, dN, dx, D, voigt, out):
    """total_lagrangian_force with its sizes read at run time: the reference the compiled
    families are held to."""
    _tl_force(u, conn, dN, dx, D, voigt, out, dN.shape[3], dN.shape[2], voigt.shape[0])


@kernel(inline="always")
def _tl_force_plane(u, conn, dN, dx, D, out, nloc):
    """_tl_force for dim = 2 (Voigt xx, yy, xy) with H, E, S, P in scalars (registers, not
    scratch arrays): the same sums in the same order."""
    nel, nqp = dN.shape[0], dN.shape[1]
    for e in range(nel):
        d00, d01, d02 = D[e, 0, 0], D[e, 0, 1], D[e, 0, 2]
        d10, d11, d12 = D[e, 1, 0], D[e, 1, 1], D[e, 1, 2]
        d20, d21, d22 = D[e, 2, 0], D[e, 2, 1], D[e, 2, 2]
        for q in range(nqp):
            h00 = h01 = h10 = h11 = 0.0  # displacement gradient H = du_i / dX_j
            for a in range(nloc):
                n = conn[e, a]
                h00 += u[n, 0] * dN[e, q, a, 0]
                h01 += u[n, 0] * dN[e, q, a, 1]
                h10 += u[n, 1] * dN[e, q, a, 0]
                h11 += u[n, 1] * dN[e, q, a, 1]
            e0 = 0.5 * (h00 + h00 + h00 * h00 + h10 * h10)  # Green-Lagrange, engineering shear
            e1 = 0.5 * (h11 + h11 + h01 * h01 + h11 * h11)
            e2 = h01 + h10 + h00 * h01 + h10 * h11
            s00 = 0.0 + d00 * e0 + d01 * e1 + d02 * e2  # S = D E
            s11 = 0.0 + d10 * e0 + d11 * e1 + d12 * e2
            s01 = 0.0 + d20 * e0 + d21 * e1 + d22 * e2
            p00 = s00 + h00 * s00 + h01 * s01  # P = F S
            p01 = s01 + h00 * s01 + h01 * s11
            p10 = s01 + h10 * s00 + h11 * s01
            p11 = s11 + h10 * s01 + h11 * s11
            w = dx[e, q]
            for a in range(nloc):
                n = conn[e, a]
                out[n, 0] += (0.0 + p00 * dN[e, q, a, 0] + p01 * dN[e, q, a, 1]) * w
                out[n, 1] += (0.0 + p10 * dN[e, q, a, 0] + p11 * dN[e, q, a, 1]) * w


@kernel(inline="always")
def _gradient(u, conn, dN, e, q, H, dim, nloc):
    """At quadrature point q of element e: the displacement gradient H = du_i / dX_j (dim, dim),
    written in place."""
    for i in range(dim):
        for j in range(dim):
            acc = 0.0
            for a in range(nloc):
                acc += u[conn[e, a], i] * dN[e, q, a, j]
            H[i, j] = acc


@kernel(inline="always")
def _det_F(H, dim):
    """det F = det (I + H) of a displacement gradient H (dim, dim)."""
    if dim == 2:
        return (1.0 + H[0, 0]) * (1.0 + H[1, 1]) - H[0, 1] * H[1, 0]
    a00, a11, a22 = 1.0 + H[0, 0], 1.0 + H[1, 1], 1.0 + H[2, 2]
    return (a00 * (a11 * a22 - H[1, 2] * H[2, 1]) - H[0, 1] * (H[1, 0] * a22 - H[1, 2] * H[2, 0])
            + H[0, 2] * (H[1, 0] * H[2, 1] - a11 * H[2, 0]))


@kernel(inline="always")
def _green_lagrange(u, conn, dN, voigt, e, q, H, E, dim, nloc, ns):
    """At quadrature point q of element e: the displacement gradient H = du_i / dX_j (dim, dim)
    and the Green-Lagrange strain E (ns,) in Voigt form, engineering shear, written in place."""
    _gradient(u, conn, dN, e, q, H, dim, nloc)
    for s in range(ns):
        i, j = voigt[s, 0], voigt[s, 1]
        g = H[i, j] + H[j, i]
        for k in range(dim):
            g += H[k, i] * H[k, j]
        E[s] = 0.5 * g if i == j else g


@kernel(inline="always")  # inlined where the sizes are constants, so they fold
def _tl_force(u, conn, dN, dx, D, voigt, out, dim, nloc, ns):
    nel, nqp = dN.shape[0], dN.shape[1]
    H = np.empty((dim, dim))
    E = np.empty(ns)
    S = np.empty((dim, dim))
    P = np.empty((dim, dim))
    for e in range(nel):
        for q in range(nqp):
            _green_lagrange(u, conn, dN, voigt, e, q, H, E, dim, nloc, ns)
            for s in range(ns):
                acc = 0.0
                for t in range(ns):
                    acc += D[e, s, t] * E[t]
                i, j = voigt[s, 0], voigt[s, 1]
                S[i, j] = acc
                S[j, i] = acc
            for i in range(dim):  # first Piola-Kirchhoff P = F S
                for j in range(dim):
                    acc = S[i, j]
                    for k in range(dim):
                        acc += H[i, k] * S[k, j]
                    P[i, j] = acc
            w = dx[e, q]
            for a in range(nloc):
                n = conn[e, a]
                for i in range(dim):
                    acc = 0.0
                    for j in range(dim):
                        acc += P[i, j] * dN[e, q, a, j]
                    out[n, i] += acc * w


@kernel
def total_lagrangian_energy(u, conn, dN, dx, D, voigt, det_min):
    """The St Venant-Kirchhoff strain energy (J) of one quadrature rule, sum of E : S dx / 2,
    and each element's smallest det F over the rule's points, min-reduced into ``det_min``
    (nel,) (the inverted-element guard). Arguments as total_lagrangian_force; one pass, no
    temporaries (the einsum form cost 2-3 ms per ledger snapshot on 542 Q4)."""
    nel, nqp, nloc, dim = dN.shape
    ns = voigt.shape[0]
    H = np.empty((dim, dim))
    E = np.empty(ns)
    energy = 0.0
    for e in range(nel):
        for q in range(nqp):
            _green_lagrange(u, conn, dN, voigt, e, q, H, E, dim, nloc, ns)
            w = 0.0
            for s in range(ns):
                acc = 0.0
                for t in range(ns):
                    acc += D[e, s, t] * E[t]
                w += E[s] * acc
            energy += 0.5 * w * dx[e, q]
            det = _det_F(H, dim)
            if det < det_min[e]:
                det_min[e] = det
    return energy


@kernel
def smallest_det_F(u, conn, dN, det_min):
    """Each element's smallest det F over one quadrature rule's points, min-reduced into
    ``det_min`` (nel,): the inverted-element guard alone (run at every sample; 1.46 ms against
    the energy pass's 6.65 ms on 4,624 Hex8 of four rules, benchmarks/fem_sample.py). u (n_nodes, dim) m; conn
    (nel, nloc); dN (nel, nqp, nloc, dim) 1/m. Compiled with the element families' sizes as
    constants, as total_lagrangian_force."""
    nloc, dim = dN.shape[2], dN.shape[3]
    if dim == 3 and nloc == 8:
        _smallest_det_F(u, conn, dN, det_min, 3, 8)
    elif dim == 3 and nloc == 4:
        _smallest_det_F(u, conn, dN, det_min, 3, 4)
    elif dim == 2 and nloc == 4:
        _smallest_det_F(u, conn, dN, det_min, 2, 4)
    elif dim == 2 and nloc == 3:
        _smallest_det_F(u, conn, dN, det_min, 2, 3)
    else:
        _smallest_det_F(u, conn, dN, det_min, dim, nloc)


@kernel(inline="always")
def _smallest_det_F(u, conn, dN, det_min, dim, nloc):
    nel, nqp = dN.shape[0], dN.shape[1]
    H = np.empty((dim, dim))
    ue = np.empty((nloc, dim))
    for e in range(nel):
        for a in range(nloc):  # gathered once for the element's points
            for i in range(dim):
                ue[a, i] = u[conn[e, a], i]
        for q in range(nqp):
            for i in range(dim):
                for j in range(dim):
                    acc = 0.0
                    for a in range(nloc):
                        acc += ue[a, i] * dN[e, q, a, j]
                    H[i, j] = acc
            det = _det_F(H, dim)
            if det < det_min[e]:
                det_min[e] = det


@kernel
def add_columns(out, a, b):
    """out[:, :c] = a + b, c = a.shape[1] <= out.shape[1]: (n, dim) values into the first
    columns of (n, 3) arrays (2D FEM nodes as particles), where numpy's strided form takes a
    temporary of the whole array each call."""
    for i in range(a.shape[0]):
        for k in range(a.shape[1]):
            out[i, k] = a[i, k] + b[i, k]


@kernel
def nodes_as_particles(x, f, X, u):
    """x[:, :dim] = X + u and f = 0 (x, f (n, 3); X, u (n, dim)): the FEM's nodes as law bonds
    see particles, positions refreshed and forces cleared for an evaluation."""
    add_columns(x, X, u)
    for i in range(f.shape[0]):
        for k in range(3):
            f[i, k] = 0.0


@kernel
def add_first_columns(out, a):
    """out += a[:, :c], c = out.shape[1] (forces of (n, 3) rows onto (n, dim) nodes), in place."""
    for i in range(out.shape[0]):
        for k in range(out.shape[1]):
            out[i, k] += a[i, k]


@kernel
def axpy(y, a, x):
    """y += a x in place (y, x (n, dim); a a scalar): numpy's ``y += a * x`` without its
    temporary, the same product and sum."""
    for i in range(y.shape[0]):
        for k in range(y.shape[1]):
            y[i, k] += a * x[i, k]


@kernel
def scale_rows(v, m, c, out):
    """out = c m[:, None] v (v, out (n, dim); m (n,); c a scalar): numpy's ``c * m[:, None] * v``
    without its temporaries, the same products in the same order."""
    for i in range(v.shape[0]):
        cm = c * m[i]
        for k in range(v.shape[1]):
            out[i, k] = cm * v[i, k]


@kernel
def divide_rows(f, m, out):
    """out = f / m[:, None]: f, out (n, dim); m (n,). numpy's broadcast form buffers."""
    for i in range(f.shape[0]):
        for k in range(f.shape[1]):
            out[i, k] = f[i, k] / m[i]


@kernel
def support_reaction(f, du, a, dofs, m, a_pres, reaction_prev, reaction):
    """The prescribed DOFs ``dofs`` (flat, into (n_nodes, dim)) in one pass: reaction <- m a_pres -
    f on them (N, what the support applies beyond the residual force f), a <- a_pres there;
    returns the support's work over the motion du (n_nodes, dim) m since the last evaluation,
    trapezoidal with reaction_prev (J). m, a_pres, reaction_prev, reaction: (len(dofs),)."""
    dim = f.shape[1]
    work = 0.0
    for k in range(dofs.shape[0]):
        i, c = dofs[k] // dim, dofs[k] % dim
        r = m[k] * a_pres[k] - f[i, c]
        reaction[k] = r
        work += (reaction_prev[k] + r) * du[i, c]
        a[i, c] = a_pres[k]
    return 0.5 * work


@kernel
def residual_start(u, u_at, f_int, du, f):
    """du = u - u_at (the motion since the last force evaluation) and f = -f_int (no loads):
    np.subtract and np.negative in one pass (n_nodes, dim)."""
    for i in range(u.shape[0]):
        for k in range(u.shape[1]):
            du[i, k] = u[i, k] - u_at[i, k]
            f[i, k] = -f_int[i, k]


@kernel
def residual_finish(f, node_f, m, a, u, u_at, dofs, m_pres, a_pres, reaction_prev, reaction, du):
    """The end of a force evaluation in one pass: f += node_f[:, :dim] (the last node-force
    model's forces, (n, 3) N; none: (0, 3)), a = f / m, the prescribed DOFs' reactions and accelerations
    (support_reaction), u_at <- u (the ledger's time level). Returns the supports' work (J)."""
    n, dim = f.shape
    if node_f.shape[0]:
        add_first_columns(f, node_f)
    divide_rows(f, m, a)
    work = support_reaction(f, du, a, dofs, m_pres, a_pres, reaction_prev, reaction) if dofs.shape[0] else 0.0
    for i in range(n):
        for k in range(dim):
            u_at[i, k] = u[i, k]
    return work


@kernel
def respa_kicks(v, a, f_tie, band, m, dt, dt_fast, slow, kick, f_fast, a_slow):
    """The FEM's kicks of one DEM step of the impulse (r-RESPA) clock, in one pass:
    f_fast = f_tie - band; at a FEM step (``slow``) a_slow = a - (f_fast - f_tie) / m and
    v += dt a_slow; then v += dt_fast f_fast / m (without ``kick`` only f_fast and a_slow).
    v, a, f_tie, band, f_fast, a_slow: (n_nodes, dim) m/s, m/s^2, N, N, N (out), m/s^2 (out,
    at a FEM step); band of size 0: no band (f_fast = f_tie, a_slow = a); m (n_nodes,) kg;
    dt, dt_fast s. Each entry sees the operations of the numpy form in its order, so the
    digits are the same."""
    n, dim = v.shape
    has_band = band.size > 0
    for i in range(n):
        for k in range(dim):
            ft = f_tie[i, k]
            ff = ft - band[i, k] if has_band else ft
            f_fast[i, k] = ff
            if slow:
                s = a[i, k] - (ff - ft) / m[i] if has_band else a[i, k]
                a_slow[i, k] = s
                if kick:
                    v[i, k] += dt * s
            if kick:
                v[i, k] += dt_fast * ff / m[i]


@kernel
def respa_kicks_drift(v, a, f_tie, band, m, dt, dt_fast, slow, f_fast, a_slow, u, rest):
    """respa_kicks (with the kicks), then the FEM's drift over dt_fast where nothing moves on
    its own: the fixed DOFs ``rest`` (flat, into (n_nodes, dim)) at rest, u += dt_fast v. The
    operations of the three calls in their order (the same digits)."""
    respa_kicks(v, a, f_tie, band, m, dt, dt_fast, slow, True, f_fast, a_slow)
    dim = v.shape[1]
    for e in range(rest.shape[0]):
        v[rest[e] // dim, rest[e] % dim] = 0.0
    axpy(u, dt_fast, v)


@kernel
def kinetic_energy(m, v):
    """J: sum_n m_n |v_n|^2 / 2 over nodes n; m (n,) kg, v (n, dim) m/s."""
    e = 0.0
    for i in range(v.shape[0]):
        w = 0.0
        for k in range(v.shape[1]):
            w += v[i, k] * v[i, k]
        e += m[i] * w
    return 0.5 * e


@kernel
def face_points(x, nodes, w, start):
    """Node-to-face points into rows start + q of x (n + k, 3) m: x[start + q] = sum_a
    w[q, a] x[nodes[q, a]] (nodes, w (k, f): each point's face nodes and shape functions)."""
    for q in range(nodes.shape[0]):
        for c in range(3):
            s = 0.0
            for a in range(nodes.shape[1]):
                s += w[q, a] * x[nodes[q, a], c]
            x[start + q, c] = s


@kernel
def face_forces(f, nodes, w, start):
    """The forces on the node-to-face points (rows start + q of f (n + k, 3) N) passed to their
    face nodes by the same weights: f[nodes[q, a]] += w[q, a] f[start + q]."""
    for q in range(nodes.shape[0]):
        for a in range(nodes.shape[1]):
            for c in range(3):
                f[nodes[q, a], c] += w[q, a] * f[start + q, c]


@kernel
def add_hourglass_force(gamma, coef, conn, u, scale, out):
    """out += scale f_hg: the Flanagan-Belytschko control force f_e = coef_e gamma_e^T
    (gamma_e u_e) of every element, scattered to its nodes in place (numpy's einsum and
    scatter make three temporaries of the elements' size). gamma (nel, n_modes, nloc) -;
    coef (nel,) N/m (stiffness form, u displacements m) or kg/s (viscous form, u velocities
    m/s); conn (nel, nloc) nodes; u, out (n_nodes, dim)."""
    nel, nm, nloc = gamma.shape
    dim = u.shape[1]
    for e in range(nel):
        c = scale * coef[e]
        if c == 0.0:
            continue
        for i in range(dim):
            for m in range(nm):
                q = 0.0  # the mode's generalised displacement along axis i
                for a in range(nloc):
                    q += gamma[e, m, a] * u[conn[e, a], i]
                cq = c * q
                for a in range(nloc):
                    out[conn[e, a], i] += cq * gamma[e, m, a]


@kernel
def add_bulk_viscosity_force(b, vol, length, c, rho, conn, C0, C1, v, out):
    """out -= q b vol: each compressed element's bulk-viscosity pressure q = rho l (C0 l d^2 -
    C1 c d) (d < 0 its volumetric strain rate, 1/s) on its nodes, in place. b (nel, nloc, dim)
    1/m centroid gradients; vol, length, c, rho (nel,) m^3, m, m/s, kg/m^3; conn (nel, nloc);
    v, out (n_nodes, dim) m/s, N."""
    nel, nloc, dim = b.shape
    for e in range(nel):
        d = 0.0
        for a in range(nloc):
            for i in range(dim):
                d += b[e, a, i] * v[conn[e, a], i]
        if d >= 0.0:
            continue
        q = rho[e] * length[e] * (C0 * length[e] * d * d - C1 * c[e] * d)
        w = q * vol[e]
        for a in range(nloc):
            for i in range(dim):
                out[conn[e, a], i] -= w * b[e, a, i]
