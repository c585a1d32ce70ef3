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

from ..params import Param
from .schema import section


@dataclass(frozen=True)
class ProbeKind:
    doc: str
    fields: dict[str, Param]
    series: Callable  # (built, name, fields) -> {series name: () -> float}
    qoi: Callable  # (name, fields, history) -> {qoi name: float}


def _point_series(built, name, f):
    """Displacement component of the particle (or, without one, the FEM node) nearest (x, y)."""
    comp, sign = "xy".index(f["component"][-1]), -1.0 if f["component"].startswith("-") else 1.0
    at = np.array([f["x"], f["y"]])
    lat = built.lattice
    if lat is not None and np.min(np.linalg.norm(lat.x[:, :2] - at, axis=1)) <= lat.d:
        i = int(np.argmin(np.linalg.norm(lat.x[:, :2] - at, axis=1)))
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
    """Force of the impactor on the structure (whole width), along -y (N); its velocity (m/s)."""
    imp, w = built.impactors[f["impactor"]], built.width_factor
    if hasattr(imp, "imp"):  # on particles: the force the particles exert on it
        return {name: lambda: float(imp.force[1] * w), f"{f['impactor']}_velocity": lambda: float(imp.imp.v[1])}
    return {name: lambda: float(imp.a[1] * imp.mass * w), f"{f['impactor']}_velocity": lambda: float(imp.v[1])}


def _interfaces(built):
    """(row of each interlaminar bond's lower particle, the distinct rows, length weights m):
    bonds weighted by the beam length they stand for, both halves; the tied or clamped column
    none (it is the FEM's face or the support)."""
    lat = built.lattice
    first = lat.inter_pairs[:, 0]
    row, col = lat.row[first], lat.column[first]
    weight = np.where(col == 0, 0.5, 1.0) * lat.d * 2
    if built.end_held:
        weight[col == lat.column.max()] = 0.0
    return row, np.unique(row), weight


def _delamination_series(built, name, f):
    """Per ply interface k (bottom up): debonded length and damaged (d > 0) length (m)."""
    if built.inter is None:
        return {}
    inter = built.inter
    row, rows, weight = _interfaces(built)
    out = {}
    for k, r in enumerate(rows):
        sel = row == r
        out[f"{name}_length_{k}"] = lambda sel=sel: float(weight[sel] @ inter.failed()[sel])
        out[f"damaged_interface_length_{k}"] = lambda sel=sel: float(weight[sel] @ (inter.damage[sel] > 0))
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
    lat, inter = built.lattice, built.inter
    edge = lat.column[lat.inter_pairs[:, 0]] >= lat.column.max() - f["columns"]
    return {name: lambda: float(inter.damage[edge].max()) if edge.any() else 0.0}


def _max_qoi(name, f, h):
    return {name: float(np.max(h[name]))} if name in h else {}


_COMPONENTS = ("x", "y", "-x", "-y")
PROBES: dict[str, ProbeKind] = {
    "point_displacement": ProbeKind(
        "displacement of the material point nearest (x, y); qoi peak_NAME, time_of_peak_NAME",
        {"x": Param(0.0, "x of the point", unit="m"), "y": Param(0.0, "y of the point", unit="m"),
         "component": Param("-y", "component (a leading - reverses it)", kind="str", choices=_COMPONENTS)},
        _point_series, _peak_qoi),
    "contact_force": ProbeKind(
        "force between an impactor and the structure (whole width), and the impactor's velocity; qoi peak_NAME",
        {"impactor": Param("", "the impactor (an [impactors.*] name)", kind="str")},
        _contact_series, lambda name, f, h: {f"peak_{name}": float(np.max(h[name]))}),
    "delamination": ProbeKind(
        "debonded (NAME_length_K) and damaged (damaged_interface_length_K) length of each ply interface K, "
        "bottom up, whole beam; qoi: their final values",
        {}, _delamination_series, _final_qoi(("{name}_length_", "damaged_interface_length_"))),
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
