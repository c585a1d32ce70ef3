"""Case files: TOML in SI units, validated against the scene's schema before anything runs.

A case file names its scene in ``[case] scene = "..."``; every other table holds parameters
whose flat dotted keys (``material.E``) the scene declares. Bundled cases live under
``cases/`` and are addressed by file stem (``bar_wave``) or by path.
"""
from __future__ import annotations

import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .params import CaseError, Param, flatten, resolve
from .scenes import SCENES, Scene
from .study import Study, renamed
from .study.schema import is_study

CASES_DIR = Path(__file__).resolve().parent.parent / "cases"
MODES = ("coupled", "fem", "dem")
ENGINES = ("yade", "liggghts", "lammps")
DEFAULT_ENGINE = "liggghts"  # the fastest path (README "Engines")
CASE_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}")

# Parameters every scene has (the clock, outputs and run-time guards).
COMMON: dict[str, Param] = {
    "clock.safety": Param(0.9, "fraction of the stable step used", low=0.0, high=1.0, open_low=True),
    "clock.dt": Param(0.0, "time step; 0 = safety x stable step; above the stable step is refused", unit="s", low=0.0),
    "clock.t_end": Param(0.0, "end time; 0 = the scene's own default", unit="s", low=0.0),
    "clock.max_steps": Param(10_000_000, "largest number of clock steps a run may take (a run that "
                             "needs more is refused before it starts, with its estimate)", kind="int", low=1,
                             high=10**12),
    "clock.substeps": Param(0, "DEM steps per FEM step; 0 = automatic", kind="int", low=0, high=1000),
    "output.history_every": Param(0, "clock steps between history samples; 0 = about 1000 samples; one that leaves "
                                  "the run fewer than 10 samples is refused", kind="int", low=0),
    "output.field_frames": Param(20, "number of XDMF frames", kind="int", low=0, high=10000),
    "output.checkpoint_every": Param(0, "clock steps between checkpoints; 0 = a tenth of runs of 5,000 "
                                     "steps or more, none for shorter ones", kind="int", low=0),
    "dem.process": Param("auto", "where the DEM engine runs: auto (in-process for yade/liggghts, a worker "
                         "process for lammps), in-process, or worker", kind="str",
                         choices=("auto", "in-process", "worker")),
    "dem.ranks": Param(1, "MPI ranks of the DEM engine inside its worker (lammps only; its own mpiexec)",
                       kind="int", low=1, high=64),
    "guards.energy_growth": Param(0.05, "stop when the energy balance error exceeds this fraction", low=0.0, open_low=True),
}


@dataclass
class Case:
    """A validated case: its scene, resolved parameters (flat dotted keys, SI) and source."""

    name: str
    scene: Scene
    parameters: dict[str, Any]
    path: Path
    description: str
    given: frozenset = frozenset()  # keys set by --set (the case file's own are meant for every mode)


def bundled_cases() -> dict[str, Path]:
    """Stem -> path of every case file under cases/ (recursively)."""
    return {p.stem: p for p in sorted(CASES_DIR.rglob("*.toml"))}


def find_case(name_or_path: str) -> Path:
    if not name_or_path.strip():  # (Path('') is the working directory)
        raise CaseError(f"CASE = {name_or_path!r}: empty; allowed: a bundled case name or a .toml path")
    p = Path(name_or_path)
    if p.suffix == ".toml" or p.exists() or "/" in name_or_path:
        if p.is_dir():
            raise CaseError(f"CASE = {name_or_path!r}: is a directory; allowed: a case file (.toml) or a bundled case name")
        if not p.is_file():
            raise CaseError(f"CASE = {name_or_path!r}: no such case file")
        return p
    cases = bundled_cases()
    if name_or_path not in cases:
        raise CaseError(f"CASE = {name_or_path!r}: not a file and not a bundled case; "
                        f"bundled: {', '.join(cases)}")
    return cases[name_or_path]


