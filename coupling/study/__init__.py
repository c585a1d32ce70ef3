"""A study written as a case file: the schema (schema.py), one assembler (assemble.py), and the
registries of what no schema can say, probes (probes.py) and closed forms (closed_forms.py).

A :class:`Study` stands where a scene module stands (NAME, DESCRIPTION, MODES, PARAMETERS,
build, evaluate, plot), so the rest of the program (run, resume, bench, compare, params)
treats both alike.
"""
from __future__ import annotations

import numpy as np

from ..params import CaseError
from . import closed_forms, fields, probes
from .assemble import beam, plate
from .schema import MODES, document, parameters

__all__ = ["Study", "document_schema", "renamed"]


class Study:
    """A case file's study. ``PARAMETERS``: dotted key -> Param, the file's values as defaults."""

    def __init__(self, name: str, data: dict, where: str):
        self.NAME = name
        self.PARAMETERS, self.layout = parameters(data, where, probes.PROBES, closed_forms.CLOSED_FORMS)
        meta = self.layout.meta
        self.DESCRIPTION = str(meta.get("description", ""))
        modes = meta.get("modes", list(MODES))
        if not isinstance(modes, list) or not modes or any(m not in MODES for m in modes):
            raise CaseError(f"case.modes = {modes!r}: allowed a list of {', '.join(MODES)}")
        self.MODES = tuple(modes)
        t_end = meta.get("t_end")
        if isinstance(t_end, bool) or not isinstance(t_end, (int, float)) or not t_end > 0:
            raise CaseError(f"case.t_end = {t_end!r}: required in {where}; allowed a number > 0 [s]")
        self.t_end = float(t_end)
        ref = meta.get("reference_elements", 0)
        if isinstance(ref, bool) or not isinstance(ref, int) or ref < 0:
            raise CaseError(f"case.reference_elements = {ref!r}: allowed an integer >= 0 (0: none)")
        self.reference_elements = ref
        shape = self.PARAMETERS["geometry.shape"].default
        want = {"beam": ("x", "quad4"), "beam_3d": ("xy", "hex8"), "plate": ("xy", "hex8")}[shape]
        at = {"plate": "edges"}.get(shape, "ends")
        for name_, kind in self.layout.names["supports"].items():
            if kind != at:
                raise CaseError(f"supports.{name_}.at = {kind!r}: geometry.shape = {shape!r} is supported at its {at}")
        shapes = {"plate": ("sphere",)}.get(shape, ("cylinder",))
        for name_, kind in self.layout.names["impactors"].items():
            if kind not in shapes:
                raise CaseError(f"impactors.{name_}.shape = {kind!r}: geometry.shape = {shape!r} takes {shapes[0]!r}")
        for key, value in zip(("geometry.symmetry", "mesh.element"), want):
            if self.PARAMETERS[key].default != value:
                raise CaseError(f"{key} = {self.PARAMETERS[key].default!r}: geometry.shape = {shape!r} takes {value!r}")
        if shape == "beam" and "elements_width" in data.get("mesh", {}):
            raise CaseError("mesh.elements_width: has no effect on a beam slice; allowed: leave it out, or "
                            "geometry.shape = 'beam_3d'")
        for name_, kind in self.layout.names["checks"].items():
            qoi = self.PARAMETERS[f"checks.{name_}.qoi"].default
            if not any(p in qoi for p in self.layout.names["probes"]):
                raise CaseError(f"checks.{name_}.qoi = {qoi!r}: no probe of this study reports it; allowed a qoi of "
                                f"the probes {', '.join(self.layout.names['probes']) or '(none declared)'}")

    def structural(self, key: str) -> bool:
        """A key that says what a table is (its kind or shape): fixed by the file, not by --set."""
        from .schema import KIND_KEY
        table, _, rest = key.partition(".")
        return table in KIND_KEY and rest.count(".") == 1 and rest.endswith("." + KIND_KEY[table][0]) \
            or key in ("geometry.shape", "zone.shape", "geometry.symmetry")

    def build(self, p: dict, mode: str, dem: str):
        sim, built = (plate if p["geometry.shape"] == "plate" else beam)(self, p, mode, dem)
        sim.probes.update(probes.series(self, built, p))
        size = float(built.fem_elements + (built.lattice.n if built.lattice is not None else 0))
        sim.probes["model_size"] = lambda: size  # elements + particles
        if built.lattice is not None:
            _damage_snapshots(sim, built)
        sim.fields = fields.frames(built)  # the whole structure (study/fields.py)
        return sim

    def evaluate(self, p: dict, history: dict, mode: str):
        qoi = probes.qoi(self, p, history)
        qoi["model_size"] = float(history["model_size"][-1])
        if self.reference_elements:
            qoi["model_size_vs_reference"] = qoi["model_size"] / self.reference_elements
        return qoi, closed_forms.evaluate(self, p, qoi, history)

    def plot(self, p: dict, history: dict, qoi: dict, plots_dir):
        from . import plots
        plots.histories(self, p, history, qoi, plots_dir)
        plots.damage(history, plots_dir)


