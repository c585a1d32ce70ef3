"""Trilinear hexahedron (Hex8): 2x2x2 Gauss (full), 1 point (reduced / selective shear)."""
import skfem

from .element_type import ElementType

HEX8 = ElementType("hex8", 3, skfem.MeshHex, skfem.ElementHex1, 2, (0.5, 0.5, 0.5), 1.0)
