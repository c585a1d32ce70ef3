"""A study written as a case file: the schema (schema.py), one assembler (assemble.py), and the
registries of what no schema can say, probes (probes.py) and closed forms (closed_forms.py).

A :class:`Study` stands where a scene module stands (NAME, DESCRIPTION, MODES, PARAMETERS,
build, evaluate, plot), so the rest of the program (run, resume, bench, compare, params)
treats both alike.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np

from ..params import CaseError
from . import closed_forms, fields, probes
from .assemble import beam, plate
from .block import block
from .bonded import bonded_beam
from .disc import disc
from .panel import panel as assemble_panel
from .growth import Growth
from .placement import estimate, place
from .schema import BONDED, KIND_KEY, LAMINATED, MODES, document, parameters, section

__all__ = ["Study", "document_schema", "renamed"]


class Study:
    """A case file's study. ``PARAMETERS``: dotted key -> Param, the file's values as defaults."""

    def __init__(self, name: str, data: dict, where: str):
        self.NAME = name
        self.PARAMETERS, self.layout = parameters(data, where, probes.PROBES, closed_forms.CLOSED_FORMS)
        self.ranged = frozenset(data.get("ranges", {}))  # keys whose [ranges] the tests verify
        if self.ranged:  # the help says which of the specimen's keys are verified only at the file's value
            self.PARAMETERS.update({k: replace(v, doc=v.doc + " (verified at this value; another runs, warned)")
                                    for k, v in self.PARAMETERS.items()
                                    if k.startswith(SPECIMEN) and k not in self.ranged and not self.structural(k)
                                    and (v.choices is None or len(v.choices) > 1)})
        meta = self.layout.meta
        self.DESCRIPTION = str(meta.get("description", ""))
        shape = self.PARAMETERS["geometry.shape"].default
        modes = meta.get("modes", ["fem", "coupled"] if shape == "panel" else list(MODES))
        if not isinstance(modes, list) or not modes or any(m not in MODES for m in modes):
            raise CaseError(f"case.modes = {modes!r}: allowed a list of {', '.join(MODES)}")
        self.MODES = tuple(modes)
        t_end = meta.get("t_end")
        if shape == "panel":  # a panel's run lasts its load's ramp
            if t_end is not None:
                raise CaseError(f"case.t_end = {t_end!r}: a panel's run lasts its load's duration_periods; allowed: "
                                "leave it out (clock.t_end cuts a run short)")
            if "dem" in self.MODES:
                raise CaseError(f"case.modes = {modes!r}: a panel runs in coupled and fem modes; allowed: leave dem out")
            t_end = np.inf
        elif isinstance(t_end, bool) or not isinstance(t_end, (int, float)) or not t_end > 0:
            raise CaseError(f"case.t_end = {t_end!r}: required in {where}; allowed a number > 0 [s]")
        elif isinstance(data.get("clock"), dict) and "t_end" in data["clock"]:  # one duration per file
            raise CaseError(f"clock.t_end = {data['clock']['t_end']!r}: the file's duration is case.t_end = {t_end!r} "
                            f"in {where}; allowed: one of them (clock.t_end with --set cuts a run short)")
        self.t_end = float(t_end)
        ref = meta.get("reference_elements", 0)
        if isinstance(ref, bool) or not isinstance(ref, int) or ref < 0:
            raise CaseError(f"case.reference_elements = {ref!r}: allowed an integer >= 0 (0: none)")
        self.reference_elements = ref
        self.no_fracture_reference = meta.get("no_fracture_reference", False)
        if not isinstance(self.no_fracture_reference, bool):
            raise CaseError(f"case.no_fracture_reference = {self.no_fracture_reference!r}: allowed true or false")
        self._no_fracture, self._placed = {}, {}
        self.growth = None  # the last coupled run's growing zone (study/growth.py)
        self._shape_tables(shape, data)
        _one_each(self.layout.names)
        _curve_or_file(data.get("loads", {}), where)
        probes.refuse_clashing_qoi(self.layout.names["probes"], self._recorded())
        want = {"beam": ("x", "quad4"), "beam_3d": ("xy", "hex8"), "plate": ("xy", "hex8"), "disc": ("xy", "hex8"),
                "bonded_beam": ("x", "quad4"), "bonded_beam_3d": ("xy", "hex8"), "panel": ("none", "quad4"),
                "block": ("xy", "hex8")}[shape]
        at = {"plate": "edges", "disc": "rim", "block": "bottom"}.get(shape, "ends")
        for name_, kind in self.layout.names["supports"].items():
            if kind != at:
                raise CaseError(f"supports.{name_}.at = {kind!r}: geometry.shape = {shape!r} is supported at its {at}")
        shapes = {"plate": ("sphere", "rod"), "block": ("sphere", "rod"), "disc": ("rod",), "bonded_beam": (),
                  "bonded_beam_3d": (), "panel": (),
                  "beam": ("cylinder", "flat_punch")}.get(shape, ("cylinder",))
        for name_, kind in self.layout.names["impactors"].items():
            if kind not in shapes:
                raise CaseError(f"impactors.{name_}.shape = {kind!r}: geometry.shape = {shape!r} takes "
                                f"{repr(shapes[0]) if shapes else 'no impactor (a [loads.*] instead)'}")
        for key, value in zip(("geometry.symmetry", "mesh.element"), want):
            if self.PARAMETERS[key].default != value:
                raise CaseError(f"{key} = {self.PARAMETERS[key].default!r}: geometry.shape = {shape!r} takes {value!r}")
        if shape in ("beam", "bonded_beam") and "elements_width" in data.get("mesh", {}):  # (before the pop)
            raise CaseError(f"mesh.elements_width: has no effect on a slice; allowed: leave it out, or "
                            f"geometry.shape = '{shape}_3d'")
        for name_, kind in self.layout.names["checks"].items():
            if kind in FORM_NEEDS:  # a closed form of one shape and one kind of loading
                shape_, needs = FORM_NEEDS[kind]
                given = {**{k: "impactor" for k in self.layout.names["impactors"].values()},
                         **{k: "load" for k in self.layout.names["loads"].values()}}
                if shape != shape_ or not given or not all(k == needs or given[k] == needs for k in given):
                    raise CaseError(f"checks.{name_}.closed_form = {kind!r}: for geometry.shape = {shape_!r} under "
                                    f"{FORM_WORDS[needs]}; allowed: another check")
            qoi = self.PARAMETERS[f"checks.{name_}.qoi"].default
            kinds = self.layout.names["probes"]
            if not any(p in qoi or qoi in probes.PROBES[k].reports for p, k in kinds.items()):
                raise CaseError(f"checks.{name_}.qoi = {qoi!r}: no probe of this study reports it; allowed a qoi of "
                                f"the probes {', '.join(self.layout.names['probes']) or '(none declared)'}")

    def _shape_tables(self, shape: str, data: dict) -> None:
        """The tables and keys a shape takes: a laminated body needs a laminate, a bonded beam its
        material, depth, one sheet and one load; keys of the other kind are refused."""
        P, names = self.PARAMETERS, self.layout.names
        given = lambda table, key: key in data.get(table, {})
        if shape != "panel" and names["delaminations"]:
            raise CaseError(f"[delaminations.{next(iter(names['delaminations']))}]: geometry.shape = {shape!r} takes "
                            "none (a panel's)")
        want_load = {"panel": "shortening", "block": "pressure", "plate": "pressure"}.get(shape, "patch")
        for name_, kind in names["loads"].items():
            if kind != want_load:
                raise CaseError(f"loads.{name_}.kind = {kind!r}: geometry.shape = {shape!r} takes {want_load!r}")
        if shape == "panel":
            for table in ("sheets", "impactors"):
                if names.get(table):
                    raise CaseError(f"[{table}.{next(iter(names[table]))}]: geometry.shape = 'panel' takes none")
            for table in ("delaminations", "loads", "supports"):
                if len(names[table]) != 1:
                    raise CaseError(f"[{table}.NAME]: geometry.shape = 'panel' takes exactly one; given "
                                    f"{len(names[table])}")
            for name_, kind in names["materials"].items():
                if kind != "ply":
                    raise CaseError(f"materials.{name_}.kind = {kind!r}: geometry.shape = 'panel' takes ply materials")
            # the FEM's crack is the delamination's (no far-field cohesive interfaces): not a panel's keys
            for table, field in (("laminates", "far_field_interfaces"), ("interfaces", "penalty")):
                for name_ in names[table]:
                    if field in data[table][name_]:
                        raise CaseError(f"{table}.{name_}.{field}: has no effect on geometry.shape = 'panel'; allowed: "
                                        "leave it out")
                    P.pop(f"{table}.{name_}.{field}", None)
            return
        if shape == "disc":
            need = [("geometry", "laminate"), ("zone", "particle_size")]
            refuse = [("geometry", k) for k in ("material", "depth", "length", "width")] + \
                [("zone", "plies_per_particle"), ("mesh", "elements_width"), ("mesh", "element_ratio")] + \
                [("mesh", k) for k in ("growth", "max_size", "elements_per_run")]
            refuse_tables = ("sheets", "loads")
        elif shape == "block":
            need = [("geometry", "material"), ("geometry", "depth"), ("geometry", "width"), ("zone", "particle_size")]
            refuse = [("geometry", k) for k in ("laminate", "length")] + \
                [("zone", k) for k in ("plies_per_particle", "ply_failure")] + \
                [("mesh", k) for k in ("growth", "max_size", "elements_per_ply", "elements_per_run")]
            refuse_tables = ("sheets", "laminates")
        elif shape in LAMINATED:
            need = [("geometry", "laminate"), ("geometry", "width")]
            refuse = [("geometry", k) for k in ("material", "depth", "length")] + [("zone", "particle_size")] + \
                [("mesh", k) for k in ("growth", "max_size", "elements_per_ply")] + \
                ([("mesh", "elements_per_run")] if shape == "plate" else [])
            refuse_tables = ("sheets",) if shape == "plate" else ("sheets", "loads")
        else:
            need = [("geometry", "material"), ("geometry", "depth"), ("geometry", "width"), ("zone", "particle_size")]
            refuse = [("geometry", "laminate"), ("zone", "plies_per_particle"), ("zone", "ply_failure"),
                      ("mesh", "elements_along"), ("mesh", "element_ratio"), ("mesh", "elements_per_ply"),
                      ("mesh", "elements_per_run")]
            refuse_tables = ("laminates", "impactors")
        for table, key in need:
            if not given(table, key) or P[f"{table}.{key}"].default in (0, ""):
                raise CaseError(f"{table}.{key}: required for geometry.shape = {shape!r} ({P[f'{table}.{key}'].doc})")
        for table, key in refuse:
            if given(table, key):
                raise CaseError(f"{table}.{key}: has no effect on geometry.shape = {shape!r}; allowed: leave it out")
        for table in refuse_tables:
            if names.get(table):
                raise CaseError(f"[{table}.{next(iter(names[table]))}]: geometry.shape = {shape!r} takes none")
        if shape in ("beam", "bonded_beam"):
            refuse.append(("mesh", "elements_width"))
        growing = ("beam", "beam_3d", "plate", "disc") + BONDED  # a zone grown during the run about the centre
        if shape not in ("beam", "beam_3d"):  # a zone about x = 0 placed from the estimate: beams'
            refuse += [("zone", "placement")] + ([] if shape in growing else [("zone", "grow_at")]) + \
                ([] if shape in ("plate", "block") + growing else [("zone", "margin")])
        footprint = P["zone.shape"].default if "zone.shape" in P else "box"
        if footprint in ("cylinder", "impactor") and shape not in ("plate", "block"):
            raise CaseError(f"zone.shape = {footprint!r}: a plate's or a block's footprint; allowed for {shape!r}: box")
        auto = P["zone.placement"].default == "auto" if "zone.placement" in P else False
        if shape != "panel" and P["zone.half_width"].default == 0 and not (footprint == "impactor" or auto):
            raise CaseError(f"zone.half_width: required for geometry.shape = {shape!r} with zone.shape = "
                            f"{footprint!r}; allowed: {P['zone.half_width'].allowed()}")
        if shape in ("plate", "block") and len(names["impactors"]) + len(names["loads"]) != 1:
            raise CaseError(f"[impactors.NAME] or [loads.NAME]: a {shape} takes exactly one, on its top face's "
                            f"centre; given {len(names['impactors']) + len(names['loads'])}")
        if shape not in growing:  # a zone grown during the run: the beams', bonded beams' and plates' so far
            for key in ("grow", "grow_to", "conversion", "grow_every"):
                if given("zone", key):
                    raise CaseError(f"zone.{key}: a zone grown during the run is built for the beams and bonded beams "
                                    f"(geometry.shape = {', '.join(repr(s) for s in growing)}) so far; allowed for "
                                    f"{shape!r}: leave it out")
                refuse.append(("zone", key))
        if shape not in ("beam", "beam_3d", "block"):
            if given("mesh", "file"):
                raise CaseError(f"mesh.file: read for geometry.shape = 'beam', 'beam_3d' or 'block' so far; allowed for "
                                f"{shape!r}: leave it out")
            refuse.append(("mesh", "file"))
        elif given("mesh", "file"):
            for key in ("elements_along", "element_ratio", "elements_per_run") + (("elements_width",) if
                                                                                  shape != "beam" else ()):
                if given("mesh", key):
                    raise CaseError(f"mesh.{key}: has no effect with mesh.file; allowed: leave it out")
                P.pop(f"mesh.{key}", None)
        for table, key in refuse:  # not this shape's: not listed, not settable
            P.pop(f"{table}.{key}", None)
        if shape in BONDED:
            for table in ("sheets", "loads"):
                if len(names[table]) != 1:
                    raise CaseError(f"[{table}.NAME]: geometry.shape = {shape!r} takes exactly one; given "
                                    f"{len(names[table])}")
            kinds = {n: k for n, k in names["materials"].items()}
            body, sheet = P["geometry.material"].default, P[f"sheets.{next(iter(names['sheets']))}.material"].default
            if kinds.get(body) != "isotropic":
                raise CaseError(f"geometry.material = {body!r}: a bonded beam's body is an isotropic material")
            if kinds.get(sheet) != "ply":
                raise CaseError(f"sheets.{next(iter(names['sheets']))}.material = {sheet!r}: a sheet is a ply material")
        elif shape == "block":
            body = P["geometry.material"].default
            if names["materials"].get(body) != "isotropic":
                raise CaseError(f"geometry.material = {body!r}: a block's body is an isotropic material")
        else:
            for name_, kind in names["materials"].items():
                if kind != "ply":
                    raise CaseError(f"materials.{name_}.kind = {kind!r}: geometry.shape = {shape!r} takes ply materials")

    def resolve_files(self, p: dict, folder) -> None:
        """Files a study reads (load curves, a mesh), relative to its case file's folder; a load
        file's rows checked as an inline curve's."""
        loads = [f"loads.{n}.file" for n in self.layout.names["loads"]]
        resolve_files(p, loads + ["mesh.file"], folder)
        for key in loads:
            if p.get(key):
                load_file_rows(key, p[key])

    def refuse_inconsistent(self, p: dict, given: frozenset = frozenset()) -> None:
        """CaseError for resolved values that contradict each other or change nothing; given: the
        keys of --set (a value off the case file's is the user's setting)."""
        changed = {k for k in given if k in self.PARAMETERS and p[k] != self.PARAMETERS[k].default}
        for name in self.layout.names["loads"]:
            curve, file = f"loads.{name}.curve", f"loads.{name}.file"
            if curve in changed and p.get(file):  # (the file is read instead of the curve)
                raise CaseError(f"{curve} = {[list(r) for r in p[curve]]}: has no effect with {file} = {p[file]!r}; "
                                f"allowed: leave it out, or the curve in the case file instead of its file")
        for name in (n for n, kind in self.layout.names["checks"].items() if kind == "test_between"):
            low, high = p[f"checks.{name}.low"], p[f"checks.{name}.high"]
            if low > high:
                raise CaseError(f"checks.{name}.low = {low:g}: above checks.{name}.high = {high:g} (no value could "
                                "pass); allowed: low <= high")
        _hourglass(p, changed)
        probes.refuse_points_outside(self.layout.names["probes"], p)

    def _recorded(self) -> set:
        """The qoi a run records besides its probes' (a probe reporting one of them would vanish)."""
        forms = [closed_forms.CLOSED_FORMS[k].reference_qoi for k in self.layout.names["checks"].values()]
        return {"model_size", "model_size_vs_reference"} | {q + end for q in forms if q for end in ("", "_upper")}

    def no_fracture_history(self, p: dict) -> dict:
        """The history of this study's all-FEM twin (no fracture), run once per parameter set:
        the reference of the cracking checks and of no_fracture_reference."""
        from ..simulation import run_clock
        key = _physics_key(p)
        if key not in self._no_fracture:
            q = dict(p, **{"clock.dt": 0.0, "output.field_frames": 0})
            self._no_fracture[key] = run_clock(self.build(q, "fem", ""))["history"]
        return self._no_fracture[key]

    def structural(self, key: str) -> bool:
        """A key that says what a table is (its kind or shape): fixed by the file, not by --set."""
        from .schema import KIND_KEY
        table, _, rest = key.partition(".")
        return table in KIND_KEY and rest.count(".") == 1 and rest.endswith("." + KIND_KEY[table][0]) \
            or key in ("geometry.shape", "zone.shape", "geometry.symmetry")

    def placement(self, p: dict, mode: str):
        """The zone placed from the all-FEM estimate (zone.placement = "auto", coupled mode), once
        per parameter set; None otherwise."""
        if mode != "coupled" or p.get("zone.placement", "box") != "auto":
            return None
        # the estimate (an all-FEM run) once per physics, whatever the placement's own keys
        key = tuple(kv for kv in _physics_key(p) if kv[0] not in PLACEMENT_KEYS)
        if key not in self._placed:
            self._placed[key] = estimate(self, p)
        return place(self, p, self._placed[key])

    def changed(self, p: dict) -> list[str]:
        """The keys of the specimen (its materials, geometry, loads, ...) that ``p`` sets off the
        case file's values, sorted."""
        return sorted(k for k, param in self.PARAMETERS.items()
                      if k.startswith(SPECIMEN) and k in p and p[k] != param.default)

    def specimen_warnings(self, p: dict) -> list[str]:
        """What a run off the case file's specimen should know: changes outside the verified
        [ranges] (its checks were never verified there), test data not compared."""
        changed, out = self.changed(p), []
        loose = [k for k in changed if k not in self.ranged]
        if self.ranged and loose:
            out.append(f"not verified: {', '.join(f'{k} = {p[k]!r}' for k in loose)} (off the case file's value; "
                       "the checks are verified over the keys of its [ranges], listed by femdem params)")
        data = [n for n, kind in self.layout.names["checks"].items() if closed_forms.CLOSED_FORMS[kind].specimen]
        if changed and data:
            out.append(f"checks {', '.join(data)} not compared: their test data are the case file's specimen's, and "
                       f"this run changes {', '.join(changed)}")
        return out

    def build(self, p: dict, mode: str, dem: str, start=None):
        """The Simulation of ``p`` in ``mode`` on engine ``dem``; start: the state a grown zone's
        coupled model continues from (study/growth.py), None for a run from rest."""
        sim, built = self.assemble(p, mode, dem, start)
        sim.warnings += [w for w in self.specimen_warnings(p) if w not in sim.warnings]
        if mode == "coupled":  # (an all-FEM twin built meanwhile leaves the coupled run's record)
            self.growth = Growth(self, p, dem, built, sim) if p.get("zone.grow") else None
        return sim

    def assemble(self, p: dict, mode: str, dem: str, start=None):
        """(Simulation, Built) of ``p``: the participants, the probes and the fields."""
        assemble = {"plate": plate, "disc": disc, "bonded_beam": bonded_beam, "bonded_beam_3d": bonded_beam,
                    "panel": assemble_panel, "block": block}
        if p.get("zone.conversion") == "release" and not (p.get("zone.grow") and
                                                          p["geometry.shape"] in ("beam", "beam_3d")):
            raise CaseError("zone.conversion = 'release': seeded particles are built for a growing zone (zone.grow = "
                            "true) of a laminated beam (geometry.shape = 'beam' or 'beam_3d'); allowed here: rebuild")
        placed = self.placement(p, mode)
        if placed is not None:
            p = dict(p, **{"zone.half_width": placed.half_width})
        shape = assemble.get(p["geometry.shape"], beam)
        sim, built = shape(self, p, mode, dem, start) if start is not None else shape(self, p, mode, dem)
        if placed is not None:
            sim.warnings += placed.warnings
        sim.probes.update(probes.series(self, built, p))
        size = float(built.fem_elements + (built.lattice.n if built.lattice is not None else built.particles))
        sim.probes["model_size"] = lambda: size  # elements + particles
        if built.lattice is not None:
            _damage_snapshots(sim, built)
        if p["geometry.shape"] != "panel":  # (a panel keeps its participants' frames: FEM and windows)
            sim.fields = fields.frames(built)  # the whole structure (study/fields.py)
        return sim, built

    def evaluate(self, p: dict, history: dict, mode: str):
        qoi = probes.qoi(self, p, history)
        qoi["model_size"] = float(history["model_size"][-1])
        if self.no_fracture_reference and mode != "fem":
            ref = self.no_fracture_history(p)
            history["no_fracture.time"] = ref["time"]  # saved with the history, drawn by the plots
            for name, kind in self.layout.names["probes"].items():
                if kind == "point_displacement" and name in ref:
                    history[f"no_fracture.{name}"] = ref[name]
                    qoi[f"peak_{name}_no_fracture"] = float(np.max(ref[name]))
                    still = qoi[f"peak_{name}_no_fracture"]  # (0 in a run too short to move: no change to speak of)
                    qoi[f"{name}_change_by_fracture"] = qoi[f"peak_{name}"] / still - 1 if still else float("nan")
        placed = self.placement(p, mode)
        if placed is not None:
            qoi.update(placed.qoi())
        if mode == "coupled" and p.get("zone.grow") and self.growth is not None:
            qoi.update(self.growth.qoi())
            history.update(self.growth.history())  # saved with the history
        if self.reference_elements:
            qoi["model_size_vs_reference"] = qoi["model_size"] / self.reference_elements
        return qoi, closed_forms.evaluate(self, p, qoi, history)

    def run_warnings(self, p: dict, history: dict, qoi: dict, mode: str) -> list[str]:
        """What a finished run should say beside its qoi: a point_displacement probe whose peak a
        check judges and which is the run's last sample (probes.peak_at_end: a peak still rising
        at the end is no peak; a probe no check reads, e.g. the CFRP beam's deflection under its
        rising load, is a history, not a peak); in coupled mode, a far_field_failure probe whose
        index reached 1 (damage the FEM cannot take: probes.left_out)."""
        judged = {section(p, f"checks.{c}")["qoi"] for c in self.layout.names["checks"]}
        lines = []
        for name, kind in self.layout.names["probes"].items():
            if kind == "point_displacement" and f"peak_{name}" in judged:
                lines += probes.peak_at_end(name, history)
            elif kind == "far_field_failure" and mode == "coupled":
                lines += probes.left_out(name, history, qoi)
        return lines

    def plot(self, p: dict, history: dict, qoi: dict, plots_dir):
        from . import plots
        if p["geometry.shape"] == "panel":
            from .panel import plot
            plot(p, history, qoi, plots_dir)
            return
        plots.histories(self, p, history, qoi, plots_dir)
        plots.damage(history, plots_dir)
        plots.zone(history, plots_dir)


