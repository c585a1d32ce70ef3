"""Constant-strain triangle (T3): one point is exact, so all integration modes coincide."""
import skfem

from .element_type import ElementType

TRI3 = ElementType("tri3", 2, skfem.MeshTri, skfem.ElementTriP1, 1, (1 / 3, 1 / 3), 0.5)
