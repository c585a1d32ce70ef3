"""Closed forms and readings of a delaminated panel under axial compression (the seed paper's
example 5.2): the buckled thin film, the stepped column, Southwell's plot, Hutchinson & Suo's
energy release rate. Pure functions of numbers (N, m, Pa, J/m^2); study/panel.py feeds them.

Closed forms:
- local: the clamped thin film buckles at eps_c = (pi^2 / 3) (h / l)^2 (Chai, Babcock & Knauss
  1981), i.e. at the panel load P_local = E11 H b eps_c (uniform strain before buckling). Its
  tips are not rigid clamps: the laminate ahead of each tip lets the film's end turn, as it
  lets a DCB arm's root turn. The film is lengthened by corrected beam theory's crack-length
  correction chi h at each tip (Hashemi, Kinloch & Williams 1990; chi = 1.81 for Table 2's
  ply, a 10 % lower load) and Engesser's shear flexibility (2 %):
  eps_c = e / (1 + E11 e / (kappa G12)), e = (pi^2 / 3) (h / (l + 2 chi h))^2. The rigid-clamp
  value is reported beside it. Measured on the full mesh, all-FEM, ramps of 32 / 64 / 128
  periods: 5.62 / 5.41 / 5.30 kN, approaching the corrected 5.23 kN as the ramp slows (the
  rigid-clamp 5.88 kN is left behind);
- global: once the film has buckled it holds about its critical force and the base alone bends
  in the middle. The panel then buckles as a clamped stepped column (Timoshenko & Gere 2.10:
  intact ends EI(H), the base EI(H - h) in the middle carrying P minus the film's force), with
  Engesser's shear flexibility (kappa G12 A, kappa = 5/6; E11 / G12 = 25 makes it a 10 %
  effect). The intact panel's Euler load 4 pi^2 E11 I / L^2 (34.8 kN, 31.1 kN with shear) is
  reported beside it: with the reference loads' ratio the delamination spans half the free
  length, and a panel whose middle half has lost the film's bending stiffness does not reach it
  (measured: the base bends away from the buckled film, the opening mode; the faces never touch).
"""
from __future__ import annotations

import numpy as np


def panel_loads(E11: float, G12: float, chi: float, b: float, H: float, h: float, L: float, l: float) -> dict:
    """N: local (thin film, with its tips' root rotation and shear; and with rigid clamps),
    global of the intact panel (Euler, and with shear) and global of the delaminated panel
    once the film has buckled (stepped column). E11, G12 Pa; chi: corrected beam theory's
    crack-length factor; b width, H panel and h sublaminate thickness, L free length, l
    delamination length (m)."""
    kG = 5.0 / 6.0 * G12  # Pa, Engesser's shear flexibility (kappa = 5/6)
    eps_clamped = np.pi**2 / 3 * (h / l) ** 2
    # the film's ends turn as a DCB arm's root does: each tip moves chi h into the laminate
    e_root = np.pi**2 / 3 * (h / (l + 2 * chi * h)) ** 2
    eps_c = e_root / (1 + E11 * e_root / kG)
    euler = 4 * np.pi**2 * E11 * (b * H**3 / 12) / L**2
    kGA = kG * b  # N per unit thickness
    return {"local": E11 * H * b * eps_c, "local_clamped": E11 * H * b * eps_clamped,
            "global_intact": euler, "global_intact_shear": euler / (1 + euler / (kGA * H)),
            "global": stepped_column_load(E11 * b * H**3 / 12, E11 * b * (H - h) ** 3 / 12, L, l,
                                          E11 * h * b * eps_c, euler, kGA * H, kGA * (H - h))}


def stepped_column_load(EI1: float, EI2: float, L: float, l: float, P_film: float, P_max: float,
                        kGA1: float = np.inf, kGA2: float = np.inf) -> float:
    """N, symmetric buckling load of a clamped-clamped stepped column (Timoshenko & Gere,
    Theory of Elastic Stability, 2.10): ends of length (L - l) / 2 and bending stiffness EI1
    (N m^2) carrying P, a middle part of length l and stiffness EI2 (the base sublaminate)
    carrying P - P_film (the buckled film holds its critical force P_film and no lateral
    load). Shear flexibility by Engesser: each part's wave number k^2 = N / (EI (1 - N / kGA))
    with kGA (N) its shear stiffness (for a uniform column P = P_E / (1 + P_E / kGA)). The
    lowest root in (P_film, P_max) of the determinant of the support and continuity
    conditions, bracketed on a grid; nan if none."""
    from scipy.optimize import brentq
    a = 0.5 * (L - l)

    def det(P):
        k1 = np.sqrt(P / (EI1 * (1 - P / kGA1)))
        k2 = np.sqrt((P - P_film) / (EI2 * (1 - (P - P_film) / kGA2)))
        c1, s1, c2, s2 = np.cos(k1 * a), np.sin(k1 * a), np.cos(k2 * (a - L / 2)), np.sin(k2 * (a - L / 2))
        # end part: w = A + B x + C cos k1 x + D sin k1 x; middle (symmetric): w = A2 + C2 cos k2 (x - L/2)
        return np.linalg.det(np.array([
            [1, 0, 1, 0, 0, 0],  # w(0) = 0
            [0, 1, 0, k1, 0, 0],  # w'(0) = 0
            [1, a, c1, s1, -1, -c2],  # w continuous at x = a
            [0, 1, -k1 * s1, k1 * c1, 0, k2 * s2],  # slope
            [0, 0, -EI1 * k1**2 * c1, -EI1 * k1**2 * s1, 0, EI2 * k2**2 * c2],  # moment EI w"
            [0, 1, 0, 0, 0, 0],  # shear: EI w""" + N w' is P B at the ends, 0 in the middle
        ], float))

    P = np.linspace(max(1.001 * P_film, 1e-3 * P_max), min(P_max, 0.999 * kGA1, P_film + 0.999 * kGA2), 2000)
    d = np.array([det(x) for x in P])
    k = np.flatnonzero(np.sign(d[:-1]) != np.sign(d[1:]))
    return float(brentq(det, P[k[0]], P[k[0] + 1])) if k.size else float("nan")


