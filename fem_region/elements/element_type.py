from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ElementType:
    """A finite element as the explicit solver needs it.

    mesh_cls / element_cls: scikit-fem mesh and scalar element classes.
    full_order: skfem intorder for full integration.
    centroid: (dim,) centroid in skfem's reference domain; one_point_weight: its weight,
    the reference-domain volume (one-point rule, used for reduced and selective integration).
    """

    name: str
    dim: int
    mesh_cls: type
    element_cls: type
    full_order: int
    centroid: tuple[float, ...]
    one_point_weight: float

    def one_point_rule(self) -> tuple[np.ndarray, np.ndarray]:
        """(X (dim, 1), W (1,)) in skfem's reference domain."""
        return np.array(self.centroid, dtype=float)[:, None], np.array([self.one_point_weight])
