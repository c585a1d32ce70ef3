"""Structured mesh generators (graded towards a region) and file meshes through meshio.

Returns scikit-fem meshes; coordinates in m.
"""
from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np
import skfem

from .elements import ELEMENTS


# Peak memory per node of a mesh in a run (coordinates, the sparse stiffness, element data,
# the state vectors and the XDMF frames)
BYTES_PER_NODE = 2048


class TooLarge(MemoryError):
    """A model that cannot fit in this machine's memory (bad input: the message has the count
    and the estimate)."""


def check_fits(n: float, bytes_each: float, items: str, what: str) -> None:
    """Refuse a model of ``n`` items (nodes, particles) before any array of them exists, when
    n x bytes_each exceeds the memory available now (MemAvailable of /proc/meminfo)."""
    need = float(n) * bytes_each
    try:
        with open("/proc/meminfo") as f:
            avail = next(float(line.split()[1]) * 1024 for line in f if line.startswith("MemAvailable:"))
    except (OSError, StopIteration):
        return
    if need > avail:
        raise TooLarge(f"{what}: {n:.3g} {items} need about {need / 2**30:.3g} GiB, {avail / 2**30:.3g} GiB "
                       "available; allowed: a coarser spacing or a smaller model")


def graded(a: float, b: float, n: int, ratio: float = 1.0, toward: float | None = None) -> np.ndarray:
    """n + 1 coordinates on [a, b]; element size grows by ``ratio`` per element away from ``toward``.

    ratio = 1 gives a uniform spacing; toward = a point in [a, b] where the elements are smallest.
    """
    check_fits(n, 8, "coordinates", f"{n} elements along one line")
    if ratio == 1.0 or toward is None:
        return np.linspace(a, b, n + 1)
    if not a <= toward <= b:
        raise ValueError(f"grading point {toward} outside [{a}, {b}]")
    # split n between the two sides in proportion to their lengths, grade each side
    nl = int(round(n * (toward - a) / (b - a)))
    left = _geometric(toward, a, nl, ratio) if nl else np.array([toward])
    right = _geometric(toward, b, n - nl, ratio) if n - nl else np.array([toward])
    return np.concatenate([left[::-1], right[1:]])


def _geometric(start: float, end: float, n: int, ratio: float) -> np.ndarray:
    h = ratio ** np.arange(n)
    return start + (end - start) * np.concatenate([[0.0], np.cumsum(h) / h.sum()])


def rectangle(xs: np.ndarray, ys: np.ndarray, element: str = "quad4") -> skfem.Mesh:
    """Tensor-product 2D mesh on the coordinate lines xs, ys (m); element 'quad4' or 'tri3'."""
    if element not in ("quad4", "tri3"):
        raise ValueError(f"element {element!r}: 2D elements are quad4, tri3")
    check_fits(float(len(xs)) * len(ys), BYTES_PER_NODE, "FEM nodes", f"a mesh of {len(xs) - 1} x {len(ys) - 1} elements")
    return ELEMENTS[element].mesh_cls.init_tensor(np.asarray(xs, float), np.asarray(ys, float))


def cut_rectangle(xs: np.ndarray, ys: np.ndarray, keep, crack_y: float | None = None,
                  crack_x_max: float = -np.inf, crack_x_min: float = -np.inf) -> skfem.Mesh:
    """Quad4 mesh on the lines xs, ys (m) with holes and a crack: cells whose centre (xc, yc)
    fails ``keep(xc, yc)`` are left out; nodes on the line y = crack_y with crack_x_min < x <=
    crack_x_max are doubled so the cells above and below the line do not share them (a
    traction-free crack; its tip nodes at crack_x_min stay shared)."""
    xs, ys = np.asarray(xs, float), np.asarray(ys, float)
    m = rectangle(xs, ys, "quad4")
    p, t = m.p.copy(), m.t.copy()
    centre = p[:, t].mean(axis=1)
    t = t[:, np.array([bool(keep(cx, cy)) for cx, cy in centre.T])]
    if crack_y is not None:
        tol = 1e-9 * (np.ptp(xs) + np.ptp(ys))
        on = np.flatnonzero((np.abs(p[1] - crack_y) < tol) & (p[0] <= crack_x_max + tol)
                            & (p[0] > crack_x_min + tol))
        twin = np.arange(p.shape[1])
        twin[on] = p.shape[1] + np.arange(on.size)
        p = np.hstack([p, p[:, on]])
        above = p[1, t].mean(axis=0) > crack_y
        t[:, above] = twin[t[:, above]]
    used = np.unique(t)
    renum = np.full(p.shape[1], -1)
    renum[used] = np.arange(used.size)
    return skfem.MeshQuad1(np.ascontiguousarray(p[:, used]), np.ascontiguousarray(renum[t]))


