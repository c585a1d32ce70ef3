"""The probe registry: what a study may measure, by ``[probes.NAME] kind = "..."``.

A probe kind declares its fields (typed, documented), makes the history series of a run
(name -> callable giving a float, SI, sampled by the clock) from what the assembler built, and
reduces the histories to quantities of interest. A kind with nothing to measure in a mode (a
damage probe in an all-FEM run) adds no series there.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.integrate import trapezoid

from ..params import CaseError, Param, positive
from .panel import buckling_qoi, buckling_series, growth_qoi, growth_series
from .schema import section


@dataclass(frozen=True)
class ProbeKind:
    doc: str
    fields: dict[str, Param]
    series: Callable  # (built, name, fields) -> {series name: () -> float}
    qoi: Callable  # (name, fields, history[, p]) -> {qoi name: float}
    with_params: bool = False  # qoi also takes the resolved parameters (readings that need the geometry)
    reports: tuple = ()  # qoi names it reports whatever the probe's name (the others contain the name)
    names: tuple = ()  # every qoi name it reports: {name} the probe's, a trailing * any ending (one per
    # interface or time); a clash between two probes' is refused (one of them would vanish)


def _point_series(built, name, f):
    """Displacement component of the particle (or, without one within a spacing, the FEM node)
    nearest (x, y[, z])."""
    dim = built.dim
    comp, sign = "xyz".index(f["component"][-1]), -1.0 if f["component"].startswith("-") else 1.0
    if comp >= dim:
        raise CaseError(f"probes.{name}.component = {f['component']!r}: allowed x, y (2D), z (3D), with a leading -")
    at = np.array([f["x"], f["y"], f["z"]])[:dim]
    lat = built.lattice
    if lat is not None and np.min(np.linalg.norm(lat.x[:, :dim] - at, axis=1)) <= built.t:
        i = int(np.argmin(np.linalg.norm(lat.x[:, :dim] - at, axis=1)))
        backend, x0 = built.backend, lat.x[i, comp]
        return {name: lambda: sign * float(backend.positions_of(np.array([i]))[0, comp] - x0)}
    dyn = built.dyn
    i = int(np.argmin(np.linalg.norm(dyn.region.X - at, axis=1)))
    return {name: lambda: sign * float(dyn.state.u[i, comp])}


def _peak_qoi(name, f, h):
    u, time = np.asarray(h[name]), np.asarray(h["time"])
    k = int(np.argmax(u))
    return {f"peak_{name}": float(u[k]), f"time_of_peak_{name}": float(time[k])}


def _contact_series(built, name, f):
    """Force of the impactor on the structure (whole structure), upwards on it (N); its
    vertical velocity (m/s)."""
    imp, w, up = built.impactors[f["impactor"]], built.width_factor, built.dim - 1
    name_v = f"{f['impactor']}_velocity"
    if hasattr(imp, "imp"):  # on particles: the force the particles exert on it
        return {name: lambda: float(imp.force[up] * w), name_v: lambda: float(imp.imp.v[up])}
    return {name: lambda: float(imp.a[up] * imp.mass * w), name_v: lambda: float(imp.v[up])}


def _delamination_series(built, name, f):
    """Per ply interface k (bottom up), over the whole structure: debonded area (m^2), and the
    debonded and damaged (d > 0) lengths, area / width (m), of the zone's bonds and, with a
    cohesive far field, the FEM's node pairs. The tied or clamped column is not counted (it is
    the FEM's face or the support)."""
    if built.lam is None or (built.inter is None and built.node_bonds is None):
        return {}
    W, up, lam = built.p["geometry.width"], built.dim - 1, built.lam
    levels = np.cumsum(lam.plies)[:-1] * lam.ply_thickness  # the interfaces, bottom up
    parts = []  # (bonds, area (whole structure), interface index of each bond)
    if built.inter is not None:
        inter, first = built.inter, built.inter.pairs[:, 0]
        area = built.width_factor * inter.area
        if built.end_held:
            area = np.where(built.column[first] == built.column.max(), 0.0, area)
        parts.append((inter, area, np.searchsorted(levels, built.lattice.x[first, up])))
    if built.node_bonds is not None:
        nb = built.node_bonds
        z = built.dyn.region.X[nb.pairs[:, 0], up]
        parts.append((nb, built.width_factor * nb.area, np.argmin(np.abs(z[:, None] - levels[None, :]), axis=1)))
    out = {}
    for k in sorted(set(np.concatenate([idx for _, _, idx in parts]).tolist())):
        sel = [(b, a, idx == k) for b, a, idx in parts]
        debonded = lambda sel=sel: float(sum(a[s] @ b.failed()[s] for b, a, s in sel))
        out[f"{name}_area_{k}"] = debonded
        out[f"{name}_length_{k}"] = lambda debonded=debonded: debonded() / W
        out[f"damaged_interface_length_{k}"] = lambda sel=sel: float(sum(a[s] @ (b.damage[s] > 0) for b, a, s in sel)) / W
    return out


