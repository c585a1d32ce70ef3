"""The closed-form registry: what a study's checks compare with, by
``[checks.NAME] closed_form = "..."``. Each form computes its reference from the run's own
parameters (never from a previous run) and names the qoi it records it as."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from numpy.polynomial import polynomial as P

from dem_region import ply_lattice

from ..checks import check, energy_balance, within
from ..params import Param
from . import panel
from .schema import section

_CHECK = {"qoi": Param("", "the qoi compared (a name the run reports)", kind="str"),
          "tol": Param(0.05, "relative tolerance", low=0.0, open_low=True, high=10.0)}


@dataclass(frozen=True)
class ClosedForm:
    doc: str
    reference_qoi: str  # the qoi the reference is recorded as ("": not recorded)
    reference: Callable  # (study, p, the check's fields) -> float or (low, high), SI
    source: str  # "": the check's own source field
    fields: dict = None  # the check's fields (default: qoi and tol)
    costly: bool = False  # computed only when the checked qoi exists (it runs a model)
    with_qoi: bool = False  # reference(study, p, fields, qoi): it reads the run's measured qoi; None: no check
    specimen: bool = False  # data measured on the case file's specimen: compared only when the run is that specimen

    def __post_init__(self):
        object.__setattr__(self, "fields", dict(self.fields or _CHECK))


def beam_spring_mass(study, p: dict, f: dict | None = None, delaminated: bool = False) -> float:
    """Peak centre deflection (m) of a beam struck at mid-span by a rigid mass: v sqrt(M / k),
    quasi-static stiffness k = 192 D / L^3 clamped or 48 D / L^3 simply supported (L the span,
    D the plane-strain bending stiffness per width), M the impactor's mass plus the beam's
    effective mass, 0.37 (clamped, Rayleigh's 13/35) or 17/35 (simply supported) of its own.
    ``delaminated``: every interface between plies of different angle debonded, each run of
    plies bending about its own mid-plane (D = sum E_x t^3 / 12, frictionless)."""
    from .assemble import laminate
    lam = laminate(p, p["geometry.laminate"])
    (support,) = study.layout.names["supports"]
    clamped = p[f"supports.{support}.condition"] == "clamped"
    span = p["geometry.span"]
    if delaminated:
        D = sum(ply_lattice.slice_moduli(lam.D(a))[0] * (n * lam.ply_thickness) ** 3 / 12
                for a, n in zip(lam.angles, lam.plies))
    else:
        D = lam.bending_stiffness()
    k = (192 if clamped else 48) * D / span**3
    (imp,) = study.layout.names["impactors"]
    q = section(p, f"impactors.{imp}")
    M = q["mass_per_width"] + (0.37 if clamped else 17 / 35) * lam.ply["rho"] * lam.thickness * span
    return q["velocity"] * np.sqrt(M / k)


def plate_stiffness(p: dict) -> float:
    """k (N/m) of the whole clamped plate's one-term Ritz mode under a central load (plate_spring_mass)."""
    D = _plate_D(p)
    a, b = p["geometry.span"], p["geometry.width"]
    al, be = 2 * np.pi / a, 2 * np.pi / b
    return a * b / 64 * (3 * D[0, 0] * al**4 + 2 * (D[0, 1] + 2 * D[2, 2]) * al**2 * be**2 + 3 * D[1, 1] * be**4)


def impactor_mass(study, p: dict) -> float:
    """kg, the study's one impactor's whole mass: a sphere's, or a rod's rho pi r^2 L."""
    (imp,) = study.layout.names["impactors"]
    q = section(p, f"impactors.{imp}")
    if study.layout.names["impactors"][imp] == "rod":
        return q["rho"] * np.pi * q["radius"] ** 2 * q["length"]
    return q["mass"]


def plate_contact_radius(study, p: dict) -> float:
    """The plate's impactor's contact radius (m): a rod's face; a sphere's Hertz radius
    (3 F R / (4 E*))^(1/3) at the bending spring-mass peak force F = v sqrt(k M),
    E* = E22 / (1 - nu23^2) (the laminate's through-thickness stiffness against a rigid ball)."""
    from .assemble import laminate
    ply = laminate(p, p["geometry.laminate"]).ply
    return _contact_radius(study, p, ply["E22"] / (1 - ply["nu23"] ** 2),
                           lambda q: q["velocity"] * np.sqrt(plate_stiffness(p) * impactor_mass(study, p)))


def _contact_radius(study, p: dict, E_star: float, peak_force) -> float:
    """m: a pressure load's disc, a rod's face, or a sphere's Hertz radius (3 F R / (4 E*))^(1/3)
    at the peak force peak_force(its fields) against a body of contact modulus E_star Pa."""
    if not study.layout.names["impactors"]:
        (load,) = study.layout.names["loads"]
        return p[f"loads.{load}.radius"]
    (name,) = study.layout.names["impactors"]
    q = section(p, f"impactors.{name}")
    if study.layout.names["impactors"][name] == "rod":
        return q["radius"]
    return float(np.cbrt(3 * peak_force(q) * q["radius"] / (4 * E_star)))


def block_contact_radius(study, p: dict) -> float:
    """A block's impactor's contact radius (m): a rod's face; a sphere's Hertz radius
    (3 F R / (4 E*))^(1/3) at Hertz's peak impact force on a half-space,
    F = (5 M v^2 / 4)^(3/5) (4 E* sqrt(R) / 3)^(2/5), E* = E / (1 - nu^2) (a rigid ball); or
    a pressure load's disc."""
    m = section(p, f"materials.{p['geometry.material']}")
    E_star = m["E"] / (1 - m["nu"] ** 2)
    return _contact_radius(study, p, E_star, lambda q: (1.25 * q["mass"] * q["velocity"] ** 2) ** 0.6
                           * (4 / 3 * E_star * np.sqrt(q["radius"])) ** 0.4)


def block_spring_mass(study, p: dict, f: dict | None = None) -> float:
    """Peak displacement (m) of the top face's centre of a block struck by a flat-faced rod:
    quasi-static, the rod's mass M on the face's stiffness on a half-space (Boussinesq;
    Sneddon 1965), k_B = 2 E a / (1 - nu^2) for a rigid flat circular face of radius a, in
    series with the contact's penalty k_c = penalty pi a^2: the peak force v sqrt(M k),
    1 / k = 1 / k_B + 1 / k_c, over k_B. The block's finite depth on a floor (stiffer) and its
    free sides (softer) are left out: valid for a block deep and wide against the face."""
    (imp,) = study.layout.names["impactors"]
    q = section(p, f"impactors.{imp}")
    if study.layout.names["impactors"][imp] != "rod":
        from ..params import CaseError
        raise CaseError(f"impactors.{imp}.shape = 'sphere': the closed form block_spring_mass is for a flat-faced rod; "
                        "allowed: a rod, or another check")
    m = section(p, f"materials.{p['geometry.material']}")
    a = q["radius"]
    k_B = 2 * m["E"] * a / (1 - m["nu"] ** 2)
    k = 1 / (1 / k_B + 1 / (q["penalty"] * np.pi * a**2))
    return q["velocity"] * np.sqrt(impactor_mass(study, p) * k) / k_B


def block_pressure(study, p: dict, f: dict | None = None) -> float:
    """Peak displacement (m) of the top face's centre of a block under a uniform pressure on a
    disc of radius a, quasi-static on a half-space (Boussinesq; Timoshenko & Goodier, Theory of
    Elasticity, 1970, section 138): w0 = 2 (1 - nu^2) F / (pi a E), F the load's peak. Valid
    for a load slow against the block's waves and a block deep and wide against a."""
    (load,) = study.layout.names["loads"]
    m = section(p, f"materials.{p['geometry.material']}")
    from .bonded import load_curve
    curve = load_curve(p, load)
    F = max(abs(curve(t)) for t in curve.t)
    return 2 * (1 - m["nu"] ** 2) * F / (np.pi * p[f"loads.{load}.radius"] * m["E"])


def plate_spring_mass(study, p: dict, f: dict | None = None) -> float:
    """Peak centre deflection (m) of a clamped rectangular plate (span a along x, width b along
    y) struck at its centre by a rigid mass (a sphere or a flat-faced rod): v sqrt(M / k), with
    the one-term Ritz mode w = W (1 + cos 2 pi x / a)(1 + cos 2 pi y / b) / 4 of a specially
    orthotropic plate: k = (a b / 64) [3 D11 al^4 + 2 (D12 + 2 D66) al^2 be^2 + 3 D22 be^4],
    al = 2 pi / a, be = 2 pi / b (the bending energy of the mode; an upper bound, 9 % above
    Timoshenko's clamped square, 178.6 D / a^2), and M the impactor's mass plus 9 / 64 of the
    plate's."""
    _clamped(study, p, "plate_spring_mass")
    (imp,) = study.layout.names["impactors"]
    return p[f"impactors.{imp}.velocity"] * np.sqrt(_plate_mass(study, p) / plate_stiffness(p))


def plate_spring_mass_bracket(study, p: dict, f: dict | None = None) -> tuple[float, float]:
    """(low, high) peak centre deflection (m) of the clamped plate under a central impact,
    v sqrt(M / k): low with the plate's bending stiffness under a central point load alone,
    high with Mindlin's transverse shear in series, 1 / k = 1 / k_b + ln(R / r) /
    (2 pi kappa G t) about a load on a disc of radius r (the contact radius, at least half the
    thickness: through the plies a load spreads over about it, where Mindlin's point load is
    singular) in a clamped disc of radius R = min(a, b) / 2, kappa = 5/6, G the mean of G12 and
    G23 (as disc_spring_mass). k_b: Ritz on (1 - xi^2)^2 xi^(2m) x (1 - eta^2)^2 eta^(2n),
    m, n < 10 (clamped_point_stiffness: the clamped isotropic square within 0.5 % of Timoshenko's
    178.6 D / a^2); M the impactor's mass plus 9 / 64 of the plate's."""
    _clamped(study, p, "plate_spring_mass_bracket")
    from .assemble import laminate
    lam = laminate(p, p["geometry.laminate"])
    a, b, t = p["geometry.span"], p["geometry.width"], lam.thickness
    r = max(plate_contact_radius(study, p), t / 2)
    G = 0.5 * (lam.ply["G12"] + lam.ply["G23"])
    k_bending = clamped_point_stiffness(_plate_D(p), a, b)
    k_shear = 2 * np.pi * 5 / 6 * G * t / np.log(0.5 * min(a, b) / r)
    (imp,) = study.layout.names["impactors"]
    v, M = p[f"impactors.{imp}.velocity"], _plate_mass(study, p)
    return v * np.sqrt(M / k_bending), v * np.sqrt(M * (1 / k_bending + 1 / k_shear))


def plate_pressure_bracket(study, p: dict, f: dict | None = None) -> tuple[float, float]:
    """(low, high) quasi-static centre deflection (m) of the clamped plate under its pressure
    load's peak F on a central disc: F / k_b (the plate's bending stiffness under a point load,
    clamped_point_stiffness) and F (1 / k_b + ln(R / r) / (2 pi kappa G t)) with Mindlin's shear
    about the disc (r at least half the thickness), as plate_spring_mass_bracket. Valid for a
    load slow against the plate's first period."""
    _clamped(study, p, "plate_pressure_bracket")
    from .assemble import laminate
    from .bonded import load_curve
    lam = laminate(p, p["geometry.laminate"])
    a, b, t = p["geometry.span"], p["geometry.width"], lam.thickness
    (load,) = study.layout.names["loads"]
    curve = load_curve(p, load)
    F = max(abs(curve(s)) for s in curve.t)
    r = max(p[f"loads.{load}.radius"], t / 2)
    G = 0.5 * (lam.ply["G12"] + lam.ply["G23"])
    k_bending = clamped_point_stiffness(_plate_D(p), a, b)
    k_shear = 2 * np.pi * 5 / 6 * G * t / np.log(0.5 * min(a, b) / r)
    return F / k_bending, F * (1 / k_bending + 1 / k_shear)


def _clamped(study, p: dict, form: str) -> None:
    (support,) = study.layout.names["supports"]
    if p[f"supports.{support}.condition"] != "clamped":
        from ..params import CaseError
        raise CaseError(f"supports.{support}.condition = {p[f'supports.{support}.condition']!r}: the closed form "
                        f"{form} is for clamped edges; allowed: clamped, or another check")


def _plate_mass(study, p: dict) -> float:
    """kg: the impactor's mass plus 9 / 64 of the plate's (the Ritz mode's share)."""
    from .assemble import laminate
    lam = laminate(p, p["geometry.laminate"])
    return impactor_mass(study, p) + 9 / 64 * lam.ply["rho"] * lam.thickness * p["geometry.span"] * p["geometry.width"]


def _plate_D(p: dict) -> np.ndarray:
    """(3, 3) N m, the laminate's plane-stress bending stiffness about its mid-plane."""
    from fem_region import materials
    from .assemble import laminate
    lam = laminate(p, p["geometry.laminate"])
    z = np.cumsum([0] + lam.plies) * lam.ply_thickness - lam.thickness / 2
    return sum(materials.plane_stress(lam.C(angle)) * (z1**3 - z0**3) / 3
               for angle, z0, z1 in zip(lam.angles, z[:-1], z[1:]))


def clamped_point_stiffness(D: np.ndarray, a: float, b: float, n: int = 10) -> float:
    """k (N/m), a central point load over the centre deflection of a clamped specially
    orthotropic a x b plate of bending stiffness D (3, 3) N m: Ritz with the clamped trial
    functions (1 - xi^2)^2 xi^(2m), xi = 2 x / a (and in eta = 2 y / b), m < n, integrated
    exactly as polynomials."""

    def grams(length):  # {(i, j): int f_m^(i) f_q^(j) dx} over [-length / 2, length / 2]
        basis = [P.polymul(P.polypow([1, 0, -1], 2), [0] * (2 * m) + [1]) for m in range(n)]
        s = 2.0 / length  # d/dx = s d/dxi
        out = {}
        for i, j in ((0, 0), (1, 1), (2, 2), (2, 0), (0, 2)):
            G = np.empty((n, n))
            for m, f in enumerate(basis):
                for q, g in enumerate(basis):
                    F = P.polyint(P.polymul(P.polyder(f, i) * s**i, P.polyder(g, j) * s**j))
                    G[m, q] = (P.polyval(1.0, F) - P.polyval(-1.0, F)) / s
            out[i, j] = G
        return out

    X, Y = grams(a), grams(b)
    K = (D[0, 0] * np.kron(X[2, 2], Y[0, 0]) + D[1, 1] * np.kron(X[0, 0], Y[2, 2])
         + D[0, 1] * (np.kron(X[2, 0], Y[0, 2]) + np.kron(X[0, 2], Y[2, 0])) + 4 * D[2, 2] * np.kron(X[1, 1], Y[1, 1]))
    load = np.zeros(n * n)
    load[0] = 1.0  # only the first trial function is non-zero at the centre
    return 1.0 / float(load @ np.linalg.solve(K, load))


def disc_spring_mass(study, p: dict, f: dict | None = None, delaminated: bool = False) -> float:
    """Peak centre deflection (m) of a clamped circular laminated plate struck by a rod:
    v sqrt(M / k), 1 / k = R^2 / (16 pi D*) + ln(R / r) / (2 pi kappa G t): bending in series
    with transverse shear (Mindlin, load on the rod's disc of radius r, kappa = 5/6, G the mean
    of G12 and G23, t the thickness); M the whole rod's mass plus a fifth of the plate's.
    D* = (3 D11 + 2 (D12 + 2 D66) + 3 D22) / 8, the clamped orthotropic disc's axisymmetric
    (one-term Ritz) bending stiffness (Lekhnitskii, Anisotropic Plates, 1968), D of the plies
    about the mid-plane; ``delaminated``: every interface between plies of different angle
    debonded, each run of plies bending about its own mid-plane (frictionless)."""
    from fem_region import materials
    from .assemble import laminate
    lam = laminate(p, p["geometry.laminate"])
    if delaminated:  # runs of plies, each about its own mid-plane
        parts = [(a, -n * lam.ply_thickness / 2, n * lam.ply_thickness / 2) for a, n in zip(lam.angles, lam.plies)]
    else:
        z = np.cumsum([0] + lam.plies) * lam.ply_thickness - lam.thickness / 2
        parts = list(zip(lam.angles, z[:-1], z[1:]))
    D = sum(materials.plane_stress(lam.C(a)) * (z1**3 - z0**3) / 3 for a, z0, z1 in parts)
    D_star = (3 * D[0, 0] + 2 * (D[0, 1] + 2 * D[2, 2]) + 3 * D[1, 1]) / 8
    R, H = 0.5 * p["geometry.span"], lam.thickness
    (imp,) = study.layout.names["impactors"]
    q = section(p, f"impactors.{imp}")
    k_bending = 16 * np.pi * D_star / R**2
    G = 0.5 * (lam.ply["G12"] + lam.ply["G23"])
    k_shear = 2 * np.pi * 5 / 6 * G * H / np.log(R / q["radius"])
    M = q["rho"] * np.pi * q["radius"] ** 2 * q["length"] + 0.2 * lam.ply["rho"] * H * np.pi * R**2
    return q["velocity"] * np.sqrt(M * (1 / k_bending + 1 / k_shear))


SMALL_MASS = 0.23  # Olsson (2000): below this impactor / plate mass ratio the response is wave-controlled


def disc_mass_ratio(study, p: dict) -> float:
    """The rod's mass over the whole disc's (Olsson's impact-regime parameter)."""
    from .assemble import laminate
    lam = laminate(p, p["geometry.laminate"])
    (imp,) = study.layout.names["impactors"]
    q = section(p, f"impactors.{imp}")
    plate = lam.ply["rho"] * lam.thickness * (0.5 * p["geometry.span"]) ** 2
    return q["rho"] * q["radius"] ** 2 * q["length"] / plate  # pi cancels


def disc_spring_mass_bracket(study, p: dict, f: dict | None = None) -> tuple[float, float]:
    """(intact, fully delaminated) spring-mass estimates of the disc's peak deflection (m): a
    plate that delaminates lies between them. Below Olsson's small-mass ratio (rod / plate
    < 0.23) the rod rebounds before the plate's static mode forms and the deflection falls
    below the intact estimate (measured: -49 % at 0.12, -20 to -28 % at 0.18-0.23, -12 % at
    0.35, 0 to +18 % from 0.6): only the upper bound is checked there (low 0)."""
    low = disc_spring_mass(study, p) if disc_mass_ratio(study, p) >= SMALL_MASS else 0.0
    return low, disc_spring_mass(study, p, delaminated=True)


def beam_spring_mass_bracket(study, p: dict, f: dict | None = None) -> tuple[float, float]:
    """(intact, fully delaminated) spring-mass estimates of the peak centre deflection (m): a
    beam that delaminates lies between them."""
    return beam_spring_mass(study, p), beam_spring_mass(study, p, delaminated=True)


def elastic_cracking_time(study, p: dict, f: dict) -> float:
    """When the no-fracture (all-FEM) run's fibre stress (the ``probe``, a fibre_stress probe)
    first reaches the weakest body bond's strength, (1 - strength_scatter) ft (s; nan if never)."""
    from .probes import first_time
    ref = study.no_fracture_history(p)
    body = section(p, f"materials.{p['geometry.material']}")
    weakest = (1 - body["strength_scatter"]) * body["ft"]
    return first_time(np.asarray(ref["time"]), np.asarray(ref[f["probe"]]) - weakest)


_SOURCE = Param("", "where the value comes from (a test, a paper)", kind="str")


CLOSED_FORMS: dict[str, ClosedForm] = {
    "panel_axial_stiffness": ClosedForm(
        "a panel's pre-buckling axial stiffness E11 H b / L (panels)", "closed_form_axial_stiffness",
        panel.axial_stiffness, "pre-buckling axial stiffness E11 H b / L", with_qoi=True),
    "thin_film_buckling": ClosedForm(
        "the panel load at which a delaminated film buckles: clamped thin film E11 H b (pi^2/3)(h/l)^2 with "
        "l + 2 chi h (corrected beam theory's root rotation) and Engesser's shear (panels)", "closed_form_local",
        panel.film_buckling_load, "closed forms for this geometry (VALIDATION.md): thin film clamped at its "
        "tips, E11 H b (pi^2/3)(h/l)^2, with l + 2 chi h (corrected beam theory's root rotation) and Engesser's "
        "shear", with_qoi=True),
    "stepped_column_buckling": ClosedForm(
        "the delaminated panel's limit load: a clamped stepped column, the base alone in the middle carrying P "
        "minus the buckled film's force (Timoshenko & Gere 2.10); when the delamination grew before the limit load, "
        "the bracket of its loads for the length at the limit load and the initial length (panels)",
        "closed_form_global", panel.stepped_column_buckling_load,
        "clamped stepped column (Timoshenko & Gere 2.10): intact ends, the base sublaminate in the middle carrying "
        "P minus the film's critical force (grown before the limit load: between the lengths at the limit and at the "
        "start)",
        with_qoi=True),
    "film_growth_onset": ClosedForm(
        "the panel load at which the delamination grows: Hutchinson & Suo's G of the film at its measured critical "
        "strain first reaches the B-K toughness of the mode mix the tips carry at that moment (panels, coupled, when it "
        "grew)", "",
        panel.growth_onset, "Hutchinson & Suo (1992): G = (h / 2E)(sigma - sigma_c)(sigma + 3 sigma_c) = Gc(B) "
        "of the mode mix measured at each sample, first reached; sigma the base laminate's stress", with_qoi=True),
    "within_windows": ClosedForm(
        "the delamination stopped inside the DEM windows (growth_reached_window_edge = 0), unless they reach the "
        "clamps' neighbourhood (panels, coupled, when it grew)", "", panel.window_room,
        "the delamination stopped inside the DEM windows, or they reach the clamps' neighbourhood (else raise "
        "zone.window_ahead)", {"qoi": _CHECK["qoi"]}, with_qoi=True),
    "toughness_range": ClosedForm(
        "energy: the interface dissipates between GIc and GIIc per new crack area (the B-K range; panels, coupled, "
        "when it grew)", "", panel.toughness_range,
        "energy: the interface dissipates between GIc and GIIc per new crack area (B-K toughness range)",
        {"qoi": _CHECK["qoi"]}, with_qoi=True),
    "elastic_cracking_time": ClosedForm(
        "the time the no-fracture all-FEM twin's fibre stress reaches the weakest bond's strength (1 - scatter) ft "
        "(bonded beams; a first crack should appear then)", "elastic_cracking_time", elastic_cracking_time,
        "the no-fracture FEM's bottom fibre at mid-span reaches (1 - scatter) ft",
        {**_CHECK, "probe": Param("", "the fibre_stress probe read in the all-FEM twin", kind="str")}, costly=True),
    "disc_spring_mass_bracket": ClosedForm(
        "the peak deflection of a clamped disc under a rod between the spring-mass estimates of the intact plate and "
        "of the plate delaminated at every interface (its runs of plies bending apart), within tol below and above",
        "spring_mass_estimate", disc_spring_mass_bracket,
        "between (1 - tol) v sqrt(M / k_intact) and (1 + tol) v sqrt(M / k_delaminated), plate bending "
        "(Lekhnitskii's axisymmetric D*) and transverse shear in series; below Olsson's small-mass ratio (rod / "
        "plate < 0.23) the upper bound alone"),
    "disc_spring_mass": ClosedForm(
        "spring-mass estimate of a clamped disc's peak deflection under a rod: plate bending and transverse shear in "
        "series (an estimate)", "spring_mass_estimate", disc_spring_mass,
        "spring-mass estimate v sqrt(M / k), plate bending and shear in series (an estimate)"),
    "test_value": ClosedForm(
        "a value measured in a test (independent data), within tol", "", lambda study, p, f: f["value"], "",
        {**_CHECK, "value": Param(0.0, "the measured value (SI)"), "source": _SOURCE}, specimen=True),
    "test_between": ClosedForm(
        "a measured range (independent data): the qoi between low and high", "",
        lambda study, p, f: (f["low"], f["high"]), "",
        {"qoi": _CHECK["qoi"], "low": Param(0.0, "lowest value (SI)"), "high": Param(0.0, "highest value (SI)"),
         "source": _SOURCE}, specimen=True),
    "beam_spring_mass_bracket": ClosedForm(
        "the peak deflection between the spring-mass estimates of the intact beam and of the beam delaminated at "
        "every interface (its runs of plies bending apart), within tol below and above",
        "spring_mass_estimate", beam_spring_mass_bracket,
        "between (1 - tol) v sqrt(M / k_intact) and (1 + tol) v sqrt(M / k_delaminated), k = 192 D / L^3 (clamped) "
        "or 48 D / L^3 (simply supported)"),
    "plate_spring_mass": ClosedForm(
        "spring-mass estimate of a clamped plate's peak deflection under a central impact (one impactor)",
        "spring_mass_estimate", plate_spring_mass,
        "spring-mass estimate v sqrt(M / k), k of the one-term Ritz mode of a clamped orthotropic plate"),
    "plate_spring_mass_bracket": ClosedForm(
        "spring-mass bracket of a clamped plate's peak deflection under a central impact (one impactor): the "
        "bending stiffness under a point load (Ritz, converged) alone and in series with Mindlin's transverse shear",
        "spring_mass_estimate", plate_spring_mass_bracket,
        "spring-mass bracket v sqrt(M / k): k of a clamped orthotropic plate under a central point load (Ritz), "
        "alone and with Mindlin's transverse shear about the contact radius"),
    "block_spring_mass": ClosedForm(
        "spring-mass estimate of a block's peak indentation under a flat-faced rod (Boussinesq's rigid punch on a "
        "half-space in series with the contact penalty)", "spring_mass_estimate", block_spring_mass,
        "spring-mass estimate v sqrt(M k) / k_B, k_B = 2 E a / (1 - nu^2) (Boussinesq, Sneddon 1965) in series with "
        "the contact penalty"),
    "plate_pressure_bracket": ClosedForm(
        "quasi-static bracket of a clamped plate's centre deflection under a pressure disc (one [loads.*] of kind "
        "pressure): point-load bending (Ritz) alone and with Mindlin's shear about the disc", "static_estimate",
        plate_pressure_bracket,
        "quasi-static bracket F / k: k of a clamped orthotropic plate under a central point load (Ritz), alone and "
        "with Mindlin's transverse shear about the disc"),
    "block_pressure": ClosedForm(
        "quasi-static displacement of a block's top face's centre under a pressure disc (one [loads.*] of kind "
        "pressure; Boussinesq's half-space)", "static_estimate", block_pressure,
        "quasi-static w0 = 2 (1 - nu^2) F / (pi a E), a uniform pressure disc on a half-space (Timoshenko & Goodier)"),
    "beam_spring_mass": ClosedForm(
        "spring-mass estimate of a beam's peak deflection under a central impact (one impactor, one support "
        "kind at both ends)", "spring_mass_estimate", beam_spring_mass,
        "spring-mass estimate v sqrt(M / k), k = 192 D / L^3 (clamped) or 48 D / L^3 (simply supported)"),
}


def evaluate(study, p: dict, qoi: dict, history: dict) -> dict:
    """The study's checks, plus the energy balance every run has; records each reference as qoi."""
    checks, changed = {}, study.changed(p)
    for name, form_name in study.layout.names["checks"].items():
        form, f = CLOSED_FORMS[form_name], section(p, f"checks.{name}")
        if form.costly and f["qoi"] not in qoi or form.specimen and changed:  # (another specimen: Study.build says)
            continue
        ref = form.reference(study, p, f, qoi) if form.with_qoi else form.reference(study, p, f)
        if ref is None:  # the form does not apply to this run (e.g. growth that did not happen)
            continue
        source = form.source or f["source"]
        tol = f.get("tol", 0.0)
        if isinstance(ref, tuple):  # a bracket (low, high)
            if form.reference_qoi:
                qoi[form.reference_qoi], qoi[form.reference_qoi + "_upper"] = ref
            if f["qoi"] in qoi:
                checks[name] = within(qoi[f["qoi"]], (1 - tol) * ref[0], (1 + tol) * ref[1], source, tol)
            continue
        if form.reference_qoi:
            qoi[form.reference_qoi] = ref
        if f["qoi"] in qoi:
            checks[name] = check(qoi[f["qoi"]], ref, tol, source)
    checks["energy_balance"] = energy_balance(history)
    return checks
