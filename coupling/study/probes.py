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

from ..params import CaseError, Param
from .schema import section


@dataclass(frozen=True)
class ProbeKind:
    doc: str
    fields: dict[str, Param]
    series: Callable  # (built, name, fields) -> {series name: () -> float}
    qoi: Callable  # (name, fields, history) -> {qoi name: float}


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
    debonded and damaged (d > 0) lengths, area / width (m). The tied or clamped column is not
    counted (it is the FEM's face or the support)."""
    if built.inter is None:
        return {}
    inter, W = built.inter, built.p["geometry.width"]
    first = inter.pairs[:, 0]
    layer = built.lattice.x[first, built.dim - 1]
    area = built.width_factor * inter.area
    if built.end_held:
        area = np.where(built.column[first] == built.column.max(), 0.0, area)
    out = {}
    for k, z in enumerate(np.unique(layer)):
        sel = layer == z
        out[f"{name}_area_{k}"] = lambda sel=sel: float(area[sel] @ inter.failed()[sel])
        out[f"{name}_length_{k}"] = lambda sel=sel: float(area[sel] @ inter.failed()[sel]) / W
        out[f"damaged_interface_length_{k}"] = lambda sel=sel: float(area[sel] @ (inter.damage[sel] > 0)) / W
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
    """The largest interlaminar damage in the last ``columns`` columns before the zone's edge:
    near 1, the damage reached the edge and the zone must widen."""
    if built.inter is None:
        return {}
    inter, column = built.inter, built.column
    edge = column[inter.pairs[:, 0]] >= column.max() - f["columns"]
    return {name: lambda: float(inter.damage[edge].max()) if edge.any() else 0.0}


def _max_qoi(name, f, h):
    return {name: float(np.max(h[name]))} if name in h else {}


_COMPONENTS = ("x", "y", "z", "-x", "-y", "-z")
PROBES: dict[str, ProbeKind] = {
    "point_displacement": ProbeKind(
        "displacement of the material point nearest (x, y); qoi peak_NAME, time_of_peak_NAME",
        {"x": Param(0.0, "x of the point", unit="m"), "y": Param(0.0, "y of the point", unit="m"),
         "z": Param(0.0, "z of the point (3D)", unit="m"),
         "component": Param("-y", "component (a leading - reverses it); z in 3D", kind="str", choices=_COMPONENTS)},
        _point_series, _peak_qoi),
    "contact_force": ProbeKind(
        "force between an impactor and the structure (whole width), and the impactor's velocity; qoi peak_NAME",
        {"impactor": Param("", "the impactor (an [impactors.*] name)", kind="str")},
        _contact_series, lambda name, f, h: {f"peak_{name}": float(np.max(h[name]))}),
    "delamination": ProbeKind(
        "debonded area (NAME_area_K), debonded and damaged lengths (NAME_length_K, damaged_interface_length_K: "
        "area / width) of each ply interface K, bottom up, whole structure; qoi: their final values",
        {}, _delamination_series, _final_qoi(("{name}_area_", "{name}_length_", "damaged_interface_length_"))),
    "ply_cracks": ProbeKind(
        "failed intralaminar bonds in the plies of one angle (or all); qoi: the final count",
        {"angle": Param("90", "ply angle, or all", kind="str", choices=("0", "90", "all"))},
        _ply_crack_series, _final_qoi(("{name}",))),
    "zone_edge_damage": ProbeKind(
        "largest interlaminar damage near the zone's edge (1: the zone is too narrow); qoi: its maximum",
        {"columns": Param(2, "particle columns counted from the edge", kind="int", low=0, high=100)},
        _zone_edge_series, _max_qoi),
}


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
        if any(k == name or k.startswith(name + "_") for k in history):
            out.update(PROBES[kind].qoi(name, fields, history))
    return out