def load_case(name_or_path: str, overrides: dict[str, Any] | None = None, where: str = "--set") -> Case:
    """Read, validate and resolve a case; ``overrides`` are --set values (strings allowed);
    where: the option that gave them, for the error line (a bench's --sweep)."""
    path = find_case(name_or_path)
    data = _parse(path)
    if is_study(data):
        return _load_study(path, data, overrides, where)
    meta = data.pop("case", None)
    if not isinstance(meta, dict) or "scene" not in meta:
        raise CaseError(f"{path}: case.scene missing; allowed scenes: {', '.join(SCENES)}")
    extra = set(meta) - {"scene", "description", "name"}
    if extra:
        raise CaseError(f"case.{sorted(extra)[0]}: unknown key in {path.name}; allowed: scene, name, description")
    scene_name = meta["scene"]
    if not isinstance(scene_name, str) or scene_name not in SCENES:
        raise CaseError(f"case.scene = {scene_name!r}: allowed {', '.join(SCENES)}")
    for key in ("name", "description"):
        if not isinstance(meta.get(key, ""), str):
            raise CaseError(f"case.{key} = {meta[key]!r}: expected a string")
    name = _case_name(meta, path)
    scene = SCENES[scene_name]
    schema = {**COMMON, **scene.PARAMETERS}
    params = resolve(schema, flatten(data), f"case file {path.name}", typed=True)
    if overrides:
        resolve(schema, overrides, where)  # unknown keys, bad values
        params.update({k: schema[k].coerce(k, v) for k, v in overrides.items()})
    return Case(name, scene, params, path.absolute(), meta.get("description", ""), frozenset(overrides or ()))


def _case_name(meta: dict, path: Path) -> str:
    """case.name, or the case file's name without .toml; it becomes the run directory's name:
    never a path, never outside runs/."""
    if "name" in meta:
        name, what = meta["name"], f"case.name = {meta['name']!r}"
    else:
        name, what = path.stem, f"the case file's name {path.name!r} (its case name, case.name not given)"
    if not isinstance(name, str) or not CASE_NAME.fullmatch(name):
        raise CaseError(f"{what}: allowed letters, digits and _ . - (not first), at most 100 characters "
                        "(or a case.name of them in the file)")
    return name


def _load_study(path: Path, data: dict, overrides: dict[str, Any] | None, where: str = "--set") -> Case:
    """A study file: its schema from its own tables, then the same resolution as a scene's."""
    meta = data.get("case", {})
    name = _case_name(meta if isinstance(meta, dict) else {}, path)
    study = Study(name, data, path.name)
    schema = {**COMMON, **study.PARAMETERS}
    given = flatten({k: v for k, v in data.items() if k not in ("case", "ranges")})
    params = resolve(schema, given, f"case file {path.name}", typed=True)
    if overrides:
        resolve(schema, overrides, where, renamed=lambda key: renamed(key, study))
        fixed = sorted(k for k in overrides if study.structural(k) and schema[k].coerce(k, overrides[k]) != params[k])
        if fixed:
            raise CaseError(f"{fixed[0]}: says what the table is; allowed: change it in the case file "
                            f"({path.name}), not with {where}")
        params.update({k: schema[k].coerce(k, v) for k, v in overrides.items()})
    study.resolve_files(params, path.absolute().parent)
    study.refuse_inconsistent(params, frozenset(overrides or ()))
    return Case(name, study, params, path.absolute(), study.DESCRIPTION, frozenset(overrides or ()))


# a zone's placement and growth: coupled runs only (a bench's reference run takes them from the
# coupled runs' --set, and ignores them)
ZONE_GROWTH = ("zone.grow", "zone.grow_at", "zone.grow_to", "zone.grow_every", "zone.conversion", "zone.placement",
               "zone.margin")


def input_digests(case_file: str | Path, parameters: dict) -> dict[str, str]:
    """{"case_file" or a parameter's key: sha256 of the file's bytes} of every file a run reads as
    its input: the case file and each file a parameter names (a mesh, a load curve: keys ending
    in "file", their paths resolved by load_case); "unreadable" for one that cannot be read. What
    a cached reference (bench) and a resumed run (run.resume) must find unchanged."""
    import hashlib
    files = {"case_file": case_file, **{k: v for k, v in parameters.items()
                                       if k.rsplit(".", 1)[-1].endswith("file") and isinstance(v, str) and v}}
    out = {}
    for key, path in files.items():
        try:
            out[key] = hashlib.sha256(Path(path).read_bytes()).hexdigest()
        except OSError:
            out[key] = "unreadable"
    return out