# closed forms of one shape and one loading: form -> (shape, what loads it)
FORM_NEEDS = {"block_spring_mass": ("block", "rod"), "block_pressure": ("block", "pressure"),
              "plate_spring_mass": ("plate", "impactor"), "plate_spring_mass_bracket": ("plate", "impactor"),
              "plate_pressure_bracket": ("plate", "pressure")}
FORM_WORDS = {"rod": "a flat-faced rod (impactors.*.shape = 'rod')", "impactor": "an impactor",
              "pressure": "a pressure load ([loads.*] kind = 'pressure')"}
# the tables that say what is simulated (not how: mesh, zone, fem, clock, output)
SPECIMEN = ("materials.", "interfaces.", "laminates.", "geometry.", "impactors.", "loads.", "delaminations.",
            "sheets.", "supports.")
PLACEMENT_KEYS = ("zone.placement", "zone.grow_at", "zone.margin", "zone.half_width", "zone.grow", "zone.grow_to",
                  "zone.grow_every", "zone.conversion")


def _physics_key(p: dict) -> tuple:
    """The parameters that decide a run's physics (not its output, engine or coupling)."""
    return tuple(sorted((k, v) for k, v in p.items() if not k.startswith(("output.", "dem.", "coupling."))))


def _damage_snapshots(sim, built) -> None:
    """Damage pictures at the first sixth of the run and at its end."""
    lat, intra, backend = built.lattice, built.intra, built.backend
    inter = built.inter if built.inter is not None else _NoBonds()
    in_90 = (np.array(built.lam.angles)[lat.ply] == 90).astype(float) if built.lam is not None else np.zeros(lat.n)
    t_end = sim.n_steps * sim.dt
    far = _far_field(built)
    if built.bonded is not None:  # the pictures' legend: adhesive and body, not plies
        far_plies = far
        far = lambda: {**far_plies(), "bonded": np.ones(1)}
    if built.dim == 3:
        j = (lat.index[:, 1] if built.lam is not None else built.width_index).astype(float)
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


