"""Bond laws that the coupling layer can evaluate on any engine's bonds (vectorised over bonds).

HashinCohesiveLaw: the seed paper's interlaminar bond. Quadratic (Hashin) initiation with
normal strength Z0 and shear strength R0, no damage under compression; linear softening
whose area is the critical energy release rate, mixed mode by Benzeggagh-Kenane or the power
law; irreversible damage; under compression the normal penalty stays (impenetrability).
Written in the mixed-mode bilinear form of Camanho & Davila (NASA/TM-2002-211737) with one
penalty stiffness K for both modes, which is the seed's mu = Z0^2 h / (2 Gc) softening
(the slope in terms of the equivalent strain over an interface layer of thickness h).

Units: separations m, tractions Pa, K Pa/m, strengths Pa, toughness J/m^2. A bond that
stands for an interface area A carries the force A t.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .compiled import kernel

MIXED_MODE = ("bk", "power")


@dataclass(frozen=True)
class HashinCohesiveLaw:
    """K: penalty stiffness (Pa/m); Z0, R0: normal and shear strength (Pa); GIc, GIIc:
    toughness (J/m^2); eta: B-K (or power-law) exponent; mixed_mode: "bk" | "power"."""

    K: float
    Z0: float
    R0: float
    GIc: float
    GIIc: float
    eta: float = 2.284
    mixed_mode: str = "bk"

    def __post_init__(self):
        if self.mixed_mode not in MIXED_MODE:
            raise ValueError(f"mixed_mode {self.mixed_mode!r}: allowed {MIXED_MODE}")
        for name in ("K", "Z0", "R0", "GIc", "GIIc", "eta"):
            if not getattr(self, name) > 0:
                raise ValueError(f"{name} = {getattr(self, name)!r}: must be > 0")
        if self.GIc < self.Z0**2 / (2 * self.K) or self.GIIc < self.R0**2 / (2 * self.K):
            raise ValueError("toughness below the elastic energy at initiation: raise K or Gc "
                             "(needs Gc >= strength^2 / (2 K))")

    def toughness(self, B: np.ndarray) -> np.ndarray:
        """Mixed-mode Gc (J/m^2) at mode ratio B = GII / (GI + GII)."""
        B = np.asarray(B, float)
        if self.mixed_mode == "bk":
            return self.GIc + (self.GIIc - self.GIc) * B**self.eta
        # power law (GI/GIc)^eta + (GII/GIIc)^eta = 1 with GI = (1 - B) G, GII = B G
        return 1.0 / (((1 - B) / self.GIc) ** self.eta + (B / self.GIIc) ** self.eta) ** (1.0 / self.eta)

    def onset_and_final(self, dn: np.ndarray, ds: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(equivalent separation at onset, at full decohesion, mode ratio B) for the
        current mode mix; dn opening (m), ds shear slip magnitude (m)."""
        K = self.K
        n0, s0 = self.Z0 / K, self.R0 / K
        open_ = dn > 0
        beta = np.where(open_, ds / np.where(open_, dn, 1.0), np.inf)
        with np.errstate(invalid="ignore", over="ignore"):
            b2 = np.where(open_, beta**2, 0.0)
            m0 = np.where(open_, n0 * s0 * np.sqrt((1 + b2) / (s0**2 + b2 * n0**2)), s0)
            B = np.where(open_, b2 / (1 + b2), 1.0)
        Gc = np.where(open_, self.toughness(B), self.GIIc)
        mf = 2 * Gc / (K * m0)
        return m0, mf, B

    def tractions(self, dn: np.ndarray, ds: np.ndarray, damage: np.ndarray):
        """Tractions for separations dn (n,) opening m and ds (n, k) slip m, given the
        damage reached so far (n,); returns (t_n (n,), t_s (n, k), new damage (n,)).

        Damage never decreases; compression (dn < 0) keeps the full normal penalty."""
        dn = np.asarray(dn, float)
        ds = np.asarray(ds, float).reshape(len(dn), -1)
        slip = np.linalg.norm(ds, axis=1)
        m = np.sqrt(np.maximum(dn, 0.0) ** 2 + slip**2)
        m0, mf, _ = self.onset_and_final(dn, slip)
        with np.errstate(invalid="ignore", divide="ignore"):
            d_now = np.where(m > m0, mf * (m - m0) / (m * (mf - m0)), 0.0)
        d = np.clip(np.maximum(damage, np.nan_to_num(d_now)), 0.0, 1.0)
        tn = np.where(dn > 0, (1 - d) * self.K * dn, self.K * dn)
        ts = ((1 - d) * self.K)[:, None] * ds
        return tn, ts, d

    def damage_on(self, other: "HashinCohesiveLaw", damage: np.ndarray) -> np.ndarray:
        """(n,) the damage of bonds of law ``other`` (the same strengths and toughness, another
        penalty K') at the point of their softening where bonds of this law are at ``damage``
        (n,): the same fraction s of the way from onset to decohesion, so the same residual
        strength (1 - s) K m0 and inelastic opening s mf (neither depends on K: m0 ~ 1 / K, and
        mf = 2 Gc / (K m0)). From d = mf (m - m0) / (m (mf - m0)), s = d m0 / ((1 - d) mf + d m0),
        which gives d' = d K' / (d K' + (1 - d) K) under any mode mix. A bond's state carries onto
        another stiffness by this, not by its damage value."""
        if (self.Z0, self.R0, self.GIc, self.GIIc, self.eta, self.mixed_mode) != \
                (other.Z0, other.R0, other.GIc, other.GIIc, other.eta, other.mixed_mode):
            raise ValueError("damage_on: the two laws differ in more than their penalty")
        d = np.clip(np.asarray(damage, float), 0.0, 1.0)
        return d * other.K / (d * other.K + (1.0 - d) * self.K)

    def failed(self, damage: np.ndarray) -> np.ndarray:
        return np.asarray(damage) >= 1.0

    def stored_density(self, dn: np.ndarray, ds: np.ndarray, damage: np.ndarray) -> np.ndarray:
        """(n,) J/m^2 elastic energy of the tractions at opening dn (n,), slip ds (n, k)."""
        return 0.5 * self.K * ((1 - damage) * (np.maximum(dn, 0) ** 2 + np.sum(ds**2, axis=1)) + np.minimum(dn, 0) ** 2)

    def tractions_fast(self, delta: np.ndarray, normal: np.ndarray, damage: np.ndarray):
        """The same law as ``tractions`` in one compiled pass (a per-step loop over bonds):
        delta (n, 3) separations m, normal (n, 3) unit; returns (t (n, 3) Pa, new damage (n,))."""
        t = np.empty_like(delta)
        d = np.empty_like(damage)
        _cohesive(delta, normal, damage, self.K, self.Z0, self.R0, self.GIc, self.GIIc, self.eta,
                  self.mixed_mode == "bk", t, d)
        return t, d