def _final_qoi(prefixes):
    def qoi(name, f, h):
        return {k: float(np.asarray(v)[-1]) for k, v in h.items()
                if any(k.startswith(p.format(name=name)) for p in prefixes)}
    return qoi


def _ply_crack_series(built, name, f):
    """Failed intralaminar bonds with both ends in plies of the given angle (or all)."""
    if built.intra is None:
        return {}
    lat, intra = built.lattice, built.intra
    if f["angle"] == "all":
        return {name: lambda: float(np.sum(intra.failed()))}
    angle = np.array(built.lam.angles)[lat.ply]
    inside = (angle[lat.intra_pairs] == float(f["angle"])).all(axis=1)
    return {name: lambda: float(np.sum(intra.failed() & inside))}


def _zone_edge_series(built, name, f):
    """The largest damage in the last ``columns`` columns before the zone's edge that the far
    field cannot carry on: the interlaminar (or adhesive) bonds', unless the far field's plies
    are cohesive (a delamination runs on into them), and the body's or plies' bonds with both
    ends there (bonded beams; laminates whose plies fail). Near 1: the damage reached the edge
    and the zone must widen."""
    if built.inter is None:
        return {}
    column, last = built.column, built.column.max() - f["columns"]
    families = [(b, column[b.pairs].min(axis=1) >= last) for b in uncarried(built)]
    families = [(b, edge) for b, edge in families if edge.any()]
    return {name: lambda: max((float(b.damage[edge].max()) for b, edge in families), default=0.0)}


def uncarried(built) -> list:
    """The zone's bond families (LawBonds) whose damage the far field cannot carry on: the
    interlaminar (or adhesive) bonds unless the far field's plies are cohesive (a delamination
    runs on into them), and the body's or plies' bonds (bonded beams; laminates whose plies
    fail)."""
    if built.inter is None:
        return []
    families = [] if built.node_bonds is not None else [built.inter]
    if getattr(built, "edge_intra", False) or (built.lam is not None and not built.lam.elastic):
        families.append(built.intra)
    return families


