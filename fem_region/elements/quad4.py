"""Bilinear quadrilateral (Q4): 2x2 Gauss (full), 1 point (reduced / selective shear)."""
import skfem

from .element_type import ElementType

QUAD4 = ElementType("quad4", 2, skfem.MeshQuad, skfem.ElementQuad1, 2, (0.5, 0.5), 1.0)
