"""The case schema: what a study file may declare, each value typed, ranged and documented.

A study file is TOML in SI units. Named tables (``[materials.graphite_epoxy]``) hold a kind's
fields; every value has one flat dotted key (``materials.graphite_epoxy.E11``), the key that
``--set`` takes and summary.json echoes. ``femdem schema`` prints this file's tables.
A value keeps its TOML type: numbers unquoted (``"5"`` is text, refused), integers without a
decimal point; ``--set`` reads its text as a number where the key takes one.

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
                slice of a beam of one isotropic material with a sheet bonded under it),
                "bonded_beam_3d" (a quarter of it), "disc" (a quarter of a circular plate),
                "block" (a quarter of a block of one isotropic material) or "panel" (a slice
                of a laminate clamped at both ends, with a delamination); its laminate (with
                tied or cohesive FEM interfaces) or material and depth, span, width, length,
                symmetry
- mesh:         FEM elements and their sizing, graded towards the zone
- fem:          the FEM's integration and formulation
- zone:         the DEM damage zone: shape "box" (|x| <= half_width, the whole thickness),
                "cylinder" or "impactor" (a plate's or a block's footprint: a radius, or the
                impactor's contact radius plus a margin) or "crack_tips" (a panel's: a window
                across the delamination at each tip), plies_per_particle (laminates) or
                particle_size (bonded beams, the disc, a block),
                ply_failure
- supports.*:   at "ends" (a beam's, x = +-span / 2), "edges" (a plate's), "rim" (a disc's),
                condition clamped or simply_supported; or "bottom" (a block's: fixed or sliding)
- impactors.*:  shape "cylinder" (a beam's, along its width, on the top face at x = 0: radius,
                mass_per_width, velocity, penalty, friction) or "flat_punch" (a 2D beam's: a
                flat face of half_width, otherwise as the cylinder) or "sphere" (a plate's or a
                block's, on its centre: radius, mass, velocity, penalty, friction) or "rod" (a
                disc's, a plate's or a block's: a flat-faced punch on its centre: radius, length,
                rho, velocity, penalty per area)
- loads.*:      kind "patch" (a bonded beam's: a force history on its top face about x = 0, as
                a curve of [time, force] rows or a CSV file, with scale factors), "pressure" (a
                block's or a plate's: the same history as a uniform pressure on a disc of its top
                face about its centre) or "shortening" (a panel's: the end shortening, a slow ramp in periods
                of its first mode)
- delaminations.*: kind "through_width" (a panel's: the plies above it, its length, centred,
                the sublaminate's bump, contact of its faces)
- probes.*:     kind from the registry (study/probes.py), with what the run reports of them
- checks.*:     a qoi against a closed form registered in code (study/closed_forms.py) or against
                a test's value or range given with its source
- coupling:     the FEM-DEM tie
- ranges:       "key" = [low, high], the verified range of a numeric key, or a list of a text
                key's verified values (a layup, a support condition; outside: refused); a
                run that changes a key of the specimen (materials, interfaces, laminates,
                geometry, impactors, loads, delaminations, sheets, supports) with no range
                is warned that its checks are not verified there, and test data (test_value,
                test_between) are compared only on the case file's own specimen
"""
from __future__ import annotations

from dataclasses import dataclass

from fem_region import materials as fem_materials
from fem_region.region import FORMULATIONS, INTEGRATIONS

from ..params import CaseError, Param, density, modulus, positive
from ..participants.coupled import COUPLING

REQUIRED = None  # a field's default when the file must give it
SHAPES = ("beam", "beam_3d", "plate", "disc", "bonded_beam", "bonded_beam_3d", "panel", "block")
LAMINATED, BONDED = ("beam", "beam_3d", "plate", "disc"), ("bonded_beam", "bonded_beam_3d")


def _ratio(default, doc, low=0.0, high=0.49):
    return Param(default, doc, low=low, high=high)


def _toughness(doc):
    return Param(REQUIRED, doc, unit="J/m^2", low=0.0, open_low=True)


def _strength(doc):
    return positive(REQUIRED, doc, "Pa")