def _far_field_series(built, name, f):
    """The largest failure indices over the FEM's elements now (1 at initiation): Hoffman's
    ply index and, where the far-field plies are tied (a cohesive far field delaminates by
    itself), Hashin's interlaminar index, from each element's centroid strain and ply
    (study/fields.ElementIndex on FemIndices' ply stresses; 0 at rest, and a negative Hoffman
    index reads 0); a peak at 1 or more is damage the model leaves out. No series without a FEM
    or a laminate."""
    dyn = built.dyn
    if dyn is None or built.lam is None:
        return {}
    from .fields import ElementIndex, FemIndices
    region = dyn.region
    fi = FemIndices(region, built.lam, built.dim)
    # each criterion alone in the growth check's compiled pass (numpy took 0.2 ms a sample on
    # 208 Q4, a twentieth of a 2-ply coupled beam's run)
    tied = built.node_bonds is None  # (Hashin's series only where the far field cannot delaminate)
    criteria = [ElementIndex(region, fi.ply_stress, False, True, fi.k, fi.Z0, fi.R0) if tied else None,
                ElementIndex(region, fi.ply_stress, True, False, fi.k, fi.Z0, fi.R0)]  # (Hashin, Hoffman)
    x = region.X[region.mesh.t.T][:, :, 0].mean(axis=1)  # (nel,) m each element's centroid along x
    now: dict[int, tuple[float, float, float]] = {}  # criterion -> (t, its peak, the peak's x)

    def largest(which: int, where: bool = False) -> float:
        if which not in now or now[which][0] != dyn.state.t:  # (once per sample for its two series)
            index = criteria[which](dyn.state.u)
            k = int(np.argmax(index))
            now[which] = (dyn.state.t, float(index[k]), float(x[k]))
        return now[which][2] if where else now[which][1]

    series = {f"{name}_hoffman": lambda: largest(1), f"{name}_hoffman_x": lambda: largest(1, True)}
    if tied:
        series.update({f"{name}_interlaminar": lambda: largest(0), f"{name}_interlaminar_x": lambda: largest(0, True)})
    return series


def _far_field_qoi(name, f, h):
    """peak_NAME_CRITERION and x_of_peak_NAME_CRITERION (m, the element's centroid)."""
    out = {}
    for c in ("hoffman", "interlaminar"):
        if f"{name}_{c}" in h:
            k = int(np.argmax(h[f"{name}_{c}"]))
            out[f"peak_{name}_{c}"] = float(h[f"{name}_{c}"][k])
            out[f"x_of_peak_{name}_{c}"] = float(h[f"{name}_{c}_x"][k])
    return out


def left_out(name: str, h: dict, qoi: dict) -> list[str]:
    """Warnings for a far_field_failure probe NAME whose index reached 1 (initiation) in the
    FEM, which cannot fail: damage a coupled model leaves out."""
    lines = []
    for c, what in (("hoffman", "Hoffman ply"), ("interlaminar", "Hashin interlaminar")):
        peak = qoi.get(f"peak_{name}_{c}", 0.0)
        if peak >= 1.0:
            t = float(h["time"][np.argmax(np.asarray(h[f"{name}_{c}"]) >= 1.0)])
            x = qoi.get(f"x_of_peak_{name}_{c}", np.nan)  # (nan: a peak before a resume from an older checkpoint)
            where = f", at x = {x * 1e3:.3g} mm" if np.isfinite(x) else ""
            lines.append(f"the far field's {what} index reached 1 at t = {t:.3g} s and {peak:.2f} at most{where}: "
                         "damage the coupled model leaves out there (its FEM cannot fail); --mode dem shows it, or a "
                         "zone that holds it")
    return lines


def peak_at_end(name: str, h: dict) -> list[str]:
    """A warning for a point_displacement probe NAME whose peak is the history's last sample:
    still rising when the run ended, so peak_NAME and time_of_peak_NAME may not be the peak's.
    h: the history, h[NAME] (n,) m and h["time"] (n,) s."""
    u, time = np.asarray(h.get(name, [])), np.asarray(h["time"])
    if u.size < 2 or int(np.argmax(u)) != u.size - 1:  # (argmax: the first of equal values)
        return []
    return [f"peak_{name} = {u[-1]:.4g} m is at the run's last sample (t = {time[-1]:.4g} s): the run may end "
            "before the peak; a longer clock.t_end finds it"]


def at_time(at: float, time: np.ndarray, series: np.ndarray) -> float:
    """``series`` (n,) at time ``at`` (s) of the samples ``time`` (n,) s, linearly interpolated;
    nan after the run's last sample (np.interp would hold the last value: a moment the run
    never reached)."""
    return float(np.interp(at, time, series)) if at <= time[-1] * (1 + 1e-9) else float("nan")


