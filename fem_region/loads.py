"""Load and motion histories: tabulated curves, smooth pulses, surface tractions."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np
import skfem

from physics.curves import Table

from .explicit import NodalLoad
from .region import FemRegion


def tabulated(path: str | Path, time_scale: float = 1.0, value_scale: float = 1.0) -> Callable[[float], float]:
    """Piecewise-linear curve from a two-column CSV (header and '#' lines skipped), zero outside.

    time_scale / value_scale convert the file's units to SI (ms -> s: 1e-3; kN -> N: 1e3).
    """
    rows = []
    for line in Path(path).read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        try:
            rows.append([float(x) for x in line.split(",")[:2]])
        except ValueError:
            continue  # header
    if len(rows) < 2:
        raise ValueError(f"{path}: needs at least two numeric rows time,value")
    t, f = np.array(rows).T * [[time_scale], [value_scale]]
    if np.any(np.diff(t) <= 0):
        raise ValueError(f"{path}: times must increase")
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
