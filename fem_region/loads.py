"""Load and motion histories: tabulated curves, smooth pulses, surface tractions."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np
import skfem

from physics.curves import Table

from .explicit import NodalLoad
from .region import FemRegion


def read_rows(path: str | Path) -> list[tuple[float, float]]:
    """The rows time,value of a two-column CSV file: UTF-8, '#' and blank lines skipped, a header
    before the data; ValueError (what is wrong, where, what is allowed) for anything else: a row
    not of two finite numbers (a nan, a third column, a stray line among the data), fewer than two
    rows, times not increasing. UnicodeDecodeError and OSError as reading raises them."""
    rows = []
    for number, line in enumerate(Path(path).read_bytes().decode("utf-8").splitlines(), 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        try:
            row = [float(x) for x in line.split(",")]
        except ValueError:
            if rows:  # a header comes first; a line that is not numbers after the data would be dropped
                raise ValueError(f"line {number} {line!r} is not numbers; allowed: a header, then rows time,value") \
                    from None
            continue
        if len(row) != 2 or not all(map(np.isfinite, row)):
            why = f"{len(row)} columns" if len(row) != 2 else "not finite"
            raise ValueError(f"line {number} {line!r}: {why}; allowed: two columns time,value of finite numbers")
        rows.append((row[0], row[1]))
    if len(rows) < 2:
        raise ValueError(f"{len(rows)} row(s) of numbers; allowed: at least two rows time,value")
    for a, b in zip(rows, rows[1:]):
        if b[0] <= a[0]:
            raise ValueError(f"time {b[0]:g} after {a[0]:g}; allowed: times increasing")
    return rows


def tabulated(path: str | Path, time_scale: float = 1.0, value_scale: float = 1.0) -> Callable[[float], float]:
    """Piecewise-linear curve from a two-column CSV (read_rows), zero outside.

    time_scale / value_scale convert the file's units to SI (ms -> s: 1e-3; kN -> N: 1e3).
    """
    t, f = np.array(read_rows(path)).T * [[time_scale], [value_scale]]
    return Table(t, f)


def sine_squared(peak: float, duration: float) -> Callable[[float], float]:
    """peak sin^2(pi t / duration) on [0, duration), zero after: a smooth one-sided pulse."""
    return lambda t: peak * np.sin(np.pi * t / duration) ** 2 if 0.0 <= t < duration else 0.0


def surface_traction(region: FemRegion, where: Callable[[np.ndarray], np.ndarray], traction,
                     curve: Callable[[float], float] = lambda t: 1.0) -> NodalLoad:
    """Consistent nodal forces of a uniform traction (dim,) Pa on the boundary facets whose
    midpoints satisfy ``where(x (dim, m)) -> bool (m,)``; multiplied by curve(t)."""
    facets = region.mesh.facets_satisfying(where, boundaries_only=True)
    if len(facets) == 0:
        raise ValueError("surface_traction: no boundary facet satisfies the predicate")
    fb = skfem.FacetBasis(region.mesh, region.etype.element_cls(), facets=facets)
    w = skfem.LinearForm(lambda v, _: v).assemble(fb) * region.thickness  # (n_nodes,) m^2
    nodes = np.flatnonzero(w)
    t = np.asarray(traction, float)
    dofs = (nodes[:, None] * region.dim + np.arange(region.dim)).ravel()
    return NodalLoad(dofs, (w[nodes][:, None] * t[None, :]).ravel(), curve)