def first_time(time: np.ndarray, series: np.ndarray) -> float:
    """First sample time at which ``series`` > 0 (nan if never)."""
    hit = np.flatnonzero(np.asarray(series) > 0)
    return float(time[hit[0]]) if hit.size else float("nan")


def _load_series(built, name, f):
    """The whole load (N) a [loads.*] applies now."""
    return {name: built.load_probes[f["load"]]}


def _fibre_stress_series(built, name, f):
    """sigma_xx (Pa) of the body's material on the small-strain centroid strain of the FEM
    element nearest the point (all-FEM runs; on a bonded beam's bottom row the element holds the
    sheet smeared: its strain is the body's, its stress is not)."""
    if built.lattice is not None or built.dyn is None:
        return {}
    region, dyn = built.dyn.region, built.dyn
    at = np.array([f["x"], f["y"], f["z"]])[:built.dim]
    centroid = region.X[region.mesh.t.T].mean(axis=1)
    e = int(np.argmin(np.linalg.norm(centroid - at, axis=1)))
    row = built.fibre_stiffness
    return {name: lambda: float(row @ region.centroid_strain_stress(dyn.state.u)[0][e])}


def _crack_series(built, name, f):
    """Cracks in a bonded beam's body: bonds softening; bonds open by more than visible_opening
    (a crack one sees in a test) at the bottom face within one depth of mid-span, at the top face
    within half a depth; the highest such crack near mid-span (m); all such; traction-free."""
    if built.intra is None or not hasattr(built, "bonded"):
        return {}
    c, x, d, up = built.intra, built.lattice.x, built.t, built.dim - 1
    H = built.bonded.depth
    xm = 0.5 * (x[c.pairs[:, 0]] + x[c.pairs[:, 1]])
    near = np.abs(xm[:, 0]) < H
    bottom = near & (xm[:, up] < d)  # bonds touching the bottom row
    top = (np.abs(xm[:, 0]) < H / 2) & (xm[:, up] > H - d)
    w = f["visible_opening"]
    cracked = lambda: (c.damage > 0) & (c.split(c.delta)[0] >= w)
    return {
        f"{name}_bottom": lambda: float(np.sum(cracked()[bottom])),
        f"{name}_softening": lambda: float(np.sum(c.damage > 0)),
        f"{name}_top": lambda: float(np.sum(cracked()[top])),
        f"{name}_height": lambda: float(xm[near & cracked(), up].max() + d / 2) if np.any(near & cracked()) else 0.0,
        f"{name}_visible": lambda: float(np.sum(cracked())),
        f"{name}_traction_free": lambda: float(np.sum(c.failed())),
    }


def _crack_qoi(name, f, h):
    time = np.asarray(h["time"])
    return {"crack_onset_time": first_time(time, h[f"{name}_softening"]),
            "crack_initiation_time": first_time(time, h[f"{name}_bottom"]),
            "crack_top_time": first_time(time, h[f"{name}_top"]),
            "cracked_bonds": float(h[f"{name}_visible"][-1]),
            "traction_free_bonds": float(h[f"{name}_traction_free"][-1])}


def _debond_series(built, name, f):
    """A bonded sheet: debonded (traction-free) and damaged lengths of the adhesive along the
    beam (whole beam, m; 3D: areas over the width), broken sheet bonds."""
    if built.inter is None or not hasattr(built, "bonded"):
        return {}
    bond, sheet, whole = built.inter, built.sheet, built.bond_whole
    return {f"{name}_length": lambda: float(whole @ bond.failed()),
            f"{name}_damaged_length": lambda: float(whole @ (bond.damage > 0)),
            f"{name}_sheet_broken": lambda: float(np.sum(sheet.failed()))}


def _debond_qoi(name, f, h):
    time, length = np.asarray(h["time"]), np.asarray(h[f"{name}_length"])
    at = f["at"]
    return {"debond_initiation_time": first_time(time, length), "debonded_length": float(length[-1]),
            f"debonded_fraction_{round(at * 1e6)}us": at_time(at, time, length) / f["beam_length"],
            "sheet_broken_bonds": float(h[f"{name}_sheet_broken"][-1])}