def box(xs: np.ndarray, ys: np.ndarray, zs: np.ndarray, element: str = "hex8") -> skfem.Mesh:
    """Tensor-product 3D mesh; element 'hex8' or 'tet4'."""
    if element not in ("hex8", "tet4"):
        raise ValueError(f"element {element!r}: 3D elements are hex8, tet4")
    check_fits(float(len(xs)) * len(ys) * len(zs), BYTES_PER_NODE, "FEM nodes",
               f"a mesh of {len(xs) - 1} x {len(ys) - 1} x {len(zs) - 1} elements")
    return ELEMENTS[element].mesh_cls.init_tensor(*(np.asarray(c, float) for c in (xs, ys, zs)))


def joined(*meshes: skfem.Mesh) -> tuple[skfem.Mesh, list[np.ndarray]]:
    """One mesh of several of one element type that share no node (their nodes and elements
    numbered in turn), and each part's element indices in it: parts meshed independently, e.g.
    the two sides of a node-to-face interface (fem_region.node_to_face)."""
    kinds = {type(m) for m in meshes}
    if len(kinds) != 1:
        raise ValueError(f"meshes of {sorted(k.__name__ for k in kinds)}: one element type")
    offsets = np.cumsum([0] + [m.p.shape[1] for m in meshes])
    first = np.cumsum([0] + [m.t.shape[1] for m in meshes])
    p = np.hstack([m.p for m in meshes])
    t = np.hstack([m.t + o for m, o in zip(meshes, offsets)])
    parts = [np.arange(a, b) for a, b in zip(first[:-1], first[1:])]
    return kinds.pop()(np.ascontiguousarray(p), np.ascontiguousarray(t)), parts


def read(path: str | Path) -> skfem.Mesh:
    """Any mesh meshio reads (Gmsh .msh, XDMF, VTK ...) as a scikit-fem mesh."""
    return skfem.Mesh.load(str(path))


