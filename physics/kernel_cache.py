"""Where numba keeps the compiled kernels: a directory per version of the files that define them.

numba's disk cache checks a kernel against the file that defines it (its time stamp and size),
not against the files of the kernels it calls and compiles into itself. After the Hoffman
index's shear terms changed in kernels.py, law_kernels' cached bonds pass (unchanged file) kept
the old index and ran it without a word: the fused ply bonds' forces 33 x off the reference in
tests/test_law_kernels.py. The same would meet a user whose update changed one kernel file and
not its callers. Here the cache directory is named by a digest of every file that defines
kernels, so a change to any of them compiles anew. Kernels call only kernels (and numpy), so
those files are all the compiled code depends on. Standard library only: the directory must be
set before numba is imported.
"""
from __future__ import annotations

import hashlib
import os
import re
import shutil
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("physics", "fem_region", "dem_region", "interfaces", "coupling")
# what marks a file that defines compiled kernels (the project's decorator, or numba's own)
MARKERS = (b"compiled import kernel", b"@njit", b"njit(")
PREFIX = "kernels-"
UNUSED_DAYS = 14  # another version's directory, untouched this long, is removed
# numba's own directories, one per package directory and checkout (name_<sha1 of its path>), that
# versions before these digests wrote straight into the project's cache (~150 MB on a developer's
# machine); removed from the project's own cache directory only, once unused as long
LEGACY = re.compile(r"(physics|fem_region|dem_region|interfaces|coupling|elements|backends|study|scenes|participants)"
                    r"_[0-9a-f]{40}")


def sources_digest(root: Path = ROOT) -> str:
    """16 hex digits: the digest of the paths and contents of the files under ``root``'s
    packages that define kernels."""
    h = hashlib.sha256()
    for package in PACKAGES:
        for f in sorted((root / package).rglob("*.py")):
            text = f.read_bytes()
            if any(m in text for m in MARKERS):
                h.update(f.relative_to(root).as_posix().encode() + b"\0" + text + b"\0")
    return h.hexdigest()[:16]


def cache_dir(base: str | os.PathLike, root: Path = ROOT, own: bool = False) -> Path:
    """``base`` / kernels-<digest of the sources>, created and marked as used now. A ``base``
    that is itself such a directory (inherited by a child process) is taken as its parent.
    Other versions' directories not used for UNUSED_DAYS days are removed; with ``own`` (the
    project's default directory, not one a user named) the old layout's directories too."""
    base = Path(base)
    if base.name.startswith(PREFIX):
        base = base.parent
    mine = base / f"{PREFIX}{sources_digest(root)}"
    mine.mkdir(parents=True, exist_ok=True)
    os.utime(mine)
    old = time.time() - UNUSED_DAYS * 86400
    try:
        stale = [d for d in base.iterdir() if d.name.startswith(PREFIX) or (own and LEGACY.fullmatch(d.name))]
    except OSError:  # (a directory one may write but not list: nothing is pruned)
        stale = []
    for d in stale:
        try:
            if d != mine and d.is_dir() and d.stat().st_mtime < old:
                shutil.rmtree(d, ignore_errors=True)
        except OSError:  # (removed meanwhile by another process)
            pass
    return mine
