"""The case schema: what a study file may declare, each value typed, ranged and documented.

A study file is TOML in SI units. Named tables (``[materials.graphite_epoxy]``) hold a kind's
fields; every value has one flat dotted key (``materials.graphite_epoxy.E11``), the key that
``--set`` takes and summary.json echoes. ``femdem schema`` prints this file's tables.

Sections (one concept, one key):
- case:         description, name, t_end, modes, reference_elements, no_fracture_reference
- materials.*:  kind "ply" (a transversely isotropic ply: moduli, density, Hoffman strengths,
                fracture energies) or "isotropic" (a quasi-brittle solid, concrete: E, nu, rho,
                ft, fc, Gf, the scatter of its bond strengths)
- interfaces.*: kind "hashin" (interlaminar or adhesive law: Z0, R0, GIc, GIIc, friction)
- laminates.*:  layup, ply_thickness, material, interface
- sheets.*:     a bonded beam's sheet on its bottom face: material (a ply), thickness, interface
- geometry:     shape "beam" (a plane-strain slice of a laminated beam along x, y through the
                thickness, centred on x = 0), "beam_3d" (a quarter of it, the thickness along
                z), "plate" (a quarter of a rectangular plate), "bonded_beam" (a plane-stress
                slice of a beam of one isotropic material with a sheet bonded under it) or
                "bonded_beam_3d" (a quarter of it) or "disc" (a quarter of a circular plate); its
                laminate (with tied or cohesive FEM interfaces) or material and depth, span,
                width, length, symmetry
- mesh:         FEM elements and their sizing, graded towards the zone
- fem:          the FEM's integration and formulation
- zone:         the DEM damage zone: shape "box" (|x| <= half_width, the whole thickness),
                plies_per_particle (laminates) or particle_size (bonded beams, the disc),
                ply_failure
- supports.*:   at "ends" (a beam's, x = +-span / 2), "edges" (a plate's) or "rim" (a disc's),
                condition clamped or simply_supported
- impactors.*:  shape "cylinder" (a beam's, along its width, on the top face at x = 0: radius,
                mass_per_width, velocity, penalty, friction) or "sphere" (a plate's, on its centre:
                radius, mass, velocity, penalty, friction) or "rod" (a disc's, flat-faced, on its
                centre: radius, length, rho, velocity, penalty per area)
- loads.*:      kind "patch" (a bonded beam's: a force history on its top face about x = 0, as
                a curve of [time, force] rows or a CSV file, with scale factors)
- probes.*:     kind from the registry (study/probes.py), with what the run reports of them
- checks.*:     a qoi against a closed form registered in code (study/closed_forms.py) or against
                a test's value or range given with its source
- coupling:     the FEM-DEM tie
- ranges:       "key" = [low, high], the verified range of a numeric key (outside: refused)
"""
from __future__ import annotations

from dataclasses import dataclass

from fem_region import materials as fem_materials
from fem_region.region import FORMULATIONS, INTEGRATIONS

from ..params import CaseError, Param, density, modulus, positive
from ..participants.coupled import COUPLING

REQUIRED = None  # a field's default when the file must give it
SHAPES = ("beam", "beam_3d", "plate", "disc", "bonded_beam", "bonded_beam_3d")
LAMINATED, BONDED = ("beam", "beam_3d", "plate", "disc"), ("bonded_beam", "bonded_beam_3d")


def _ratio(default, doc, low=0.0, high=0.49):
    return Param(default, doc, low=low, high=high)


def _toughness(doc):
    return Param(REQUIRED, doc, unit="J/m^2", low=0.0, open_low=True)


def _strength(doc):
    return positive(REQUIRED, doc, "Pa")