def _damage_snapshots(sim, built) -> None:
    """Damage pictures at the first sixth of the run and at its end."""
    lat, intra, inter, backend = built.lattice, built.intra, built.inter, built.backend
    in_90 = (np.array(built.lam.angles)[lat.ply] == 90).astype(float)
    t_end = sim.n_steps * sim.dt
    far = _far_field(built)
    if built.dim == 3:
        j = lat.index[:, 1].astype(float)
        for t_snap in (t_end / 6, t_end):
            sim.snapshots[f"damage_{round(t_snap * 1e6)}us"] = (t_snap, lambda: {
                **far(), "x": backend.positions(), "width_index": j, "in_90": in_90,
                "intra_damage": intra.softened(), "inter_damage": inter.damage.copy(),
                "intra_pairs": intra.pairs.astype(float), "inter_pairs": inter.pairs.astype(float)})
        return
    for t_snap in (t_end / 6, t_end):
        sim.snapshots[f"damage_{round(t_snap * 1e6)}us"] = (t_snap, lambda: {
            **far(), "x": backend.positions(), "intra_failed": intra.failed().astype(float),
            "inter_failed": inter.failed().astype(float), "inter_damage": inter.damage.copy(),
            "intra_damage": intra.damage.copy(), "intra_pairs": intra.pairs.astype(float),
            "inter_pairs": inter.pairs.astype(float), "in_90": in_90})


def _far_field(built):
    """() -> the FEM's deformed nodes and its element edges along the axes, for the damage
    pictures of the whole structure (empty without a FEM)."""
    dyn = built.dyn
    if dyn is None:
        return lambda: {}
    X, conn = dyn.region.X, dyn.region.mesh.t.T
    a, b = np.triu_indices(conn.shape[1], 1)
    edges = np.stack([conn[:, a], conn[:, b]], axis=-1).reshape(-1, 2)
    along_axis = (np.abs(X[edges[:, 0]] - X[edges[:, 1]]) > 1e-12 * np.ptp(X)).sum(axis=1) == 1
    edges = np.unique(np.sort(edges[along_axis], axis=1), axis=0).astype(float)
    dim = dyn.region.dim
    X0 = np.pad(X, ((0, 0), (0, 3 - dim)))
    return lambda: {"fem_x": np.pad(X + dyn.state.u, ((0, 0), (0, 3 - dim))), "fem_x0": X0, "fem_edges": edges}


def document_schema() -> str:
    return document(probes.PROBES, closed_forms.CLOSED_FORMS)


def renamed(key: str, study: Study) -> str | None:
    """The study key that replaced a scene module's key, or None."""
    names = study.layout.names
    one = lambda c: next(iter(names[c]), None)
    tail = key.split(".", 1)[-1]
    if key.startswith(("material.", "strength.", "fracture.")) and one("materials"):
        lam = study.PARAMETERS["geometry.laminate"].default
        return f"materials.{study.PARAMETERS[f'laminates.{lam}.material'].default}.{tail}"
    if key.startswith("interface.") and one("interfaces"):
        return f"interfaces.{one('interfaces')}.{tail}"
    if key.startswith("impactor.") and one("impactors"):
        return f"impactors.{one('impactors')}.{tail}"
    return {"dem.half_width": "zone.half_width", "dem.plies_per_row": "zone.plies_per_particle",
            "geometry.half_span": "geometry.span (the whole span)", "laminate.layup": f"laminates.{one('laminates')}.layup",
            "laminate.ply_thickness": f"laminates.{one('laminates')}.ply_thickness"}.get(key)