class _NoBonds:
    """The interlaminar family of a body without interfaces (a block): no pairs."""

    pairs, damage = np.zeros((0, 2), int), np.zeros(0)

    def failed(self):
        return np.zeros(0, bool)


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
    bonds = built.node_bonds  # a cohesive far field: its node pairs' damage, drawn as the particles' bonds
    pairs = bonds.pairs[:, 0] if bonds is not None else np.zeros(0, int)
    return lambda: {"fem_x": np.pad(X + dyn.state.u, ((0, 0), (0, 3 - dim))), "fem_x0": X0, "fem_edges": edges,
                    "fem_bond_nodes": pairs.astype(float),
                    "fem_bond_damage": bonds.damage.copy() if bonds is not None else np.zeros(0)}


def document_schema() -> str:
    return document(probes.PROBES, closed_forms.CLOSED_FORMS)


def renamed(key: str, study: Study) -> str | None:
    """The study key that replaced a scene module's key, or None."""
    names = study.layout.names
    one = lambda c: next(iter(names[c]), None)
    tail = key.split(".", 1)[-1]
    if names["delaminations"]:  # the former panel_buckling scene's
        delam, load = f"delaminations.{one('delaminations')}", f"loads.{one('loads')}"
        new = {"geometry.length": "geometry.span", "geometry.delamination_length": f"{delam}.length",
                "geometry.sublaminate_plies": f"{delam}.sublaminate_plies", "local.imperfection": f"{delam}.imperfection",
                "global.imperfection": "geometry.imperfection", "interface.contact": f"{delam}.contact",
                "interface.penalty": f"{delam}.penalty", "interface.cohesive_zone_bonds": "zone.cohesive_zone_bonds",
                "load.shortening_factor": f"{load}.shortening_factor", "load.duration_periods": f"{load}.duration_periods",
                "geometry.ply_thickness": f"laminates.{one('laminates')}.ply_thickness",
                "geometry.plies": f"laminates.{one('laminates')}.layup"}.get(key)
        if new:
            return new
    if key.startswith(("material.", "strength.", "fracture.")) and one("materials"):
        lam = study.PARAMETERS["geometry.laminate"].default
        return f"materials.{study.PARAMETERS[f'laminates.{lam}.material'].default}.{tail}"
    if key.startswith("interface.") and one("interfaces"):
        return f"interfaces.{one('interfaces')}.{tail}"
    if key.startswith(("plate.", "rod.")) and one("impactors"):  # the former rod_impact scene's
        lam = study.PARAMETERS["geometry.laminate"].default
        table = f"materials.{study.PARAMETERS[f'laminates.{lam}.material'].default}" if key.startswith("plate.") \
            else f"impactors.{one('impactors')}"
        return f"{table}.{tail}"
    if key.startswith("impactor.") and one("impactors"):
        return f"impactors.{one('impactors')}.{tail}"
    if key.startswith(("concrete.", "cfrp.", "bond.", "load.", "crack.")) and names["sheets"]:
        return _renamed_bonded(key, study)
    return {"dem.half_width": "zone.half_width", "dem.plies_per_row": "zone.plies_per_particle",
            "geometry.half_span": "geometry.span (the whole span)", "laminate.layup": f"laminates.{one('laminates')}.layup",
            "laminate.ply_thickness": f"laminates.{one('laminates')}.ply_thickness",
            "geometry.radius": "geometry.span (the diameter)", "mesh.radial": "mesh.elements_along",
            "mesh.per_layer": "mesh.elements_per_ply",
            "geometry.layer_thickness": f"laminates.{one('laminates')}.ply_thickness",
            "contact.penalty": f"impactors.{one('impactors')}.penalty"}.get(key)