KINDS: dict[str, dict[str, dict[str, Param]]] = {
    "materials": {
        "ply": {
            "E11": modulus(REQUIRED, "modulus along the fibres"),
            "E22": modulus(REQUIRED, "transverse modulus"),
            "G12": modulus(REQUIRED, "in-plane shear modulus"),
            "G23": modulus(REQUIRED, "transverse shear modulus"),
            "nu12": _ratio(REQUIRED, "major Poisson ratio"),
            "nu23": _ratio(REQUIRED, "transverse Poisson ratio"),
            "rho": density(REQUIRED, "density"),
            "Xt": _strength("tensile strength along the fibres"),
            "Xc": _strength("compressive strength along the fibres"),
            "Yt": _strength("transverse tensile strength"),
            "Yc": _strength("transverse compressive strength"),
            "S12": _strength("in-plane shear strength"),
            "S23": _strength("transverse shear strength"),
            "Gf_fibre": _toughness("fracture energy of a crack across the fibres"),
            "Gf_matrix": _toughness("fracture energy of a matrix crack (along the fibres)"),
        },
        "isotropic": {  # a quasi-brittle solid (concrete): cracks by Hoffman with its two strengths
            "E": modulus(REQUIRED, "Young's modulus"),
            "nu": _ratio(REQUIRED, "Poisson ratio"),
            "rho": density(REQUIRED, "density"),
            "ft": _strength("tensile strength"),
            "fc": _strength("compressive strength"),
            "Gf": _toughness("fracture energy (area of the linear softening per crack area)"),
            "strength_scatter": Param(0.0, "bond strengths uniform in 1 +- this (heterogeneity, so that cracks "
                                      "localise as in a real concrete instead of softening uniformly)",
                                      low=0.0, high=0.5),
            "seed": Param(1, "random seed of the strength scatter (the same on every engine)", kind="int", low=0),
        },
    },
    "interfaces": {
        "hashin": {
            "Z0": _strength("interlaminar normal strength (Hashin initiation)"),
            "R0": _strength("interlaminar shear strength (Hashin initiation)"),
            "GIc": _toughness("mode I toughness (area of the linear softening)"),
            "GIIc": _toughness("mode II toughness"),
            "friction": Param(0.3, "Coulomb friction of debonded faces", low=0.0, high=2.0),
            "penalty": Param(0.0, "stiffness per area of the FEM's node-pair bonds where the far field carries "
                             "this interface (laminates' far_field_interfaces = 'cohesive'; 0: not used)",
                             unit="Pa/m", low=0.0),
        },
    },
    "impactors": {
        "sphere": {  # on a plate's centre
            "radius": positive(REQUIRED, "sphere radius", "m"),
            "mass": positive(REQUIRED, "mass", "kg"),
            "velocity": positive(REQUIRED, "impact speed (downwards, on the top face at the centre)", "m/s"),
            "penalty": Param(0.0, "contact penalty per particle / node; 0 = E22 times the particle size",
                             unit="N/m", low=0.0),
            "friction": Param(0.2, "impactor friction", low=0.0, high=2.0),
        },
        "rod": {  # a disc's: a flat-faced rod along z on its centre
            "radius": positive(REQUIRED, "rod radius", "m"),
            "length": positive(REQUIRED, "rod length (its mass with rho)", "m"),
            "rho": density(REQUIRED, "rod density"),
            "velocity": positive(REQUIRED, "impact speed (downwards, on the top face at the centre)", "m/s"),
            "penalty": positive(REQUIRED, "contact penalty per area (Pa/m): a FEM node gets it times its tributary "
                                "area, a particle times d^2", "Pa/m"),
        },
        "cylinder": {
            "radius": positive(REQUIRED, "cylinder radius", "m"),
            "mass_per_width": positive(REQUIRED, "mass per metre of width", "kg/m"),
            "velocity": positive(REQUIRED, "impact speed (downwards, on the top face at x = 0)", "m/s"),
            "penalty": Param(0.0, "contact penalty per particle / node; 0 = the lattice's transverse bond "
                             "stiffness E_y t", unit="N/m", low=0.0),
            "friction": Param(0.2, "impactor friction", low=0.0, high=2.0),
        },
    },
    "sheets": {
        "bottom": {  # a bonded beam's, on its bottom face over its whole length
            "material": Param(REQUIRED, "the sheet's material (a [materials.*] ply, fibres along the beam)", kind="str"),
            "thickness": positive(REQUIRED, "sheet thickness", "m"),
            "interface": Param(REQUIRED, "the adhesive between sheet and beam (an [interfaces.*] name)", kind="str"),
        },
    },
    "loads": {
        "patch": {  # on the top face, centred on x = 0, across the whole width, downwards
            "width": positive(REQUIRED, "length of the loaded patch along the beam (both halves)", "m"),
            "curve": Param(((0.0, 0.0), (1.0, 0.0)), "the whole load's history: rows [time, force] (zero outside); "
                           "times x time_scale in s, forces x value_scale in N", kind="table"),
            "file": Param("", "a CSV time,force read instead of curve (relative to the case file; header and # "
                          "lines skipped), scaled by time_scale and value_scale", kind="str"),
            "time_scale": positive(1.0, "factor on the curve's times to s (1e-3: given in ms; *DEFINE_CURVE SFA)", ""),
            "value_scale": positive(1.0, "factor on the curve's forces to N (1e3: given in kN; SFO)", ""),
            "scale": positive(1.0, "factor on the load (a study's knob)", ""),
        },
    },
    "supports": {
        "ends": {  # a beam's, at x = +-span / 2
            "condition": Param("clamped", "clamped (the end face held) or simply_supported (its bottom edge held "
                               "vertically)", kind="str", choices=("clamped", "simply_supported")),
        },
        "rim": {  # a disc's, at radius span / 2
            "condition": Param("clamped", "clamped (every DOF of the rim held)", kind="str", choices=("clamped",)),
        },
        "edges": {  # a plate's, at x = +-span / 2 and y = +-width / 2
            "condition": Param("clamped", "clamped (the edge faces held) or simply_supported (their bottom edges "
                               "held vertically)", kind="str", choices=("clamped", "simply_supported")),
        },
    },
}
# the key naming a named table's kind, and its default (a single-kind table may leave it out)
KIND_KEY = {"materials": ("kind", "ply"), "interfaces": ("kind", "hashin"), "impactors": ("shape", "cylinder"),
            "supports": ("at", "ends"), "probes": ("kind", None), "checks": ("closed_form", None),
            "sheets": ("face", "bottom"), "loads": ("kind", "patch")}

