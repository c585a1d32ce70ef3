"""Element technology: one element per module, each an :class:`ElementType` record.

Shape functions, reference domains and quadrature come from scikit-fem; a record says which
skfem mesh/element pair it is and which quadrature rules give full and one-point integration.
"""
from .element_type import ElementType
from .hex8 import HEX8
from .quad4 import QUAD4
from .tet4 import TET4
from .tri3 import TRI3

ELEMENTS: dict[str, ElementType] = {e.name: e for e in (TRI3, QUAD4, TET4, HEX8)}
