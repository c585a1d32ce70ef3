"""Case files: TOML in SI units, validated against the scene's schema before anything runs.

A case file names its scene in ``[case] scene = "..."``; every other table holds parameters
whose flat dotted keys (``material.E``) the scene declares. Bundled cases live under
``cases/`` and are addressed by file stem (``bar_wave``) or by path.
"""
from __future__ import annotations

import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .params import CaseError, Param, flatten, resolve
from .scenes import SCENES, Scene

CASES_DIR = Path(__file__).resolve().parent.parent / "cases"
MODES = ("coupled", "fem", "dem")
ENGINES = ("yade", "liggghts", "lammps")

# Parameters every scene has (the clock, outputs and run-time guards).
COMMON: dict[str, Param] = {
    "clock.safety": Param(0.9, "fraction of the stable step used", low=0.0, high=1.0, open_low=True),
    "clock.dt": Param(0.0, "time step; 0 = safety x stable step; above the stable step is refused", unit="s", low=0.0),
    "clock.t_end": Param(0.0, "end time; 0 = the scene's own default", unit="s", low=0.0),
    "clock.substeps": Param(0, "DEM steps per FEM step; 0 = automatic", kind="int", low=0, high=1000),
    "output.history_every": Param(0, "clock steps between history samples; 0 = about 1000 samples", kind="int", low=0),
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


def bundled_cases() -> dict[str, Path]:
    """Stem -> path of every case file under cases/ (recursively)."""
    return {p.stem: p for p in sorted(CASES_DIR.rglob("*.toml"))}


def find_case(name_or_path: str) -> Path:
    p = Path(name_or_path)
    if p.suffix == ".toml" or p.exists():
        if not p.is_file():
            raise CaseError(f"CASE = {name_or_path!r}: no such case file")
        return p
    cases = bundled_cases()
    if name_or_path not in cases:
        raise CaseError(f"CASE = {name_or_path!r}: not a file and not a bundled case; "
                        f"bundled: {', '.join(cases)}")
    return cases[name_or_path]


def load_case(name_or_path: str, overrides: dict[str, Any] | None = None) -> Case:
    """Read, validate and resolve a case; ``overrides`` are --set values (strings allowed)."""
    path = find_case(name_or_path)
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise CaseError(f"{path}: not valid TOML ({exc})") from None
    meta = data.pop("case", None)
    if not isinstance(meta, dict) or "scene" not in meta:
        raise CaseError(f"{path}: case.scene missing; allowed scenes: {', '.join(SCENES)}")
    extra = set(meta) - {"scene", "description", "name"}
    if extra:
        raise CaseError(f"case.{sorted(extra)[0]}: unknown key in {path.name}; allowed: scene, name, description")
    scene_name = meta["scene"]
    if scene_name not in SCENES:
        raise CaseError(f"case.scene = {scene_name!r}: allowed {', '.join(SCENES)}")
    scene = SCENES[scene_name]
    schema = {**COMMON, **scene.PARAMETERS}
    params = resolve(schema, flatten(data), f"case file {path.name}")
    if overrides:
        resolve(schema, overrides, "--set")  # unknown keys, bad values
        params.update({k: schema[k].coerce(k, v) for k, v in overrides.items()})
    return Case(meta.get("name", path.stem), scene, params, path, meta.get("description", ""))