LAMINATE = {
    "layup": Param(REQUIRED, "layup, bottom up: [ANGLE_COUNT/...] with an optional repeat and s (symmetric), "
                   "e.g. [0_6/90_4/0_6] or [0/90_2]2s; 0 and 90 plies", kind="str", check=fem_materials.parse_layup),
    "ply_thickness": positive(REQUIRED, "ply thickness", "m"),
    "material": Param(REQUIRED, "the plies' material (a [materials.*] name)", kind="str"),
    "interface": Param(REQUIRED, "the law between plies of different angle (an [interfaces.*] name)", kind="str"),
    "far_field_interfaces": Param("tied", "in the FEM: tied (the plies share nodes: no delamination outside the "
                                  "zone) or cohesive (the plies of different angle meshed apart, their coincident "
                                  "nodes joined by the interface's Hashin law with its penalty; the disc)",
                                  kind="str", choices=("tied", "cohesive")),
}

SECTIONS: dict[str, dict[str, Param]] = {
    "geometry": {
        "shape": Param("beam", "beam: a plane-strain slice of a laminated beam along x, centred on x = 0; "
                       "beam_3d: a quarter of it (x = 0 and mid-width y = 0 symmetry planes), thickness along z; "
                       "plate: a quarter of a rectangular plate, span along x and width along y, centred on x = y = 0; "
                       "disc: a quarter of a circular plate of diameter span, clamped at its rim; "
                       "bonded_beam: a plane-stress slice of a beam of one isotropic material with a sheet bonded "
                       "to its bottom face; bonded_beam_3d: a quarter of it",
                       kind="str", choices=SHAPES),
        "laminate": Param("", "the laminate (a [laminates.*] name; beam, beam_3d, plate)", kind="str"),
        "material": Param("", "the body's material (an isotropic [materials.*] name; bonded beams)", kind="str"),
        "depth": Param(0.0, "the body's depth (bonded beams; a laminate's is its plies')", unit="m", low=0.0),
        "length": Param(0.0, "the beam's length, supports inside it at +-span / 2 (bonded beams); 0: the span",
                        unit="m", low=0.0),
        "span": positive(REQUIRED, "distance between the supports", "m"),
        "width": Param(0.0, "width out of the slice's plane (forces are reported for the whole width); not a "
                       "disc's", unit="m", low=0.0),
        "symmetry": Param("x", "the symmetry planes: x (beam: half model about x = 0) or xy (beam_3d: also "
                          "mid-width y = 0; plate)", kind="str", choices=("x", "xy")),
    },
    "mesh": {
        "element": Param("quad4", "element: quad4 (beam) or hex8 (beam_3d, plate)", kind="str",
                         choices=("quad4", "hex8")),
        "elements_along": Param(30, "FEM elements between the zone and a support (a disc: along its radius, a "
                                "multiple of 8 puts a node ring on the rod's edge)", kind="int", low=2),
        "elements_per_ply": Param(1, "a disc's: Hex8 elements through each ply", kind="int", low=1, high=8),
        "file": Param("", "a Gmsh mesh (.msh, read by meshio) of a beam slice's half, x from 0 to span / 2, y "
                      "through the thickness: its physical group named after the laminate is the FEM (quadrangles or "
                      "triangles, lines at the ply runs' interfaces and at the zone's edge); a physical group named "
                      "after the [supports.*] table holds that support's nodes; relative to the case file; "
                      "replaces elements_along and element_ratio", kind="str"),
        "element_ratio": Param(6.0, "largest / smallest element length, graded from the zone", low=1.0, high=100.0),
        "elements_width": Param(4, "Hex8 elements across the modelled half width (beam_3d, bonded_beam_3d), or "
                                "across the zone's half width (plate)", kind="int", low=1, high=200),
        "growth": Param(1.2, "bonded beams: element length ratio between neighbours, from the particle size at the "
                        "zone's edge towards the support", low=1.0, high=2.0),
        "max_size": Param(25e-3, "bonded beams: the largest element length along the beam", unit="m", low=0.0,
                          open_low=True),
    },
    "fem": {
        "integration": Param("selective", "full, or selective (shear at the centroid: no shear locking)",
                             kind="str", choices=INTEGRATIONS),
        "formulation": Param("linear", "small-strain linear or Total Lagrangian", kind="str", choices=FORMULATIONS),
        "hourglass": Param("stiffness", "hourglass control of one-point (reduced) elements: Flanagan-Belytschko "
                           "stiffness or viscous, or none", kind="str", choices=("stiffness", "viscous", "none")),
        "hourglass_kappa": Param(0.1, "hourglass coefficient", low=0.0, high=1.0),
    },
    "zone": {
        "shape": Param("box", "box: |x| <= half_width (a plate: and |y| <= half_width) through the whole "
                       "thickness", kind="str", choices=("box",)),
        "half_width": positive(REQUIRED, "half width of the DEM zone about x = 0 (coupled mode)", "m"),
        "plies_per_particle": Param(1, "plies per particle row (the particle size is this x ply thickness; "
                                    "laminates)", kind="int", low=1, high=8),
        "particle_size": Param(0.0, "lattice spacing d (bonded beams: the depth holds a whole number of rows; a "
                               "disc: it divides the ply thickness and half_width)", unit="m", low=0.0),
        "ply_failure": Param(True, "the plies fail by Hoffman in the zone; false: elastic plies (only the "
                             "interfaces fail)", kind="bool"),
    },
    "coupling": {k.split(".", 1)[1]: v for k, v in COUPLING.items()},
}
COLLECTIONS = ("materials", "interfaces", "laminates", "sheets", "impactors", "loads", "supports", "probes", "checks")
META = {"description", "name", "t_end", "modes", "reference_elements", "no_fracture_reference"}
MODES = ("coupled", "fem", "dem")