def split_interfaces(p: np.ndarray, t: np.ndarray, run: np.ndarray, levels, axis: int,
                     tol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cohesive interfaces in a mesh: the nodes on each plane ``p[axis] = level`` (levels bottom
    up) doubled, the elements of the runs above it (``run`` (nel,) > k) switched to the twins.
    p (dim, n) m, t (nodes, nel); returns (p, t, pairs (k, 2) lower / upper node), the twins
    appended after the nodes in their order."""
    p, t, pairs = p.copy(), t.copy(), []
    for k, level in enumerate(levels):
        on = np.flatnonzero(np.abs(p[axis] - level) < tol)
        twin = np.arange(p.shape[1])
        twin[on] = p.shape[1] + np.arange(on.size)
        p = np.hstack([p, p[:, on]])
        above = run > k
        t[:, above] = twin[t[:, above]]
        pairs.append(np.column_stack([on, twin[on]]))
    return p, t, np.vstack(pairs) if pairs else np.zeros((0, 2), int)


def interface_areas(p: np.ndarray, t: np.ndarray, run: np.ndarray, levels, axis: int, tol: float) -> np.ndarray:
    """(n,) the interface area each node stands for: each element of run k shares its face on the
    plane p[axis] = levels[k] (its top) equally among that face's nodes; 2D faces are edges
    (length, per unit thickness), 3D faces plane polygons (area). p (dim, n) m, t (nodes, nel)."""
    area = np.zeros(p.shape[1])
    for k, level in enumerate(levels):
        elems = np.flatnonzero(run == k)
        on = np.abs(p[axis][t[:, elems]] - level) < tol  # (nodes, m)
        for e, mask in zip(elems, on.T):
            nodes = t[mask, e]
            if len(nodes) < p.shape[0]:  # no face on the plane (the element only touches it)
                continue
            q = np.delete(p[:, nodes], axis, axis=0).T  # the face in the plane's coordinates
            if p.shape[0] == 2:
                a = float(np.ptp(q[:, 0]))
            else:  # a plane polygon: order its corners by angle, shoelace
                c = q - q.mean(axis=0)
                q = q[np.argsort(np.arctan2(c[:, 1], c[:, 0]))]
                a = 0.5 * abs(float(np.dot(q[:, 0], np.roll(q[:, 1], -1)) - np.dot(q[:, 1], np.roll(q[:, 0], -1))))
            area[nodes] += a / len(nodes)
    return area


def read_gmsh(path: str | Path, part: str) -> tuple[skfem.Mesh, dict[str, np.ndarray]]:
    """The elements of physical group ``part`` of a Gmsh mesh (2D quadrangles or triangles,
    or 3D hexahedra or tetrahedra: the part's highest dimension) as a scikit-fem mesh, and
    every physical group's node coordinates {name: (k, dim)} (for supports and loads named in
    the file). ValueError (what is wrong, what the file holds) if the part is missing."""
    import meshio
    if not Path(path).is_file():
        raise OSError(f"no such file: {path}")
    said = io.StringIO()
    try:
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said):
            m = meshio.read(str(path))
    except (Exception, SystemExit) as exc:  # meshio's parsers raise what they meet (KeyError, IndexError,
        # ...); a file no parser takes, meshio reports on the terminal and exits the process
        why = " ".join(said.getvalue().split()) or f"{type(exc).__name__}: {exc}"
        raise ValueError(f"meshio cannot read it ({why})") from None
    kinds = {"quad": skfem.MeshQuad1, "triangle": skfem.MeshTri1, "hexahedron": skfem.MeshHex1,
             "tetra": skfem.MeshTet1}
    groups = {k: v for k, v in m.cell_sets.items() if not k.startswith("gmsh:")}
    if part not in groups:
        raise ValueError(f"no physical group {part!r}; the file names {', '.join(sorted(groups)) or 'none'}")
    blocks = [(c.type, c.data[ids]) for c, ids in zip(m.cells, groups[part]) if len(ids) and c.type in kinds]
    types = {t for t, _ in blocks}
    if not blocks or len(types) > 1:
        raise ValueError(f"physical group {part!r} must hold one element type of {', '.join(kinds)}; it holds "
                         f"{', '.join(sorted(types)) or 'none of them'}")
    (kind,) = types
    cells = np.vstack([b for _, b in blocks]).astype(np.int64)
    if kind == "hexahedron":  # Gmsh's (VTK's) corner order to scikit-fem's (as skfem.io.meshio reads it)
        cells = cells[:, [0, 4, 3, 1, 7, 5, 2, 6]]
    dim = 3 if kind in ("hexahedron", "tetra") else 2
    used = np.unique(cells)
    renumber = np.full(len(m.points), -1)
    renumber[used] = np.arange(used.size)
    mesh = kinds[kind](np.ascontiguousarray(m.points[used, :dim].T), np.ascontiguousarray(renumber[cells].T))
    nodes = {name: m.points[np.unique(np.concatenate([c.data[ids].ravel() for c, ids in zip(m.cells, sets)
                                                      if len(ids)] or [np.zeros(0, int)])).astype(int), :dim]
             for name, sets in groups.items()}
    return mesh, nodes


def element_name(mesh: skfem.Mesh) -> str:
    """The ElementType name matching a scikit-fem mesh."""
    for name, e in ELEMENTS.items():
        if isinstance(mesh, e.mesh_cls):
            return name
    raise ValueError(f"unsupported mesh type {type(mesh).__name__}")