@kernel
def hashin_bond(d0, d1, d2, n0, n1, n2, damage, K, Z0, R0, GIc, GIIc, eta, bk):
    """One bond of the law (what ``tractions`` says over arrays): separation (d0, d1, d2) m,
    unit normal (n0, n1, n2), damage so far -> (t0, t1, t2) Pa and the new damage. The one
    place the fused kernels (law_kernels) and ``tractions_fast`` take the law from."""
    dn = d0 * n0 + d1 * n1 + d2 * n2
    s0_, s1_, s2_ = d0 - dn * n0, d1 - dn * n1, d2 - dn * n2
    s2 = s0_ * s0_ + s1_ * s1_ + s2_ * s2_
    slip = np.sqrt(s2)
    no, so = Z0 / K, R0 / K  # onset separations of pure opening and pure shear
    if dn > 0:
        m = np.sqrt(dn * dn + s2)
        b2 = (slip / dn) ** 2
        m0 = no * so * np.sqrt((1 + b2) / (so * so + b2 * no * no))
        B = b2 / (1 + b2)
        if bk:
            Gc = GIc + (GIIc - GIc) * B**eta
        else:
            Gc = 1.0 / (((1 - B) / GIc) ** eta + (B / GIIc) ** eta) ** (1.0 / eta)
    else:
        m = slip
        m0 = so
        Gc = GIIc
    mf = 2 * Gc / (K * m0)
    dnow = mf * (m - m0) / (m * (mf - m0)) if m > m0 else 0.0
    d = min(max(damage, dnow), 1.0)
    tn = (1 - d) * K * dn if dn > 0 else K * dn
    ks = (1 - d) * K
    return tn * n0 + ks * s0_, tn * n1 + ks * s1_, tn * n2 + ks * s2_, d