# what a beam's striker (cylinder or flat punch) declares besides its shape's size
_BEAM_STRIKER = {
    "mass_per_width": positive(REQUIRED, "mass per metre of width", "kg/m"),
    "velocity": positive(REQUIRED, "impact speed (downwards, on the top face at x = 0)", "m/s"),
    "penalty": Param(0.0, "contact penalty per particle / node; 0 = the lattice's transverse bond stiffness E_y t",
                     unit="N/m", low=0.0),
    "friction": Param(0.2, "impactor friction", low=0.0, high=2.0),
}

# a load's history: the whole force against time, as a table or a CSV file, with LS-DYNA-style scales
_PATCH_HISTORY = {
    "curve": Param(((0.0, 0.0), (1.0, 0.0)), "the whole load's history: rows [time, force] (zero outside); "
                   "times x time_scale in s, forces x value_scale in N", kind="table"),
    "file": Param("", "a CSV time,force read instead of curve (relative to the case file; header and # "
                  "lines skipped), scaled by time_scale and value_scale", kind="str"),
    "time_scale": positive(1.0, "factor on the curve's times to s (1e-3: given in ms; *DEFINE_CURVE SFA)", ""),
    "value_scale": positive(1.0, "factor on the curve's forces to N (1e3: given in kN; SFO)", ""),
    "scale": positive(1.0, "factor on the load (a study's knob)", ""),
}

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
        "sphere": {  # on a plate's or a block's centre
            "radius": positive(REQUIRED, "sphere radius", "m"),
            "mass": positive(REQUIRED, "mass", "kg"),
            "velocity": positive(REQUIRED, "impact speed (downwards, on the top face at the centre)", "m/s"),
            "penalty": Param(0.0, "contact penalty per particle / node; 0 = E22 times the particle size",
                             unit="N/m", low=0.0),
            "friction": Param(0.2, "impactor friction", low=0.0, high=2.0),
        },
        "rod": {  # a disc's, a plate's or a block's: a flat-faced rod (a 3D flat punch) along z on its centre
            "radius": positive(REQUIRED, "rod radius", "m"),
            "length": positive(REQUIRED, "rod length (its mass with rho)", "m"),
            "rho": density(REQUIRED, "rod density"),
            "velocity": positive(REQUIRED, "impact speed (downwards, on the top face at the centre)", "m/s"),
            "penalty": positive(REQUIRED, "contact penalty per area (Pa/m): a FEM node gets it times its tributary "
                                "area, a particle times d^2", "Pa/m"),
        },
        "flat_punch": {  # a 2D beam's: a flat strip face across the width, on the top face at x = 0
            "half_width": positive(REQUIRED, "half the punch's face length along the beam", "m"), **_BEAM_STRIKER},
        "cylinder": {"radius": positive(REQUIRED, "cylinder radius", "m"), **_BEAM_STRIKER},
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
            **_PATCH_HISTORY,
        },
        "pressure": {  # a block's or a plate's: a uniform pressure on a disc of its top face about its centre, downwards
            "radius": positive(REQUIRED, "radius of the loaded disc", "m"),
            **_PATCH_HISTORY,
        },
        "shortening": {  # a panel's: its right end moves towards its left, both ends clamped otherwise
            "shortening_factor": Param(1.6, "final end shortening / the intact panel's Euler shortening "
                                       "P_euler L / (E11 A)", low=1.1, high=5.0),
            # the film's snap lags a fast ramp: its reading fell 4 % from 32 to 64 periods and 2 % more
            # at 128 (full mesh, all-FEM); 64 is within 2 % of the slowest
            "duration_periods": Param(64.0, "loading time (a sin^2 ramp of the shortening rate) in periods of the "
                                      "panel's first mode; the run's duration", low=2.0),
        },
    },
    "delaminations": {
        "through_width": {  # a panel's: centred on its span, between two plies, across the whole width
            "sublaminate_plies": Param(REQUIRED, "plies above the delamination (the sublaminate that buckles)",
                                       kind="int", low=1, high=199),
            "length": positive(REQUIRED, "delamination length l (centred on the span)", "m"),
            "imperfection": Param(0.02, "initial outward bump of the sublaminate / its thickness", low=1e-4,
                                  high=1.0),
            "contact": Param(True, "frictionless penalty contact between the delaminated faces (no "
                             "interpenetration)", kind="bool"),
            "penalty": Param(0.0, "contact stiffness per area; 0 = E22 / (sublaminate element height), softened so "
                             "that it does not lower the elements' stable step", unit="Pa/m", low=0.0),
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
        "bottom": {  # a block's, its face z = 0
            "condition": Param("fixed", "fixed (every DOF of the bottom face held) or sliding (its vertical DOF: a "
                               "frictionless floor)", kind="str", choices=("fixed", "sliding")),
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
            "sheets": ("face", "bottom"), "loads": ("kind", "patch"), "delaminations": ("kind", "through_width")}

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
                       "to its bottom face; bonded_beam_3d: a quarter of it; panel: a plane-stress slice of a laminate "
                       "clamped at both ends and shortened axially, with one through-width delamination; block: a "
                       "quarter of a rectangular block of one isotropic material, span along x, width along y, depth "
                       "along z, resting on its bottom face",
                       kind="str", choices=SHAPES),
        "laminate": Param("", "the laminate (a [laminates.*] name; beam, beam_3d, plate)", kind="str"),
        "material": Param("", "the body's material (an isotropic [materials.*] name; bonded beams, a block)", kind="str"),
        "depth": Param(0.0, "the body's depth (bonded beams, a block; a laminate's is its plies')", unit="m", low=0.0),
        "length": Param(0.0, "the beam's length, supports inside it at +-span / 2 (bonded beams); 0: the span",
                        unit="m", low=0.0),
        "span": positive(REQUIRED, "distance between the supports", "m"),
        "width": Param(0.0, "width out of the slice's plane (forces are reported for the whole width); not a "
                       "disc's", unit="m", low=0.0),
        "symmetry": Param("x", "the symmetry planes: x (beam: half model about x = 0) or xy (beam_3d: also "
                          "mid-width y = 0; plate, disc, block)", kind="str", choices=("x", "xy")),
    },
    "mesh": {
        "element": Param("quad4", "element: quad4 (beam) or hex8 (beam_3d, plate, disc, block)", kind="str",
                         choices=("quad4", "hex8")),
        "elements_along": Param(30, "FEM elements between the zone and a support, at most: none shorter than the "
                                "particle spacing (a beam; a disc: along its radius, a "
                                "multiple of 8 puts a node ring on the rod's edge)", kind="int", low=2),
        "elements_per_ply": Param(1, "a disc's: Hex8 elements through each ply", kind="int", low=1, high=8),
        "file": Param("", "a Gmsh mesh (.msh, read by meshio) of a beam slice's half, x from 0 to span / 2, y "
                      "through the thickness: its physical group named after the laminate is the FEM (quadrangles or "
                      "triangles, lines at the ply runs' interfaces and at the zone's edge; the runs may be meshed apart there, "
                      "joined node to face by a cohesive far field); of a 3D beam's quarter, x from 0 to span / 2, y "
                      "from 0 to width / 2, z through the thickness (hexahedra or tetrahedra, planes there); or of a "
                      "block's quarter "
                      "(hexahedra; the group named after its material, elements of one particle cell over the zone's "
                      "square); a physical group named after the [supports.*] table holds that support's nodes; "
                      "relative to the case file; replaces elements_along, element_ratio (and a 3D beam's or block's "
                      "elements_width)", kind="str"),
        "element_ratio": Param(6.0, "largest / smallest element length, graded from the zone", low=1.0, high=100.0),
        "elements_per_run": Param(0, "element rows through each run of equal plies (beams); 0: one per particle "
                                  "row (a coarser far field takes a larger stable step)", kind="int", low=0, high=20),
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
        "shape": Param("box", "the zone's footprint, a column through the whole thickness: box: |x| <= half_width "
                       "(a plate, a block: and |y| <= half_width); cylinder (a plate, a block): x^2 + y^2 <= half_width^2; "
                       "impactor (a plate, a block): a cylinder about the impactor of its contact radius (a sphere's Hertz radius at "
                       "the spring-mass peak force, a rod's face, a pressure load's disc) plus margin "
                       "(study/selectors.py)", kind="str",
                       choices=("box", "cylinder", "impactor")),
        "half_width": Param(0.0, "half width of the DEM zone about x = 0 (coupled mode), a cylinder's radius; "
                          "required but with a plate's zone.shape = impactor or a beam's zone.placement = auto",
                          unit="m", low=0.0),
        "placement": Param("box", "box: the zone is half_width wide; auto (beams): placed from the study's all-FEM "
                           "run, the impactor's contact patch and every element reached from it whose failure index "
                           "reaches grow_at (Hoffman; Hashin interlaminar too with tied far-field plies), plus "
                           "margin (study/placement.py; half_width is then unused)", kind="str",
                           choices=("box", "auto")),
        "grow_at": Param(0.5, "auto placement and growth: the failure index (1 at initiation) that puts an element in the zone",
                         low=0.05, high=2.0),
        "margin": Param(0.0, "auto placement and growth: the zone's margin beyond the flagged elements, and the widest gap "
                        "between them it bridges; a plate's or block's zone.shape = impactor: beyond the contact radius; 0: "
                        "the laminate's thickness (a contact's own stress field decays over about it; a bonded beam: its "
                        "depth; a block: the contact radius) or four particle sizes, the larger", unit="m", low=0.0, high=0.5),
        "grow": Param(False, "grow the zone during the run (beams, bonded beams, a plate's box, a disc's square): at each FEM step "
                      "(zone.grow_every) the far field's failure "
                      "indices (as placement's) are evaluated, and elements whose index reaches grow_at within margin "
                      "of the zone's edge become particles, their state carried over (study/growth.py)", kind="bool"),
        "grow_every": Param(1, "the growth is checked every this many clock steps (1: each FEM step, as the far field "
                            "steps) and at each history sample; 0: at the samples only (about 1000 a run, "
                            "output.history_every). A check between samples evaluates the far field's failure indices in "
                            "one compiled pass and reads the contact and the zone's damage; a conversion it asks for comes "
                            "at the next step, with the whole snapshot. Checked every step, the coarse beam ran 1.04-1.05 x "
                            "slower than at the samples on LIGGGHTS and YADE, 1.05-1.15 x on LAMMPS, whose worker is "
                            "called at each check: benchmarks/growth_check.py", kind="int", low=0),
        "conversion": Param("rebuild", "how a grown zone's new particles enter the engine: rebuild (the engine is "
                            "built again with the grown zone's particles at each conversion) or release (beams, 2D and 3D: "
                            "every particle out to grow_to is in the engine from the start, slaved to the FEM, and "
                            "released at its conversion; study/seeded.py)", kind="str", choices=("rebuild", "release")),
        "grow_to": Param(0.0, "the farthest the zone may grow; the far field is meshed at the particle spacing out to "
                         "it; 0: 0.8 x half the span (a plate: of the smaller half side; a bonded beam: four particle sizes short of "
                         "the support; a disc: half its radius)", unit="m", low=0.0),
        "plies_per_particle": Param(1, "plies per particle row (the particle size is this x ply thickness; "
                                    "laminates)", kind="int", low=1, high=8),
        "particle_size": Param(0.0, "lattice spacing d (bonded beams, a block: the depth holds a whole number of "
                               "rows; a disc: it divides the ply thickness and half_width)", unit="m", low=0.0),
        "ply_failure": Param(True, "the plies fail by Hoffman in the zone; false: elastic plies (only the "
                             "interfaces fail)", kind="bool"),
    },
    "coupling": {k.split(".", 1)[1]: v for k, v in COUPLING.items()},
}
# a panel (a plane-stress slice of a laminate along x, y through the thickness, clamped at
# x = 0 and x = span, shortened axially, with one through-width delamination): its own fields
PANEL: dict[str, dict[str, Param]] = {
    "geometry": {
        "shape": SECTIONS["geometry"]["shape"],
        "laminate": Param(REQUIRED, "the laminate (a [laminates.*] name)", kind="str"),
        "span": positive(REQUIRED, "free length L between the clamped ends", "m"),
        "width": positive(REQUIRED, "panel width b (the slice stands for all of it)", "m"),
        "symmetry": Param("none", "none: the whole panel is modelled", kind="str", choices=("none",)),
        "imperfection": Param(0.02, "initial bow of the panel in its clamped first mode / its thickness",
                              low=1e-4, high=1.0),
    },
    "mesh": {
        "element": Param("quad4", "element: quad4", kind="str", choices=("quad4",)),
        "elements_along": Param(148, "elements along the panel", kind="int", low=20),
        "elements_sublaminate": Param(3, "elements through the sublaminate", kind="int", low=1, high=20),
        "elements_base": Param(6, "elements through the base laminate (below the delamination)", kind="int",
                               low=1, high=40),
    },
    "fem": {
        "integration": SECTIONS["fem"]["integration"],
        "formulation": Param("total_lagrangian", "internal force path (buckling needs total_lagrangian)",
                             kind="str", choices=FORMULATIONS),
        "hypothesis": Param("plane_stress", "2D hypothesis (a panel's edges are free: plane stress)", kind="str",
                            choices=("plane_stress", "plane_strain")),
    },
    "zone": {
        "shape": Param("crack_tips", "crack_tips: a window of particles across the delamination plane at each "
                       "tip (coupled mode)", kind="str", choices=("crack_tips",)),
        "particle_size": Param(0.0, "lattice spacing d; 0: two plies, or half the thinner sublaminate if less (the "
                               "window's four rows fit)", unit="m", low=0.0, plausible=(0.0, 1.0)),
        "window_ahead": Param(0.0, "window ahead of each tip, into the intact laminate (room to grow); 0: the intact "
                              "end less max(3 mm, a tenth of it), the room to the clamps", unit="m", low=0.0),
        # behind the tip the window holds the film's lower half as two particle rows: 2 mm of it
        # made the film's clamped ends 3 % softer (coupled elastic 5.75 kN against all-FEM 5.94 kN
        # on the coarse mesh; 0.5 mm: 5.94 against 5.97 kN)
        "window_behind": positive(0.5e-3, "window behind each tip, inside the delamination; also where the film "
                                  "strain gauge stops short of the tips (both modes)", "m"),
        "cohesive_zone_bonds": Param(20.0, "fewest bonds in the cohesive zone (strengths lowered to "
                                     "sqrt(9 pi E22 Gc / (32 N d)), Turon et al. 2007); 0 keeps them",
                                     low=0.0, high=50.0),
    },
}
# a panel's ply is elastic (it buckles, it does not crack): its moduli and density only
ELASTIC_PLY = {k: v for k, v in KINDS["materials"]["ply"].items() if k in ("E11", "E22", "G12", "nu12", "nu23", "rho")}
COLLECTIONS = ("materials", "interfaces", "laminates", "sheets", "impactors", "loads", "supports", "delaminations",
               "probes", "checks")
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
    geometry = data.get("geometry", {})
    panel = isinstance(geometry, dict) and geometry.get("shape") == "panel"
    sections = {**SECTIONS, **PANEL} if panel else SECTIONS
    for table, body in data.items():
        if table in ("case", "ranges") or table in common:  # the run's own tables (clock, output, ...)
            continue
        if not isinstance(body, dict):
            raise CaseError(f"{table} = {body!r}: expected a table in {where}")
        if table in sections:
            schema.update(_fields(table, sections[table], body, where))
        elif table in COLLECTIONS:
            for name, entry in body.items():
                if not isinstance(entry, dict):
                    raise CaseError(f"{table}.{name} = {entry!r}: expected a table [{table}.{name}] in {where}")
                kind, fields = _kind(table, name, entry, probe_kinds, closed_forms)
                if panel and (table, kind) == ("materials", "ply"):
                    fields = {k: v for k, v in fields.items() if k == "kind" or k in ELASTIC_PLY}
                names[table][name] = kind
                schema.update(_fields(f"{table}.{name}", fields, entry, where))
        else:
            raise CaseError(f"[{table}]: unknown table in {where}; allowed: case, "
                            f"{', '.join([*COLLECTIONS, *SECTIONS, *sorted(common)])}")
    for table, fields in sections.items():  # tables left out: their defaults (or a required key missing)
        if table not in data:
            schema.update(_fields(table, fields, {}, where))
    layout = Layout(names, meta)
    _references(schema, layout, where)
    given = {f"{t}.{k}" for t, body in data.items() if isinstance(body, dict) for k in body}
    given |= {f"{t}.{n}.{k}" for t, body in data.items() if t in COLLECTIONS and isinstance(body, dict)
              for n, entry in body.items() if isinstance(entry, dict) for k in entry}
    _ranges(schema, data.get("ranges", {}), where, given)
    return schema, layout