def _motion_series(built, name, f):
    """An impactor's velocity into the structure (m/s, positive towards it) and how far its face
    has moved in (m) from where it started (its center: a grown zone's model is built with the
    impactor already moved)."""
    imp = built.impactors[f["impactor"]]
    rigid = imp.imp if hasattr(imp, "imp") else imp
    up, z0 = built.dim - 1, float(rigid.center[built.dim - 1])
    return {f"{name}_velocity": lambda: float(-rigid.v[up]), f"{name}_displacement": lambda: float(-(rigid.x[up] - z0))}


def _separation(*families) -> float:
    """m, the largest opening of the interface bonds."""
    return float(max(max(np.einsum("bi,bi->b", b.delta, b.normal).max(initial=0.0), 0.0) for b in families))


def _interface_damage_series(built, name, f):
    """Over every ply interface, the far field's node-pair bonds and the zone's together, whole
    structure: debonded and damaged (d > 0) areas (m^2), the largest opening (m)."""
    fams = [b for b in (built.node_bonds, built.inter) if b is not None]
    if not fams:
        return {}
    w = built.width_factor
    area = [b.area for b in fams]
    return {"debonded_area": lambda: float(w * sum(a @ b.failed() for a, b in zip(area, fams))),
            "damaged_area": lambda: float(w * sum(a @ (b.damage > 0) for a, b in zip(area, fams))),
            "layer_separation": lambda: _separation(*fams)}


def _when(*series):
    """A qoi function that reports only when the probe made its series in this mode."""
    def wrap(fn):
        def qoi(name, f, h):
            return fn(name, f, h) if all(s.format(name=name) in h for s in series) else {}
        return qoi
    return wrap


def _max_qoi(name, f, h):
    return {name: float(np.max(h[name]))} if name in h else {}