@dataclass
class Layout:
    """The names a study declares: {collection: {name: kind}}, and its [case] table."""

    names: dict[str, dict[str, str]]
    meta: dict


def is_study(data: dict) -> bool:
    """A case file without ``[case] scene`` that declares a geometry is a study."""
    return "geometry" in data and "scene" not in data.get("case", {})


def parameters(data: dict, where: str, probe_kinds: dict, closed_forms: dict,
               common: frozenset = frozenset({"clock", "output", "dem", "guards"})) -> tuple[dict[str, Param], Layout]:
    """(dotted key -> Param with the file's values as defaults, Layout) of a study file's tables;
    CaseError (one line) for an unknown table, key or kind, a missing required value or a
    name that refers to nothing."""
    meta = data.get("case", {})
    if not isinstance(meta, dict):
        raise CaseError(f"case: expected a table in {where}")
    extra = set(meta) - META
    if extra:
        raise CaseError(f"case.{sorted(extra)[0]}: unknown key in {where}; allowed: {', '.join(sorted(META))}")
    schema: dict[str, Param] = {}
    names: dict[str, dict[str, str]] = {c: {} for c in COLLECTIONS}
    for table, body in data.items():
        if table in ("case", "ranges") or table in common:  # the run's own tables (clock, output, ...)
            continue
        if not isinstance(body, dict):
            raise CaseError(f"{table} = {body!r}: expected a table in {where}")
        if table in SECTIONS:
            schema.update(_fields(table, SECTIONS[table], body, where))
        elif table in COLLECTIONS:
            for name, entry in body.items():
                if not isinstance(entry, dict):
                    raise CaseError(f"{table}.{name} = {entry!r}: expected a table [{table}.{name}] in {where}")
                kind, fields = _kind(table, name, entry, probe_kinds, closed_forms)
                names[table][name] = kind
                schema.update(_fields(f"{table}.{name}", fields, entry, where))
        else:
            raise CaseError(f"[{table}]: unknown table in {where}; allowed: case, "
                            f"{', '.join([*COLLECTIONS, *SECTIONS, *sorted(common)])}")
    for table, fields in SECTIONS.items():  # tables left out: their defaults (or a required key missing)
        if table not in data:
            schema.update(_fields(table, fields, {}, where))
    layout = Layout(names, meta)
    _references(schema, layout, where)
    _ranges(schema, data.get("ranges", {}), where)
    return schema, layout