def _renamed_bonded(key: str, study: Study) -> str | None:
    """The study key of a key of the former cfrp_beam_impact scene."""
    P, names = study.PARAMETERS, study.layout.names
    sheet = next(iter(names["sheets"]))
    table, _, field = key.partition(".")
    if table == "concrete":
        return f"materials.{P['geometry.material'].default}.{field}"
    if table == "cfrp":
        if field == "thickness":
            return f"sheets.{sheet}.thickness"
        ply = {"E1": "E11", "E2": "E22", "T0": "Xt (and Xc)", "sigma_t": "Yt (and Yc, S12, S23)", "Gf": "Gf_fibre"}
        return f"materials.{P[f'sheets.{sheet}.material'].default}.{ply.get(field, field)}"
    if table == "bond":
        return f"interfaces.{P[f'sheets.{sheet}.interface'].default}.{field}"
    if table == "load" and names["loads"]:
        return f"loads.{next(iter(names['loads']))}.{'width' if field == 'patch_width' else field}"
    if key == "crack.visible_opening":
        kinds = [n for n, k in names["probes"].items() if k == "flexural_cracks"]
        return f"probes.{kinds[0]}.visible_opening" if kinds else None
    return None


def _one_each(names: dict) -> None:
    """One impactor and one support per case: several are not in the schema (docs/cases.md;
    a second impactor failed mid-run)."""
    for table in ("impactors", "supports"):
        first, *more = names[table] or [None]
        if more:
            raise CaseError(f"[{table}.{more[0]}] ({KIND_KEY[table][0]} = {names[table][more[0]]!r}): a second "
                            f"[{table}.*] beside [{table}.{first}]; allowed: one per case (several are not in the "
                            "schema)")