_COMPONENTS = ("x", "y", "z", "-x", "-y", "-z")
PROBES: dict[str, ProbeKind] = {
    "point_displacement": ProbeKind(
        "displacement of the material point nearest (x, y); qoi peak_NAME, time_of_peak_NAME",
        {"x": Param(0.0, "x of the point", unit="m"), "y": Param(0.0, "y of the point", unit="m"),
         "z": Param(0.0, "z of the point (3D)", unit="m"),
         "component": Param("-y", "component (a leading - reverses it); z in 3D", kind="str", choices=_COMPONENTS)},
        _point_series, _peak_qoi,
        names=("peak_{name}", "time_of_peak_{name}", "peak_{name}_no_fracture", "{name}_change_by_fracture")),
    "contact_force": ProbeKind(
        "force between an impactor and the structure (whole width), and the impactor's velocity; qoi peak_NAME, "
        "NAME_impulse (its time integral, N s: robust where the peak is a chattering contact's largest spike)",
        {"impactor": Param("", "the impactor (an [impactors.*] name)", kind="str")},
        _contact_series, lambda name, f, h: {f"peak_{name}": float(np.max(h[name])),
                                             f"{name}_impulse": float(trapezoid(h[name], h["time"]))},
        names=("peak_{name}", "{name}_impulse")),
    "delamination": ProbeKind(
        "debonded area (NAME_area_K), debonded and damaged lengths (NAME_length_K, damaged_interface_length_K: "
        "area / width) of each ply interface K, bottom up, whole structure; qoi: their final values",
        {}, _delamination_series, _final_qoi(("{name}_area_", "{name}_length_", "damaged_interface_length_")),
        names=("{name}_area_*", "{name}_length_*", "damaged_interface_length_*")),
    "ply_cracks": ProbeKind(
        "failed intralaminar bonds in the plies of one angle (or all); qoi: the final count",
        {"angle": Param("90", "ply angle, or all", kind="str", choices=("0", "90", "all"))},
        _ply_crack_series, _final_qoi(("{name}",)),
        names=("{name}*",)),
    "zone_edge_damage": ProbeKind(
        "largest damage near the zone's edge that the far field cannot carry on (1: the zone is too narrow): "
        "interlaminar (tied far-field plies) and the plies' own; qoi: its maximum",
        {"columns": Param(2, "particle columns counted from the edge", kind="int", low=0, high=100)},
        _zone_edge_series, _max_qoi,
        names=("{name}",)),
    "far_field_failure": ProbeKind(
        "the largest failure indices in the FEM (1 at initiation; 1 or more is damage the model leaves out): "
        "Hoffman's, and Hashin's interlaminar where the far-field plies are tied; qoi peak_NAME_hoffman "
        "(peak_NAME_interlaminar), and x_of_peak_NAME_hoffman (_interlaminar) where it was; in coupled mode a peak "
        "at 1 or more warns",
        {}, _far_field_series, _when("{name}_hoffman")(_far_field_qoi),
        names=tuple(f"{w}peak_{{name}}_{c}" for w in ("", "x_of_") for c in ("hoffman", "interlaminar"))),
    "impactor_motion": ProbeKind(
        "an impactor's velocity into the structure and its face's travel; qoi final_NAME_velocity",
        {"impactor": Param("", "the impactor (an [impactors.*] name)", kind="str")},
        _motion_series, _when("{name}_velocity")(lambda name, f, h: {f"final_{name}_velocity":
                                                                       float(h[f"{name}_velocity"][-1])}),
        names=("final_{name}_velocity",)),
    "interface_damage": ProbeKind(
        "all ply interfaces together (FEM node pairs and particles), whole structure: debonded_area, damaged_area "
        "(m^2), layer_separation (largest opening, m); qoi debonded_area, damaged_area (final), "
        "peak_layer_separation",
        {}, _interface_damage_series,
        _when("debonded_area")(lambda name, f, h: {"debonded_area": float(h["debonded_area"][-1]),
                                                   "damaged_area": float(h["damaged_area"][-1]),
                                                   "peak_layer_separation": float(np.max(h["layer_separation"]))}),
        names=("debonded_area", "damaged_area", "peak_layer_separation")),
    "applied_load": ProbeKind(
        "the whole load a [loads.*] applies (N); qoi peak_NAME",
        {"load": Param("", "the load (a [loads.*] name)", kind="str")},
        _load_series, _when("{name}")(lambda name, f, h: {f"peak_{name}": float(np.max(h[name]))}),
        names=("peak_{name}",)),
    "fibre_stress": ProbeKind(
        "sigma_xx of the body's material at the FEM element nearest (x, y[, z]), all-FEM runs only (the "
        "reference of elastic_cracking_time); qoi peak_NAME",
        {"x": Param(0.0, "x of the point", unit="m"), "y": Param(0.0, "y of the point", unit="m"),
         "z": Param(0.0, "z of the point (3D)", unit="m")},
        _fibre_stress_series, _when("{name}")(lambda name, f, h: {f"peak_{name}": float(np.max(h[name]))}),
        names=("peak_{name}",)),
    "flexural_cracks": ProbeKind(
        "cracks in a bonded beam's body (bonded beams); qoi crack_onset_time (first bond softening), "
        "crack_initiation_time (a bond at the bottom face within a depth of mid-span opens visible_opening), "
        "crack_top_time (the same at the top face within half a depth), cracked_bonds, traction_free_bonds",
        {"visible_opening": positive(0.1e-3, "crack opening counted as a crack (one seen by eye in a test is "
                                     "~0.1 mm wide)", "m")},
        _crack_series, _when("{name}_bottom")(_crack_qoi),
        names=("crack_onset_time", "crack_initiation_time", "crack_top_time", "cracked_bonds",
               "traction_free_bonds")),
    "debonding": ProbeKind(
        "the adhesive between a bonded beam and its sheet (bonded beams): NAME_length (debonded, whole beam), "
        "NAME_damaged_length, NAME_sheet_broken; qoi debond_initiation_time, debonded_length, "
        "debonded_fraction_<at>us (of beam_length), sheet_broken_bonds",
        {"at": positive(750e-6, "the time of the debonded fraction (of the beam's and sheet's length)", "s")},
        _debond_series, _when("{name}_length")(_debond_qoi),
        names=("debond_initiation_time", "debonded_length", "debonded_fraction_*", "sheet_broken_bonds")),
    "panel_buckling": ProbeKind(
        "a panel's axial_force, end_shortening, deflection_A / deflection_B (mid-span, top and bottom faces), "
        "film_strain (the sublaminate's membrane strain), contact_force and interpenetration of the delaminated "
        "faces; qoi local_buckling_load (the film's critical strain x E11 H b), global_buckling_load (the limit "
        "load), film_critical_strain, their Southwell fits, axial_stiffness, tip_energy_release_rate (panels)",
        {}, buckling_series, buckling_qoi, with_params=True,
        reports=("local_buckling_load", "global_buckling_load", "film_critical_strain", "axial_stiffness",
                 "local_buckling_load_southwell", "global_buckling_load_southwell", "peak_axial_force",
                 "max_interpenetration", "tip_energy_release_rate")),
    "delamination_growth": ProbeKind(
        "a panel's delamination growth in the DEM windows (coupled): growth_left / growth_right, tip_mode_ratio, "
        "interface_dissipated (by decohesion: friction kept apart); qoi delamination_growth_left / _right, "
        "delamination_length_at_limit_load, "
        "growth_onset_load and its closed form (Hutchinson & Suo for the measured mode mix), "
        "dissipated_per_new_area, growth_reached_window_edge (panels)",
        {}, growth_series, growth_qoi, with_params=True,
        reports=("delamination_growth_left", "delamination_growth_right", "delamination_length_final",
                 "delamination_length_at_limit_load", "growth_onset_load", "growth_mode_ratio",
                 "growth_reached_window_edge", "dissipated_per_new_area", "interface_dissipated")),
    "literature_value": ProbeKind(
        "a value from a paper or a test, reported beside the run's as qoi NAME (not checked: a check compares)",
        {"value": Param(0.0, "the value (SI)"), "source": Param("", "where it comes from", kind="str")},
        lambda built, name, f: {}, lambda name, f, h, p: {name: f["value"]}, with_params=True,
        names=("{name}",)),
}