@kernel
def _cohesive(delta, normal, damage, K, Z0, R0, GIc, GIIc, eta, bk, t, d_out):
    for b in range(delta.shape[0]):
        t[b, 0], t[b, 1], t[b, 2], d_out[b] = hashin_bond(
            delta[b, 0], delta[b, 1], delta[b, 2], normal[b, 0], normal[b, 1], normal[b, 2], damage[b],
            K, Z0, R0, GIc, GIIc, eta, bk)


@kernel
def ply_bond(dn, m0, mf, damage, K):
    """One PlyBondLaw bond: opening dn m, onset / final opening m0, mf m (m0 = 0: not
    initiated), damage so far, stiffness K Pa/m -> (normal traction Pa, new damage)."""
    dnow = mf * (dn - m0) / (dn * (mf - m0)) if m0 > 0 and dn > m0 else 0.0
    d = min(max(damage, dnow), 1.0)
    return ((1 - d) * K * dn if dn > 0 else K * dn), d


def friction_traction(tn: np.ndarray, slip_rate: np.ndarray, mu: float, v_reg: float) -> np.ndarray:
    """Coulomb friction (n, k) Pa on failed, closed interfaces: mu |t_n| against the slip
    rate (n, k) m/s, regularised over v_reg m/s so it is continuous at stick."""
    p = np.maximum(-np.asarray(tn, float), 0.0)
    rate = np.asarray(slip_rate, float)
    speed = np.sqrt(np.sum(rate**2, axis=1) + v_reg**2)
    return -(mu * p / speed)[:, None] * rate