def _ranges(schema: dict[str, Param], ranges: dict, where: str) -> None:
    """[ranges] "key" = [low, high]: the range over which the study's checks are verified;
    values outside it are refused like any out-of-range value."""
    if not isinstance(ranges, dict):
        raise CaseError(f"ranges = {ranges!r}: expected a table of \"key\" = [low, high] in {where}")
    for key, pair in ranges.items():
        param = schema.get(key)
        if param is None or param.kind not in ("float", "int"):
            raise CaseError(f"ranges.{key}: not a numeric key of this study in {where}")
        if (not isinstance(pair, list) or len(pair) != 2 or any(isinstance(v, bool) or not isinstance(v, (int, float))
                                                               for v in pair) or not pair[0] <= pair[1]):
            raise CaseError(f"ranges.{key} = {pair!r}: expected [low, high] with low <= high in {where}")
        low = max(pair[0], param.low) if param.low is not None else pair[0]
        high = min(pair[1], param.high) if param.high is not None else pair[1]
        ranged = Param(param.default, param.doc + " (verified range)", param.kind, param.unit, low, high,
                       param.open_low and low == param.low, param.open_high and high == param.high,
                       param.choices, param.plausible, param.check)
        ranged.coerce(key, param.default)  # the file's own value inside its range
        schema[key] = ranged