def qoi_names(kind: str, name: str) -> tuple[str, ...]:
    """The qoi a probe NAME of this kind reports (a trailing *: any ending)."""
    return tuple(q.format(name=name) for q in PROBES[kind].names) + PROBES[kind].reports


def _same_qoi(a: str, b: str) -> bool:
    """Whether two qoi names (a trailing * any ending) can be the same name."""
    pa, pb = a.rstrip("*"), b.rstrip("*")
    if a.endswith("*") and b.endswith("*"):
        return pa.startswith(pb) or pb.startswith(pa)
    return a == b or a.endswith("*") and b.startswith(pa) or b.endswith("*") and a.startswith(pb)


def refuse_clashing_qoi(probes: dict, recorded: set) -> None:
    """CaseError for a probe reporting a qoi another probe (or the run itself: recorded) reports:
    one of them would vanish from the run's qoi. probes: {name: kind}."""
    owned = [(q, name) for name, kind in probes.items() for q in qoi_names(kind, name)]
    owned += [(q, None) for q in sorted(recorded)]
    for i, (a, first) in enumerate(owned):
        for b, second in owned[i + 1:]:
            if first != second and _same_qoi(a, b):
                whose = f"probes.{second}'s (kind {probes[second]!r})" if second else "the run's own"
                raise CaseError(f"probes.{first} (kind {probes[first]!r}): its qoi {a.rstrip('*')!r} is also "
                                f"{whose}; allowed: another probe name (each qoi is reported once)")