def _curve_or_file(loads: dict, where: str) -> None:
    """A load's history is its curve or its file, not both (the file would win silently)."""
    for name, entry in loads.items():
        if isinstance(entry, dict) and "curve" in entry and "file" in entry:
            raise CaseError(f"loads.{name}.curve and loads.{name}.file = {entry['file']!r}: both given in {where} "
                            "(the file is read instead of the curve); allowed: one of them")


def _hourglass(p: dict, changed: set) -> None:
    """fem.hourglass and its kappa act on one-point elements only (fem.integration = 'reduced');
    a case file may hold them for a --set of the integration, so only --set's are refused."""
    for key in ("fem.hourglass", "fem.hourglass_kappa"):
        if key in changed and p["fem.integration"] != "reduced":
            raise CaseError(f"{key} = {p[key]!r}: has no effect with fem.integration = {p['fem.integration']!r} "
                            "(hourglass control acts on one-point elements); allowed: leave it out, or "
                            "fem.integration = 'reduced'")


def load_file_rows(key: str, path: str) -> list[tuple[float, float]]:
    """fem_region.loads.read_rows of a load's CSV file, its faults refused as an inline curve's
    are: one line naming the key and the file."""
    from fem_region.loads import read_rows
    try:
        return read_rows(path)
    except UnicodeDecodeError as exc:
        raise CaseError(f"{key} = {path!r}: not UTF-8 text (byte {exc.object[exc.start]:#04x} at offset {exc.start}); "
                        "allowed: a UTF-8 CSV file of time,value rows") from None
    except OSError as exc:
        raise CaseError(f"{key} = {path!r}: cannot be read ({exc.strerror}); allowed: a readable CSV file") from None
    except ValueError as exc:
        raise CaseError(f"{key} = {path!r}: {exc}") from None


def resolve_files(p: dict, keys, folder: Path) -> None:
    """Files (the keys' values) relative to the case file's folder, made absolute; refused if
    missing."""
    for key in keys:
        if p.get(key):
            path = Path(p[key]).expanduser()
            path = path if path.is_absolute() else folder / path
            if not path.is_file():
                raise CaseError(f"{key} = {p[key]!r}: no such file (a relative path is read from {folder})")
            p[key] = str(path)