def southwell(P: np.ndarray, w: np.ndarray, lo: float = 0.5, hi: float = 5.0) -> float:
    """Critical load by Southwell's plot: the added deflection d = w - w0 of an imperfect strut
    is w0 (P / P_cr) / (1 - P / P_cr), so d / P against d is a line of slope 1 / P_cr. Fitted
    over the samples where d grew from lo to hi times w0 (before it first exceeds hi w0)."""
    w0 = w[0]
    d = np.abs(w - w0)
    grown = np.flatnonzero(d > hi * abs(w0))
    end = grown[0] if grown.size else len(w)
    sel = np.flatnonzero((d[:end] > lo * abs(w0)) & (P[:end] > 0))
    if sel.size < 4:
        return float("nan")
    slope = np.polyfit(d[sel], d[sel] / P[sel], 1)[0]
    return float(1.0 / slope) if slope > 0 else float("nan")


def film_critical_strain(P: np.ndarray, w_open: np.ndarray, eps_film: np.ndarray, h: float,
                         end: int | None = None) -> float:
    """The sublaminate's critical membrane strain (-, compression positive): the least
    compression it carries once buckled, from the sample where its opening first exceeds its
    thickness h (past the dynamic overshoot of the snap) to the panel's limit load. An
    elastica's membrane force is lowest, at its critical value, just after buckling and rises
    slowly in post-buckling (and as the panel bends). end: the last sample to read (before the
    delamination grows: a longer film is softer). A thick film may start to grow before it has
    opened by h (Hutchinson & Suo's onset within about half its critical stress): it is then
    read as its largest compression before ``end``, provided that is a maximum the film passed
    through (it buckled), not the last sample read. nan if the film did not buckle."""
    grown = np.flatnonzero(np.abs(w_open - w_open[0]) > h)
    end = int(np.argmax(P)) if end is None else min(end, int(np.argmax(P)))
    if grown.size and grown[0] < end:
        return float(-np.max(eps_film[grown[0]:end + 1]))
    # (eps_film < 0 in compression) the peak compression, if the film came back from it
    k = int(np.argmin(eps_film[:end + 1])) if end >= 0 else 0
    return float(-eps_film[k]) if 0 < k < end and eps_film[end] > eps_film[k] * (1 - 1e-3) else float("nan")


def base_strain(P: float, E: float, H: float, h: float, b: float, eps_c: float) -> float:
    """(-, compression positive) strain of the base laminate under the panel load P (N) once the
    film (thickness h of H) holds its critical strain eps_c: the strain the film would carry
    unbuckled, which drives its tips (compatibility of the end shortening)."""
    return float((P - E * eps_c * h * b) / (E * (H - h) * b))


def hutchinson_suo(E: float, h: float, eps_c: float, eps: float) -> float:
    """J/m^2, energy release rate at the tips of a buckled thin film of thickness h (m) under the
    applied strain eps above its critical strain eps_c (Hutchinson & Suo 1992, VALIDATION.md):
    G = (h / 2E) (sigma - sigma_c) (sigma + 3 sigma_c), sigma = E eps."""
    s, sc = E * eps, E * eps_c
    return float(h / (2 * E) * (s - sc) * (s + 3 * sc)) if s > sc else 0.0


def growth_onset_load(E: float, b: float, H: float, h: float, eps_c: float, Gc: float) -> float:
    """N, the panel load at which Hutchinson & Suo's G of a film buckled at eps_c reaches Gc:
    G(sigma) = Gc solved for sigma, the base laminate's stress, plus the film's force."""
    s_c = E * eps_c
    sigma = -s_c + np.sqrt(4 * s_c**2 + 2 * E * Gc / h)
    return float(sigma * (H - h) * b + s_c * h * b)


def growth_onset_on_path(E: float, b: float, H: float, h: float, eps_c: float, P: np.ndarray,
                         Gc: np.ndarray) -> tuple[int, float]:
    """(sample, N): the first sample of a load history P (N) at which Hutchinson & Suo's G of a
    film buckled at eps_c reaches the toughness Gc (J/m^2) of the mode mix the tips carry at
    that sample (nan where no bond softens), and the load there; (-1, nan) if it never does.
    The mix moves as the panel bends (mode II while the film alone is buckled, towards mode I
    as the base bends away from it near the limit load), so the toughness that stops growth is
    the one of each moment, not of the sample where growth is first seen."""
    G = np.array([hutchinson_suo(E, h, eps_c, base_strain(float(x), E, H, h, b, eps_c)) for x in P])
    reached = np.flatnonzero(np.isfinite(Gc) & (G >= Gc))
    return (int(reached[0]), float(P[reached[0]])) if reached.size else (-1, float("nan"))
