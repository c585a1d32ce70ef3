"""The run directory of the output contract (ARCHITECTURE.md).

Everything is written into ``<DIR>.partial/`` and the directory is renamed to ``<DIR>`` only
when the run has finished (ok, unstable or error), so a killed run never leaves a
half-written result where a finished one is expected.
"""
from __future__ import annotations

import errno
import fcntl
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
FRAMES = "frames"  # field frames stored one file each until the run finishes


@contextmanager
def _cwd(path: Path):
    # meshio's TimeSeriesWriter puts its .h5 next to the current directory, not the .xdmf
    old = os.getcwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(old)


class RunInProgress(FileExistsError):
    """Another living process holds this run directory."""


class RunOutput:
    """Writer for one run directory: fields over time, then history, summary and plots.

    The ``.partial`` directory is created with one mkdir, which fails when another run holds
    it, so two runs never share or delete each other's directories. With ``unique`` (the
    default --out) a clash adds ``-2``, ``-3``, ... to the name instead of failing. The run
    holds a lock on ``run.lock`` while it lives (the kernel drops it when the process dies,
    however it dies), so a resume never takes over a run that is still going.
    ``resume``: continue a stopped run's directory (from its checkpoint, or with ``restart``
    from the beginning when it stopped before its first checkpoint).
    """

    def __init__(self, final_dir: Path, resume: bool = False, unique: bool = False, restart: bool = False):
        final = Path(final_dir).absolute()  # a worker process writes here from its own cwd
        if final.is_symlink():  # the run is published by renaming DIR.partial to DIR, which a link
            final = final.resolve()  # is not: it goes where the link points (made there if dangling)
        final_dir = final
        self.made: list[Path] = []
        for parent in final.parents:
            if parent.exists():
                if not parent.is_dir():
                    raise NotADirectoryError(str(parent))
                break
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
                self.made = [d for d in reversed(self.dir.parents) if not d.exists()]  # to remove on bad input
                self.dir.parent.mkdir(parents=True, exist_ok=True)
                self.dir.mkdir()
                break
            except FileExistsError:
                if not unique:
                    raise FileExistsError(str(self.dir)) from None
                final = Path(f"{final_dir}-{n}").absolute()
        self._lock = open(self.dir / "run.lock", "a")
        try:
            fcntl.flock(self._lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            self._lock.close()
            raise RunInProgress(str(self.dir)) from None
        if restart:  # nothing of the stopped attempt is kept but its run.json
            for child in self.dir.iterdir():
                if child.name not in ("run.lock", "run.json"):
                    shutil.rmtree(child) if child.is_dir() else child.unlink()
        (self.dir / "plots").mkdir(exist_ok=True)
        self._frames = 0

    def discard(self) -> None:
        """Bad input found after the directory was made: remove it, and the parents it made."""
        self._lock.close()
        shutil.rmtree(self.dir, ignore_errors=True)
        for d in reversed(self.made):
            try:
                d.rmdir()
            except OSError:
                break

    def keep_frames_until(self, t_end: float) -> None:
        """Resuming: drop the stopped attempt's frames after t_end (s), the checkpoint's time;
        the run writes them again (and the XDMF of an attempt that ended with an error)."""
        for name in [*self.dir.glob("fields*.xdmf"), *self.dir.glob("fields*.h5")]:
            name.unlink(missing_ok=True)
        d, used = self.dir / FRAMES, set()
        if (d / "mesh.h5").exists():  # the one mesh file of a run begun before meshes were numbered
            os.replace(d / "mesh.h5", d / "mesh-000.h5")
        for f in sorted(d.glob("frame-*.h5")):
            with h5py.File(f, "r") as h5:
                late = float(h5.attrs["time"]) > t_end * (1 + 1e-12)
                mesh = str(h5.attrs.get("mesh", "mesh-000.h5"))
            f.unlink() if late else used.add(mesh)
        for mesh in d.glob("mesh-*.h5"):  # a grown zone's mesh the run will write again
            if mesh.name not in used:
                mesh.unlink()
        self._frames = len(list(d.glob("frame-*.h5")))

    def frame(self, t: float, f: FieldFrame) -> None:
        """Store one field frame: its own small HDF5 file, published by a rename, so a kill
        keeps every frame written before it (the XDMF is assembled by ``finish``)."""
        d = self.dir / FRAMES
        d.mkdir(exist_ok=True)
        mesh = self._mesh_of(d, f)

        def fill(h5):
            h5.attrs["time"] = t
            h5.attrs["mesh"] = mesh
            for k, v in f.point_data.items():
                h5.create_dataset(f"point_data/{k}", data=v)
            for k, blocks in (f.cell_data or {}).items():
                for n, v in enumerate(blocks):
                    h5.create_dataset(f"cell_data/{k}/{n:03d}", data=v)
        _write_atomic(d / f"frame-{self._frames:06d}.h5", fill)
        self._frames += 1

    @staticmethod
    def _mesh_of(d: Path, f: FieldFrame) -> str:
        """The mesh file of frame ``f`` in the frames' directory ``d``: the last one if the
        frame's points and cells have its shapes, else a new one (a zone that grew: fields.xdmf
        then holds the frames up to the first growth, fields-1.xdmf the next zone's, ...)."""
        meshes = sorted(d.glob("mesh*.h5"))
        sig = lambda points, cells: (points.shape, [(k, v.shape) for k, v in cells.items()])
        if meshes:
            with h5py.File(meshes[-1], "r") as h5:
                cells = {k.split(":")[-1]: h5["cells"][k] for k in sorted(h5["cells"])}
                if sig(h5["points"], cells) == sig(f.points, f.cells):
                    return meshes[-1].name
        name = f"mesh-{len(meshes):03d}.h5"
        _write_atomic(d / name, lambda h5: (h5.create_dataset("points", data=f.points),
                                            [h5.create_dataset(f"cells/{n:03d}:{k}", data=v)
                                             for n, (k, v) in enumerate(f.cells.items())]))
        return name

    def _write_xdmf(self, keep_frames: bool) -> None:
        """fields.xdmf + fields.h5 (ParaView) from the stored frames, in time order, one pair
        per mesh (fields-1.xdmf, ... after a zone grew); the frames stay with a run that may
        be resumed."""
        d = self.dir / FRAMES
        files = sorted(d.glob("frame-*.h5"))
        if not files:
            return
        # meshio writes fields.h5 through HDF5, which a full device leaves half-closed (write_h5):
        # the room for it (what the frames and meshes take, and a margin) is asked for first
        need = 1.1 * sum(f.stat().st_size for f in d.iterdir()) + 2**20
        if shutil.disk_usage(self.dir).free < need:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(self.dir))
        groups: dict[str, list] = {}
        for f in files:
            with h5py.File(f, "r") as h5:
                groups.setdefault(str(h5.attrs.get("mesh", "mesh-000.h5")), []).append(f)
        for k, mesh in enumerate(groups):  # in the order the frames use them
            with h5py.File(d / mesh, "r") as h5:
                # blocks in the frame's order (HDF5 lists keys sorted: the index prefix keeps the
                # order the cell data follows)
                points, cells = h5["points"][:], {k.split(":")[-1]: h5["cells"][k][:] for k in sorted(h5["cells"])}
            with _cwd(self.dir), meshio.xdmf.TimeSeriesWriter(f"fields{f'-{k}' if k else ''}.xdmf") as w:
                w.write_points_cells(points, cells)
                for f in groups[mesh]:
                    with h5py.File(f, "r") as h5:
                        pd = {k: v[:] for k, v in h5.get("point_data", {}).items()}
                        cd = {k: [g[n][:] for n in sorted(g)] for k, g in h5.get("cell_data", {}).items()}
                        w.write_data(float(h5.attrs["time"]), point_data=pd, cell_data=cd or None)
        if not keep_frames:
            shutil.rmtree(d)

    def finish(self, summary: dict, history: dict[str, np.ndarray], keep_checkpoint: bool = False) -> Path:
        """Write history.h5 and summary.json, close the fields, publish the directory; the
        last checkpoint stays with a run that did not finish well (to restart it)."""
        self._write_xdmf(keep_frames=keep_checkpoint)
        def fill(h5):
            g = h5.create_group("history")
            for k, v in history.items():
                g.create_dataset(k, data=np.asarray(v, dtype=float))
            g.attrs["units"] = "SI"
        write_h5(self.dir / "history.h5", fill)
        write_json(self.dir / "summary.json", summary, indent=2)
        for name in ("checkpoint.old", "checkpoint.tmp") + (() if keep_checkpoint else ("checkpoint",)):
            shutil.rmtree(self.dir / name, ignore_errors=True)
        shutil.rmtree(self.dir / SCRATCH, ignore_errors=True)
        (self.dir / "run.lock").unlink(missing_ok=True)
        if self.final.exists():
            self.final.rmdir()  # empty (checked in __init__); fails rather than merge into another run's
        os.replace(self.dir, self.final)
        self._lock.close()
        return self.final