def refuse_ineffective(case: Case, mode: str, dem: str | None, reference: bool = False) -> None:
    """CaseError for a setting that would change nothing in this configuration (a user who
    sets it expects an effect): DEM and coupling keys of --set in a run without them, a
    growing zone's settings without zone.grow, a penalty stiffness with the kinematic tie.
    reference: a bench's reference run, which takes the compared runs' zone settings."""
    p = case.parameters
    if mode == "fem" and dem is not None:
        raise CaseError(f"--dem {dem}: --mode fem runs no DEM engine; allowed: leave --dem out")
    no_dem = ("dem.", "coupling.tie", "clock.substeps", "zone.half_width", "zone.shape", "zone.particle_size",
              "zone.window_", "zone.ply_failure")
    no_tie = ("coupling.tie", "clock.substeps", "zone.half_width")  # all-DEM: the zone is the whole body
    if not reference:
        no_dem, no_tie = no_dem + ZONE_GROWTH, no_tie + ZONE_GROWTH
    schema = {**COMMON, **case.scene.PARAMETERS}
    for key in sorted(k for k in case.given if p[k] != schema[k].default):  # the default changes nothing
        if mode == "fem" and key.startswith(no_dem) or mode == "dem" and key.startswith(no_tie):
            raise CaseError(f"{key}: has no effect in --mode {mode} (no {'DEM zone' if mode == 'fem' else 'FEM-DEM tie or zone edge'}); "
                            "allowed: leave it out, or another --mode")
    if mode == "coupled" and "zone.grow" in p and not p["zone.grow"]:  # a growth setting without growth
        # (other modes take the coupled runs' settings silently: a bench's reference run)
        for key in sorted(k for k in ("zone.grow_to", "zone.grow_every", "zone.conversion")
                          if k in case.given and p[k] != schema[k].default):
            raise CaseError(f"{key} = {p[key]!r}: has no effect without zone.grow = true; allowed: leave it out, "
                            "or set zone.grow = true")
        # (growth's and placement's; a plate's zone.shape = 'impactor' takes the margin too)
        auto = p.get("zone.placement") == "auto"
        used = {"zone.grow_at": auto, "zone.margin": auto or p.get("zone.shape") == "impactor"}
        for key in sorted(k for k in used if k in case.given and p[k] != schema[k].default and not used[k]):
            raise CaseError(f"{key} = {p[key]!r}: has no effect without zone.grow = true"
                            f"{' or zone.placement = auto' if 'zone.placement' in p else ''}; allowed: leave it "
                            "out, or set zone.grow = true")
    if "run.steps" in schema and "clock.t_end" in case.given and p["clock.t_end"]:
        raise CaseError(f"clock.t_end = {p['clock.t_end']:g}: has no effect, case {case.name} runs run.steps clock "
                        "steps; allowed: 0, or set run.steps")
    if p.get("coupling.tie") == "kinematic" and p.get("coupling.tie_penalty"):
        raise CaseError(f"coupling.tie_penalty = {p['coupling.tie_penalty']:g}: has no effect with "
                        "coupling.tie = 'kinematic'; allowed: 0, or coupling.tie = 'penalty'")


def _parse(path: Path) -> dict:
    """The TOML tables of a case file: UTF-8 (TOML's encoding; a byte-order mark is dropped),
    or UTF-16 / UTF-32 marked by their byte-order mark; anything else is refused."""
    import codecs
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise CaseError(f"CASE = {str(path)!r}: cannot be read ({exc.strerror}); allowed: a readable case file") from None
    for bom, enc in ((codecs.BOM_UTF32_LE, "utf-32"), (codecs.BOM_UTF32_BE, "utf-32"), (codecs.BOM_UTF8, "utf-8-sig"),
                     (codecs.BOM_UTF16_LE, "utf-16"), (codecs.BOM_UTF16_BE, "utf-16")):
        if raw.startswith(bom):
            break
    else:
        enc = "utf-8"
    try:
        text = raw.decode(enc)
    except UnicodeDecodeError as exc:
        raise CaseError(f"CASE = {str(path)!r}: not {enc.upper()} text (byte {raw[exc.start]:#04x} at offset "
                        f"{exc.start}); allowed: a UTF-8 TOML file") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"CASE = {str(path)!r}: not valid TOML ({exc})") from None
