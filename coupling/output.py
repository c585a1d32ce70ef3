"""The run directory of the output contract (ARCHITECTURE.md).

Everything is written into ``<DIR>.partial/`` and the directory is renamed to ``<DIR>`` only
when the run has finished (ok, unstable or error), so a killed run never leaves a
half-written result where a finished one is expected.
"""
from __future__ import annotations

import json
import os
import shutil
from contextlib import contextmanager
from pathlib import Path

import h5py
import meshio
import numpy as np

from .simulation import FieldFrame

# engines' scratch files (data file, log) inside the run directory, so a killed run leaves
# nothing in /tmp (dem_region.backends.base.scratch_dir reads FEMDEM_SCRATCH_DIR)
SCRATCH = "engine-scratch"


@contextmanager
def _cwd(path: Path):
    # meshio's TimeSeriesWriter puts its .h5 next to the current directory, not the .xdmf
    old = os.getcwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(old)


class RunOutput:
    """Writer for one run directory: fields over time, then history, summary and plots.

    The ``.partial`` directory is created with one mkdir, which fails when another run holds
    it, so two runs never share or delete each other's directories. With ``unique`` (the
    default --out) a clash adds ``-2``, ``-3``, ... to the name instead of failing.
    """

    def __init__(self, final_dir: Path, resume: bool = False, unique: bool = False):
        final = Path(final_dir).absolute()  # a worker process writes here from its own cwd
        for n in range(2, 10_000):
            self.final, self.dir = final, final.with_name(final.name + ".partial")
            if resume:
                if not self.dir.is_dir():
                    raise FileNotFoundError(str(self.dir))
                break
            if self.final.exists() and (not self.final.is_dir() or any(self.final.iterdir())):
                if unique:
                    final = Path(f"{final_dir}-{n}").absolute()
                    continue
                raise FileExistsError(str(self.final))
            try:
                self.dir.parent.mkdir(parents=True, exist_ok=True)
                self.dir.mkdir()
                break
            except FileExistsError:
                if not unique:
                    raise FileExistsError(str(self.dir)) from None
                final = Path(f"{final_dir}-{n}").absolute()
        (self.dir / "plots").mkdir(exist_ok=True)
        self._xdmf = None

    def frame(self, t: float, f: FieldFrame) -> None:
        """Append one XDMF frame (the mesh is written with the first frame)."""
        with _cwd(self.dir):
            if self._xdmf is None:
                self._xdmf = meshio.xdmf.TimeSeriesWriter("fields.xdmf").__enter__()
                self._xdmf.write_points_cells(f.points, f.cells)
            self._xdmf.write_data(t, point_data=f.point_data, cell_data=f.cell_data)

    def finish(self, summary: dict, history: dict[str, np.ndarray], keep_checkpoint: bool = False) -> Path:
        """Write history.h5 and summary.json, close the fields, publish the directory; the
        last checkpoint stays with a run that did not finish well (to restart it)."""
        if self._xdmf is not None:
            with _cwd(self.dir):
                self._xdmf.__exit__()
        with h5py.File(self.dir / "history.h5", "w") as h5:
            g = h5.create_group("history")
            for k, v in history.items():
                g.create_dataset(k, data=np.asarray(v, dtype=float))
            g.attrs["units"] = "SI"
        tmp = self.dir / "summary.json.tmp"
        tmp.write_text(json.dumps(summary, indent=2, default=_jsonable) + "\n")
        os.replace(tmp, self.dir / "summary.json")
        for name in ("checkpoint.old", "checkpoint.tmp") + (() if keep_checkpoint else ("checkpoint",)):
            shutil.rmtree(self.dir / name, ignore_errors=True)
        shutil.rmtree(self.dir / SCRATCH, ignore_errors=True)
        if self.final.exists():
            self.final.rmdir()  # empty (checked in __init__); fails rather than merge into another run's
        os.replace(self.dir, self.final)
        return self.final


def _jsonable(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.bool_):
        return bool(x)
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(f"not JSON serialisable: {type(x)}")