def body_extent(p: dict) -> list[tuple[float, float]]:
    """(low, high) m of the modelled body along each axis (x along the span, then across the
    width in 3D, then through the thickness): the half or quarter about x = 0 (y = 0), a panel
    whole, a bonded beam's sheet below y (3D: z) = 0, a panel's bow beside its thickness."""
    from fem_region.materials import parse_layup
    shape = p["geometry.shape"]
    if p.get("geometry.laminate"):
        lam = f"laminates.{p['geometry.laminate']}"
        low, high = 0.0, len(parse_layup(p[f"{lam}.layup"])) * p[f"{lam}.ply_thickness"]
    else:
        low, high = 0.0, p["geometry.depth"]
    if shape.startswith("bonded_beam"):
        low = -next(v for k, v in p.items() if k.startswith("sheets.") and k.endswith(".thickness"))
    if shape == "panel":  # its bow and the sublaminate's bump move it off [0, H]
        bump = p["geometry.imperfection"] + max(v for k, v in p.items() if k.startswith("delaminations.")
                                                 and k.endswith(".imperfection"))
        low, high = low - bump * high, high * (1 + bump)
    along = p["geometry.span"] if shape == "panel" else 0.5 * (p.get("geometry.length") or p["geometry.span"])
    if shape in ("beam", "bonded_beam", "panel"):
        return [(0.0, along), (low, high)]
    across = 0.5 * (p["geometry.span"] if shape == "disc" else p["geometry.width"])
    return [(0.0, along), (0.0, across), (low, high)]


def refuse_points_outside(probes: dict, p: dict) -> None:
    """CaseError for a probe point (x, y[, z]) outside the modelled body, which the nearest node
    or particle would silently stand for, or a z on a 2D slice. probes: {name: kind}."""
    extent = body_extent(p) if any(f"probes.{n}.x" in p for n in probes) else []
    tol = 1e-9 * max((hi - lo for lo, hi in extent), default=0.0)
    shape = p["geometry.shape"]
    for name in probes:
        if f"probes.{name}.x" not in p:
            continue
        at = [p[f"probes.{name}.{axis}"] for axis in "xyz"]
        if len(extent) == 2 and at[2] != 0:
            raise CaseError(f"probes.{name}.z = {at[2]:g}: has no effect on a 2D slice (geometry.shape = {shape!r}); "
                            "allowed: 0, or leave it out")
        for i, (axis, v, (lo, hi)) in enumerate(zip("xyz", at, extent)):
            half = shape != "panel" and i < len(extent) - 1  # (a half or quarter model from its symmetry planes)
            if not lo - tol <= v <= hi + tol:
                raise CaseError(f"probes.{name}.{axis} = {v:g}: outside the modelled body (geometry.shape = {shape!r}"
                                f"{', from its symmetry plane' if half else ''}); allowed {lo:g} to {hi:g} [m]")
        if shape == "disc" and np.hypot(at[0], at[1]) > extent[0][1] + tol:
            raise CaseError(f"probes.{name}.x, y = {at[0]:g}, {at[1]:g}: outside the disc (radius {extent[0][1]:g} m); "
                            "allowed: x^2 + y^2 <= radius^2")


def series(study, built, p: dict) -> dict:
    out = {}
    for name, kind in study.layout.names["probes"].items():
        fields = section(p, f"probes.{name}")
        out.update(PROBES[kind].series(built, name, fields))
    return out


def qoi(study, p: dict, history: dict) -> dict:
    out = {}
    for name, kind in study.layout.names["probes"].items():
        fields = section(p, f"probes.{name}")
        if kind == "debonding":  # the fraction is of the sheet's length, the beam's
            fields["beam_length"] = p["geometry.length"] or p["geometry.span"]
        probe = PROBES[kind]
        if probe.with_params:
            out.update(probe.qoi(name, fields, history, p))
        elif kind == "interface_damage" or any(k == name or k.startswith(name + "_") for k in history):
            out.update(probe.qoi(name, fields, history))
    return out