def _ranges(schema: dict[str, Param], ranges: dict, where: str, given: set = frozenset()) -> None:
    """[ranges] "key" = [low, high], or a text key's list of verified values: the range over which
    the study's checks are verified; values outside it are refused like any out-of-range value,
    the file's own among them (a key the file leaves out is required when its default lies
    outside the range)."""
    if not isinstance(ranges, dict):
        raise CaseError(f"ranges = {ranges!r}: expected a table of \"key\" = [low, high] in {where}")
    for key, pair in ranges.items():
        param = schema.get(key)
        if param is None or param.kind not in ("float", "int", "str"):
            raise CaseError(f"ranges.{key}: not a numeric or text key of this study in {where}")
        if param.kind == "str":
            if not isinstance(pair, list) or not pair or not all(isinstance(v, str) for v in pair):
                raise CaseError(f"ranges.{key} = {pair!r}: expected a list of the verified values in {where}")
            for value in pair:
                param.coerce(f"ranges.{key}", value)
            ranged = Param(param.default, param.doc + " (verified values)", "str", param.unit,
                           choices=tuple(pair), check=param.check)
        else:
            if (not isinstance(pair, list) or len(pair) != 2 or any(isinstance(v, bool) or not isinstance(v, (int, float))
                                                                   for v in pair) or not pair[0] <= pair[1]):
                raise CaseError(f"ranges.{key} = {pair!r}: expected [low, high] with low <= high in {where}")
            low = max(pair[0], param.low) if param.low is not None else pair[0]
            high = min(pair[1], param.high) if param.high is not None else pair[1]
            ranged = Param(param.default, param.doc + " (verified range)", param.kind, param.unit, low, high,
                           param.open_low and low == param.low, param.open_high and high == param.high,
                           param.choices, param.plausible, param.check)
        try:
            ranged.coerce(key, param.default)  # the file's own value inside its range
        except CaseError:
            if key in given:
                raise
            raise CaseError(f"{key}: required in {where} by its [ranges] entry (its default would run unverified); "
                            f"allowed: {ranged.allowed()} ({param.doc})") from None
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
            value = param.coerce(key, given[field], typed=True)
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
    for collection in ("materials", "interfaces", "sheets", "impactors", "loads", "supports", "delaminations"):
        key = KIND_KEY[collection][0]
        for kind, fields in KINDS[collection].items():
            table(f"[{collection}.NAME]  {key} = {kind!r}", fields)
    table("[laminates.NAME]", LAMINATE)
    for name, sec in SECTIONS.items():
        table(f"[{name}]", sec)
    for name, sec in PANEL.items():
        table(f"[{name}]  geometry.shape = 'panel'", sec)
    lines.append("[materials.NAME]  kind = 'ply' with geometry.shape = 'panel': " + ", ".join(ELASTIC_PLY)
                 + " (the plies do not crack)\n")
    for kind, probe in probe_kinds.items():
        table(f"[probes.NAME]  kind = {kind!r}: {probe.doc}", probe.fields)
    for kind, form in closed_forms.items():
        table(f"[checks.NAME]  closed_form = {kind!r}: {form.doc}", form.fields)
    return "\n".join(lines)
