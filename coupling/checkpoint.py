"""Checkpoints: nested dicts of arrays and numbers in HDF5, published atomically.

A checkpoint is a directory ``checkpoint/`` in the run directory: ``state.h5`` (FEM,
orchestrator and clock-loop state) and the DEM engine's own restart file. It is written
as ``checkpoint.tmp/`` and swapped in by renames, so a run killed at any moment leaves
either the previous or the new checkpoint complete (``checkpoint.old/`` during the swap).
"""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import h5py
import numpy as np

from .output import write_h5


def _write(group: h5py.Group, tree: dict) -> None:
    for k, v in tree.items():
        if isinstance(v, dict):
            _write(group.create_group(k), v)
        elif isinstance(v, (list, tuple)) and v and not np.isscalar(v[0]):
            _write(group.create_group(k), {f"{i:06d}": x for i, x in enumerate(v)})
            group[k].attrs["sequence"] = True
        else:
            group.create_dataset(k, data=np.asarray(v))


def _read(group: h5py.Group):
    out = {}
    for k, v in group.items():
        out[k] = _read(v) if isinstance(v, h5py.Group) else (v[()] if v.shape == () else v[:])
    if group.attrs.get("sequence", False):
        return [out[k] for k in sorted(out)]
    return out


def write(run_dir: Path, state: dict, engine_save=None) -> None:
    """Write ``state`` (and the engine's own state via engine_save(directory)) as the run's
    checkpoint."""
    run_dir = Path(run_dir)
    tmp, final, old = run_dir / "checkpoint.tmp", run_dir / "checkpoint", run_dir / "checkpoint.old"
    shutil.rmtree(tmp, ignore_errors=True)
    tmp.mkdir()
    write_h5(tmp / "state.h5", lambda h5: _write(h5, state), fsync=True)
    if engine_save is not None:
        engine_save(tmp)
    if final.exists():
        shutil.rmtree(old, ignore_errors=True)
        os.replace(final, old)
    os.replace(tmp, final)
    shutil.rmtree(old, ignore_errors=True)


def latest(run_dir: Path) -> Path | None:
    """The newest complete checkpoint directory of a run (or None): one whose state.h5 opens
    and holds the clock loop's and the simulation's state."""
    for name in ("checkpoint", "checkpoint.old"):
        d = Path(run_dir) / name
        if _complete(d):
            return d
    return None


def _complete(d: Path) -> bool:
    try:
        with h5py.File(d / "state.h5", "r") as h5:
            return "loop" in h5 and "simulation" in h5 and "step" in h5["loop"]
    except (OSError, KeyError):
        return False


def corrupt(run_dir: Path) -> str | None:
    """Which checkpoint file of a run is there but unreadable (for the error line), or None."""
    for name in ("checkpoint", "checkpoint.old"):
        f = Path(run_dir) / name / "state.h5"
        if f.exists() and not _complete(f.parent):
            return str(f)
    return None


def step_of(ck_dir: Path) -> int:
    """The clock step a checkpoint was taken at (without reading its state)."""
    with h5py.File(Path(ck_dir) / "state.h5", "r") as h5:
        return int(h5["loop"]["step"][()])


class Unusable(Exception):
    """A checkpoint whose files cannot be read back into the run's model (damaged, or its
    run.json edited since): bad input to a resume, not a defect."""

    def __init__(self, ck_dir, exc: Exception):
        why = " ".join(f"{type(exc).__name__}: {exc}".split())[:240]
        super().__init__(f"the checkpoint {ck_dir} does not fit this run's model or is damaged ({why})")


def read(ck_dir: Path) -> dict:
    with h5py.File(Path(ck_dir) / "state.h5", "r") as h5:
        return _read(h5)


def write_run_info(run_dir: Path, info: dict) -> None:
    """What a resume needs to rebuild the run: case file, mode, engine, parameters."""
    tmp = Path(run_dir) / "run.json.tmp"
    tmp.write_text(json.dumps(info, indent=1, default=lambda x: x.item() if hasattr(x, "item") else str(x)))
    os.replace(tmp, Path(run_dir) / "run.json")
