"""Linear tetrahedron (Tet4): constant strain, one point exact."""
import skfem

from .element_type import ElementType

TET4 = ElementType("tet4", 3, skfem.MeshTet, skfem.ElementTetP1, 1, (0.25, 0.25, 0.25), 1 / 6)