def _kind(table: str, name: str, entry: dict, probe_kinds: dict, closed_forms: dict):
    """(kind, {field: Param}) of one named table."""
    key, default = KIND_KEY.get(table, (None, None))
    if table == "laminates":
        return "laminate", LAMINATE
    kinds = {"probes": probe_kinds, "checks": closed_forms}.get(table) or KINDS[table]
    kind = entry.get(key, default)
    if kind not in kinds:
        raise CaseError(f"{table}.{name}.{key} = {kind!r}: allowed {', '.join(repr(k) for k in kinds)}")
    fields = kinds[kind] if table not in ("probes", "checks") else kinds[kind].fields
    return kind, {key: Param(kind, f"what this {table[:-1]} is", kind="str", choices=tuple(kinds)), **fields}


def _fields(prefix: str, fields: dict[str, Param], given: dict, where: str) -> dict[str, Param]:
    unknown = sorted(set(given) - set(fields))
    if unknown:
        raise CaseError(f"{prefix}.{unknown[0]}: unknown key in {where}; allowed: {', '.join(fields)}")
    out = {}
    for field, param in fields.items():
        key = f"{prefix}.{field}"
        if field in given:
            value = param.coerce(key, given[field])
        elif param.default is REQUIRED:
            raise CaseError(f"{key}: required in {where}; allowed: {param.allowed()} ({param.doc})")
        else:
            value = param.default
        out[key] = Param(value, param.doc, param.kind, param.unit, param.low, param.high, param.open_low,
                         param.open_high, param.choices, param.plausible, param.check)
    return out


def _references(schema: dict[str, Param], layout: Layout, where: str) -> None:
    """Names that point at other tables must exist: a reference becomes a choice among them."""
    refs = {"material": "materials", "interface": "interfaces", "laminate": "laminates", "impactor": "impactors",
            "load": "loads"}
    for key, param in list(schema.items()):
        field = key.rsplit(".", 1)[-1]
        if field in refs and param.kind == "str" and key.startswith(("laminates.", "geometry.", "probes.", "sheets.")):
            target = refs[field]
            allowed = tuple(layout.names[target])
            if key.startswith("geometry.") and param.default == "":  # not this shape's (Study checks)
                continue
            if param.default not in allowed:
                raise CaseError(f"{key} = {param.default!r}: no [{target}.{param.default}] in {where}; allowed: "
                                f"{', '.join(allowed) or f'(declare a [{target}.NAME] table)'}")
            schema[key] = Param(param.default, param.doc, "str", choices=allowed)


def section(p: dict, prefix: str) -> dict:
    """{field: value} of the resolved parameters under ``prefix.``."""
    n = len(prefix) + 1
    return {k[n:]: v for k, v in p.items() if k.startswith(prefix + ".") and "." not in k[n:]}


def document(probe_kinds: dict, closed_forms: dict) -> str:
    """The schema as text (``femdem schema``): every table, key, allowed values and meaning."""
    lines = [__doc__.strip(), ""]

    def table(header, fields):
        lines.append(header)
        for field, prm in fields.items():
            value = "(required)" if prm.default is REQUIRED else repr(prm.default)
            lines.append(f"  {field} = {value}  # {prm.allowed()}; {prm.doc}")
        lines.append("")
    lines.append("[case]\n  description, name (the run directory's), t_end (s, required), modes (default "
                 "all of coupled, fem, dem), reference_elements (model_size_vs_reference), no_fracture_reference "
                 "(true: a coupled or all-DEM run also runs its all-FEM twin and reports each point displacement's "
                 "peak without fracture, peak_NAME_no_fracture and NAME_change_by_fracture)\n")
    for collection in ("materials", "interfaces", "sheets", "impactors", "loads", "supports"):
        key = KIND_KEY[collection][0]
        for kind, fields in KINDS[collection].items():
            table(f"[{collection}.NAME]  {key} = {kind!r}", fields)
    table("[laminates.NAME]", LAMINATE)
    for name, sec in SECTIONS.items():
        table(f"[{name}]", sec)
    for kind, probe in probe_kinds.items():
        table(f"[probes.NAME]  kind = {kind!r}: {probe.doc}", probe.fields)
    for kind, form in closed_forms.items():
        table(f"[checks.NAME]  closed_form = {kind!r}: {form.doc}", form.fields)
    return "\n".join(lines)
