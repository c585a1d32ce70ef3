"""Node-to-face interfaces: a ply interface whose two sides are meshed independently.

The seed paper bonds its FE plies node to face: the gap of a contactor node is its normal
distance to the face it bears on and the tangential distance between its projection now and at
the start (its eq. (6)). Here each node of one side (the slave: the side with more nodes on the
plane, so every face of the other side is reached) is bonded to the point of the other side's
face that it lies on in the reference configuration, held at fixed face coordinates. That
point moves with the face's shape functions, x_q = sum_a N_a(xi_q) x_a, and the bond force on
it goes back to the face's nodes by the same weights, so:

- forces sum to zero (momentum) and the bond energy's gradient is what the nodes receive;
- a rigid motion of any size moves the point with the node: no separation, no force;
- a uniform traction reaches the slave nodes by their tributary areas (the patch test).

Coincident meshes give weights 1 and 0: the same bonds as doubled nodes
(``mesh.split_interfaces``). Planes normal to a coordinate axis (``axis``: 1 for the y of a 2D
slice, 2 for the z of a laminate); faces are element edges in 2D (Q4, T3), quadrilaterals (Hex8)
or triangles (Tet4) in 3D.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .mesh import interface_areas


@dataclass
class NodeToFace:
    """slave (k,): the bonded nodes; nodes (k, f) and weights (k, f): the face nodes of each
    slave's point and their shape functions there (rows sum to 1); slave_above (k,) bool: the
    slave is on the upper side (its bond's normal then points down, from the node to its point);
    area (k,) m^2 (2D: m per unit thickness): the slave's tributary share of the plane."""

    slave: np.ndarray
    nodes: np.ndarray
    weights: np.ndarray
    slave_above: np.ndarray
    area: np.ndarray

    def points(self, X: np.ndarray) -> np.ndarray:
        """(k, d) the points' positions from node positions X (n, d)."""
        return np.einsum("kf,kfd->kd", self.weights, X[self.nodes])

    @classmethod
    def coincident(cls, pairs: np.ndarray, area: np.ndarray, f: int) -> "NodeToFace":
        """Doubled nodes (pairs (k, 2) lower / upper) as node-to-face bonds with f face nodes
        (the upper node at weight 1), to join them with planes meshed apart (concat)."""
        nodes = np.repeat(pairs[:, 1:2], f, axis=1)
        weights = np.zeros((len(pairs), f))
        weights[:, 0] = 1.0
        return cls(pairs[:, 0].copy(), nodes, weights, np.zeros(len(pairs), bool), np.asarray(area, float))

    @classmethod
    def concat(cls, parts: list["NodeToFace"]) -> "NodeToFace":
        """The bonds of several planes as one set (their faces of one node count)."""
        return cls(*(np.concatenate([getattr(q, k) for q in parts]) for k in
                     ("slave", "nodes", "weights", "slave_above", "area")))


def faces_on_plane(p: np.ndarray, t: np.ndarray, elements: np.ndarray, axis: int, level: float,
                   tol: float) -> np.ndarray:
    """(nf, f) node ids of the faces that ``elements`` have on the plane p[axis] = level, each
    face's nodes in order round it (an edge's along it). p (dim, n) m; t (nodes, nel)."""
    faces = []
    for e in elements:
        nodes = t[np.abs(p[axis, t[:, e]] - level) < tol, e]
        if len(nodes) < p.shape[0]:  # only an edge or corner touches the plane
            continue
        q = np.delete(p[:, nodes], axis, axis=0).T
        if p.shape[0] == 2:
            order = np.argsort(q[:, 0])
        else:  # a plane polygon: its corners by angle about the centre
            c = q - q.mean(axis=0)
            order = np.argsort(np.arctan2(c[:, 1], c[:, 0]))
        faces.append(nodes[order])
    if not faces:
        raise ValueError(f"no element face on the plane {'xyz'[axis]} = {level:g} m")
    sizes = {len(f) for f in faces}
    if len(sizes) > 1:
        raise ValueError(f"faces of {sorted(sizes)} nodes on one plane: one element type per side")
    return np.array(faces, int)


def _local(q: np.ndarray, corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shape functions (m, f) of points q (m, dim - 1) on faces with corners (m, f, dim - 1) in
    the plane's coordinates, and how far (m,) each point lies outside its face in face
    coordinates (0 inside). Edges and triangles are linear; quadrilaterals bilinear (their
    inverse map by Newton's method)."""
    f = corners.shape[1]
    if corners.shape[2] == 1:  # an edge
        a, b = corners[:, 0, 0], corners[:, 1, 0]
        s = (q[:, 0] - a) / (b - a)
        N = np.column_stack([1 - s, s])
    elif f == 3:  # a triangle: barycentric coordinates
        e1, e2, r = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0], q - corners[:, 0]
        det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
        s = (r[:, 0] * e2[:, 1] - r[:, 1] * e2[:, 0]) / det
        u = (e1[:, 0] * r[:, 1] - e1[:, 1] * r[:, 0]) / det
        N = np.column_stack([1 - s - u, s, u])
    else:  # a quadrilateral, corners in order round it: x(s, u) bilinear on [0, 1]^2
        s, u = np.full(len(q), 0.5), np.full(len(q), 0.5)
        c0, c1, c2, c3 = (corners[:, k] for k in range(4))
        for _ in range(30):
            x = ((1 - s) * (1 - u))[:, None] * c0 + (s * (1 - u))[:, None] * c1 + (s * u)[:, None] * c2 \
                + ((1 - s) * u)[:, None] * c3
            xs = (1 - u)[:, None] * (c1 - c0) + u[:, None] * (c2 - c3)
            xu = (1 - s)[:, None] * (c3 - c0) + s[:, None] * (c2 - c1)
            r = q - x
            det = xs[:, 0] * xu[:, 1] - xs[:, 1] * xu[:, 0]
            ds = (r[:, 0] * xu[:, 1] - r[:, 1] * xu[:, 0]) / det
            du = (xs[:, 0] * r[:, 1] - xs[:, 1] * r[:, 0]) / det
            s, u = s + ds, u + du
            if np.max(np.abs(ds) + np.abs(du)) < 1e-14:
                break
        N = np.column_stack([(1 - s) * (1 - u), s * (1 - u), s * u, (1 - s) * u])
    outside = np.max(np.maximum(-N, 0.0), axis=1)
    return N, outside


def project(points: np.ndarray, p: np.ndarray, faces: np.ndarray, axis: int) -> tuple[np.ndarray, np.ndarray]:
    """(nodes (k, f), weights (k, f)): the face each of ``points`` (k, dim) m lies on, seen along
    ``axis``, and its shape functions there. A point beyond every face (an edge of the plane,
    round-off) takes the nearest face, its coordinates clamped into it. p (dim, n) m."""
    plane = [a for a in range(p.shape[0]) if a != axis]
    corners = p[plane][:, faces].transpose(1, 2, 0)  # (nf, f, dim - 1)
    q = np.asarray(points, float)[:, plane]
    tree = cKDTree(corners.mean(axis=1))
    near = tree.query(q, k=min(8, len(faces)))[1].reshape(len(q), -1)
    best_N, best_out = np.zeros((len(q), faces.shape[1])), np.full(len(q), np.inf)
    best_face = np.zeros(len(q), int)
    for col in near.T:
        N, out = _local(q, corners[col])
        better = out < best_out - 1e-12
        best_N[better], best_out[better], best_face[better] = N[better], out[better], col[better]
    N = np.clip(best_N, 0.0, None)
    N /= N.sum(axis=1, keepdims=True)
    return faces[best_face], N


def node_to_face(p: np.ndarray, t: np.ndarray, lower: np.ndarray, upper: np.ndarray, axis: int, level: float,
                 tol: float) -> NodeToFace:
    """The node-to-face bonds across the plane p[axis] = level between the elements ``lower``
    and ``upper`` (indices into t's columns) of one mesh whose two sides there share no node.
    p (dim, n) m; t (nodes, nel). The slave side is the one with more nodes on the plane (the
    lower on a tie); each slave stands for its tributary share of its own side's faces."""
    sides = [faces_on_plane(p, t, e, axis, level, tol) for e in (lower, upper)]
    on = [np.unique(f) for f in sides]
    if np.intersect1d(*on).size:
        raise ValueError("the two sides share nodes on the plane: node-to-face joins separate meshes")
    above = len(on[1]) > len(on[0])
    slave, master_faces = on[int(above)], sides[1 - int(above)]
    run = np.full(t.shape[1], -1)
    run[upper if above else lower] = 0
    area = interface_areas(p, t, run, [level], axis, tol)[slave]
    nodes, weights = project(p[:, slave].T, p, master_faces, axis)
    return NodeToFace(slave, nodes, weights, np.full(len(slave), above), area)