@dataclass
class PlyBondLaw:
    """Intralaminar bond of a ply lattice: the orthotropic Hoffman criterion for initiation,
    linear softening regularised by the fracture energy, full stiffness in compression.

    K: (nb,) Pa/m, central stiffness per bond area (bond force A K dn along the bond, no shear
    spring: the lattice's diagonals carry shear); Gf: (nb, 2) J/m^2, energy a bond dissipates
    per unit of its area from initiation to full separation when the crack it joins runs normal
    to global x (column 0) or y (column 1) (or z, column 2, in a 3D block), chosen at initiation by the larger normal stress
    (so a crack dissipates the same energy per area whatever the particle size: the
    regularisation of Bazant & Oh's crack band, with the band one bond long); strengths: the nine Hoffman strengths; axes: (nb, 3, 3) ply axes
    (columns) of each bond in global coordinates.

    Initiation is decided on the bond's stress (set by ``initiate`` from the lattice's particle
    stresses): a bond in tension whose Hoffman index reaches 1 starts softening from its
    current opening m0 to mf = 2 Gf / (K m0) (brittle, mf = m0, if the bond's elastic energy at
    initiation already exceeds Gf: counted in ``snapback``). A bond in compression whose index
    reaches 1 is counted in ``crushed`` and keeps its stiffness (crushing is not softened).
    """

    K: np.ndarray
    Gf: np.ndarray
    strengths: object
    axes: np.ndarray

    @property
    def never_initiates(self) -> bool:
        """No strength is finite: every bond stays a linear spring (a lattice's elastic springs;
        the fused step then skips the Love-Weber stress and the Hoffman index)."""
        return bool(np.all(np.isinf([float(v) for v in vars(self.strengths).values()])))

    def __post_init__(self):
        self.K = np.asarray(self.K, float)
        nb = self.K.size
        g = np.asarray(self.Gf, float)
        g = g.reshape(-1, g.shape[-1] if g.ndim else 1)
        self.Gf = np.broadcast_to(g, (nb, g.shape[1])).copy()  # one column per crack normal: x, y (, z)
        self.strength_scale = np.ones(nb)  # < 1: a weaker bond (an imperfection)
        self.axes = np.broadcast_to(np.asarray(self.axes, float), (nb, 3, 3)).copy()
        self.m0 = np.zeros(nb)  # onset opening (m), 0 until initiated
        self.mf = np.zeros(nb)
        self.index = np.zeros(nb)  # Hoffman index at the last initiation check
        self.crushed = np.zeros(nb, bool)
        self.snapback = 0

    def initiate(self, stress: np.ndarray, dn: np.ndarray, normal: np.ndarray | None = None) -> None:
        """stress: (nb, 6) Voigt global Pa at each bond; dn: (nb,) current openings m;
        normal: (nb, 3) unit bond axes. With the axes, only bonds that cross the crack plane
        (normal to the largest principal stress, within 45 degrees of it) start softening:
        a bond along the crack keeps its stiffness (else a vertical bond with a tiny Poisson
        opening would soften from a near-zero peak, i.e. lose its stiffness, all over a
        tension zone)."""
        from .kernels import hoffman_ply
        k = self.strengths
        self.index = hoffman_ply(stress, self.axes, self.strength_scale,
                                 (k.Xt, k.Xc, k.Yt, k.Yc, k.Zt, k.Zc, k.S23, k.S13, k.S12))
        over = (self.index >= 1.0) & (self.m0 == 0.0)
        new = over & (dn > 0)
        self.crushed |= over & (dn <= 0)
        if normal is not None and new.any():
            b = np.flatnonzero(new)
            s = stress[b]
            S = np.empty((len(b), 3, 3))
            for (i, j), c in zip(((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)), range(6)):
                S[:, i, j] = S[:, j, i] = s[:, c]
            e1 = np.linalg.eigh(S)[1][:, :, -1]  # direction of the largest principal stress
            crossing = np.einsum("bi,bi->b", e1, normal[b]) ** 2 >= 0.5 - 1e-9
            new[b[~crossing]] = False
        if new.any():
            m0 = dn[new]
            # the crack runs normal to the largest normal stress (ties: the first axis)
            col = np.argmax(np.abs(stress[new, : self.Gf.shape[1]]), axis=1)
            Gf = self.Gf[new][np.arange(col.size), col]
            mf = 2 * Gf / (self.K[new] * m0)
            self.snapback += int(np.sum(mf <= m0))
            self.m0[new], self.mf[new] = m0, np.maximum(mf, m0 * (1 + 1e-12))

    def tractions_fast(self, delta: np.ndarray, normal: np.ndarray, damage: np.ndarray):
        """delta (nb, 3) separations m, normal (nb, 3) unit -> (t (nb, 3) Pa, new damage (nb,))."""
        dn = np.einsum("bi,bi->b", delta, normal)
        tn, d = np.empty_like(dn), np.empty_like(dn)
        _ply(dn, self.m0, self.mf, np.asarray(damage, float), self.K, tn, d)
        return tn[:, None] * normal, d

    def stored_density(self, dn: np.ndarray, ds: np.ndarray, damage: np.ndarray) -> np.ndarray:
        return 0.5 * self.K * ((1 - damage) * np.maximum(dn, 0) ** 2 + np.minimum(dn, 0) ** 2)


@kernel
def _ply(dn, m0, mf, damage, K, tn, d):
    for b in range(dn.shape[0]):
        tn[b], d[b] = ply_bond(dn[b], m0[b], mf[b], damage[b], K[b])