def as_json(obj):
    """obj as write_json writes it and json reads it back (nan as None, tuples as lists, numpy
    numbers as Python's): for comparing a value with one read from a run's files."""
    return json.loads(json.dumps(_no_nan(obj), default=_jsonable, allow_nan=False))


def write_json(path: Path, obj, indent: int = 1) -> None:
    """path <- obj as strict JSON (a quantity never reached, nan, as null: a bare NaN is not JSON
    and strict readers refuse the file), through a temporary renamed over it."""
    tmp = path.with_name(path.name + ".tmp")
    try:
        tmp.write_text(json.dumps(_no_nan(obj), indent=indent, default=_jsonable, allow_nan=False) + "\n")
    except BaseException:
        tmp.unlink(missing_ok=True)  # (a full device: nothing half-written left beside the file)
        raise
    os.replace(tmp, path)


def _no_nan(x):
    """JSON has no NaN or infinity: a quantity that was never reached is written as null."""
    if isinstance(x, dict):
        return {k: _no_nan(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_no_nan(v) for v in x]
    if isinstance(x, (float, np.floating)) and not np.isfinite(x):
        return None
    if isinstance(x, np.ndarray):
        return _no_nan(x.tolist())
    return x


def write_h5(path: Path, fill, fsync: bool = False) -> None:
    """path <- the HDF5 file ``fill(h5)`` makes, built in memory and written in one go. On a
    full device the write fails as any file's does, and what it wrote is removed: HDF5 failing
    to flush its own file left it half-closed, and freeing that file crashed the process
    (segmentation fault, after h5py's tracebacks on the terminal)."""
    with h5py.File(path.name, "w", driver="core", backing_store=False) as h5:
        fill(h5)
        h5.flush()
        image = h5.id.get_file_image()
    try:
        with open(path, "wb") as f:
            f.write(image)
            if fsync:
                os.fsync(f.fileno())
    except BaseException:
        path.unlink(missing_ok=True)
        raise


def _write_atomic(path: Path, fill) -> None:
    tmp = path.with_suffix(".tmp")
    write_h5(tmp, fill)
    os.replace(tmp, path)


def _jsonable(x):
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, np.bool_):
        return bool(x)
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, os.PathLike):
        return str(x)
    raise TypeError(f"not JSON serialisable: {type(x)}")
