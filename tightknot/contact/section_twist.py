"""The sections' reference twist and its chain rule (the sectioned level).

Each vertex's section is stored in the frame of the edge it starts. Along the edge e before
it, the interpolation turns it into e's frame by Q^T(m_e), mode n by n m_e, where m_e is the
reference twist of the joint after e: the angle between the two edges' reference frames,
carried by time-parallel transport (Bergou et al. 2010 sec. 4.2). m_e is a function of the
joint's three vertices, so the level's energy E(x, c, m(x)) has the chain terms

* gradient: sum_e (dE/dm_e) grad m_e;
* Hessian: sum_e (dE/dm_e) Hess m_e + sum_e (grad m_e C_e^T + C_e grad m_e^T)
  + sum_{e, f} M_ef grad m_e grad m_f^T,

with C_e = d2E/(dm_e dy) over all dofs y and M_ef = d2E/(dm_e dm_f). The energy sees m_e
and the stored coefficients c of e's second vertex only through Q^T(m_e) c, so these follow
from the derivatives in c (the pass kernels' :func:`~tightknot.contact.sectioned_kernels.
twist_column`, the section energy's closed form): dE/dm = grad_c . (n J c), C = H[., c] n J c
+ (n J)^T grad_c on c's rows. ``grad m`` is Bergou et al. 2010 eq. 9 and ``Hess m`` that of
Jawed, Novelia & O'Reilly, "A primer on the kinematics of discrete elastic rods" (2018)
sec. 7, the formulas of the rod's own twist energy (:mod:`tightknot.rods.elastic_kernels`),
exact where the frames were last carried (the accepted state, where Newton asks for them).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from tightknot.rods.term import BlockHessian

#: Most node pairs (nodes^2) for which the chain's blocks are found in a dense table.
DENSE_KEYS = 1 << 22


def turn_direction(c: np.ndarray, modes: np.ndarray) -> np.ndarray:
    """d(Q^T(m) c)/dm at m = 0 for rows of coefficients ``c`` (R, K) [m]: n J c per mode,
    (a_n, b_n) -> n (-b_n, a_n) (``Q^T`` turns mode n by n m counterclockwise)."""
    out = np.empty_like(c)
    out[:, 0::2] = -modes * c[:, 1::2]
    out[:, 1::2] = modes * c[:, 0::2]
    return out


def _skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrices [v]x of rows ``v`` (R, 3)."""
    z = np.zeros(v.shape[0])
    return np.stack([np.stack([z, -v[:, 2], v[:, 1]], axis=1),
                     np.stack([v[:, 2], z, -v[:, 0]], axis=1),
                     np.stack([-v[:, 1], v[:, 0], z], axis=1)], axis=1)


def _sym_outer(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a b^T + b a^T for rows (R, 3)."""
    return np.einsum("ri,rj->rij", a, b) + np.einsum("ri,rj->rij", b, a)


def reference_twist_derivatives(x: np.ndarray, joint_vertex: np.ndarray
                                ) -> tuple[np.ndarray, np.ndarray]:
    """Gradient (J, 3, 3) and Hessian (J, 9, 9) [1/m, 1/m^2] of the reference twists of the
    joints with vertices ``joint_vertex`` (J, 3: before, at, after) over those vertices'
    positions ``x`` [m] (module docstring: Bergou 2010 eq. 9, Jawed et al. 2018 sec. 7)."""
    v = np.asarray(joint_vertex, dtype=np.int64)
    e0 = x[v[:, 1]] - x[v[:, 0]]
    e1 = x[v[:, 2]] - x[v[:, 1]]
    a = np.einsum("ij,ij->i", e0, e0)
    b = np.einsum("ij,ij->i", e1, e1)
    d = np.einsum("ij,ij->i", e0, e1)
    n0, n1 = np.sqrt(a), np.sqrt(b)
    nn = n0 * n1
    # as the rod's bend: a hairpin's S clamped so that the derivatives stay finite
    s = np.maximum(nn + d, 1e-12 * nn)
    kb = 2.0 * np.cross(e0, e1) / s[:, None]
    dm0 = kb / (2.0 * n0[:, None])
    dm1 = kb / (2.0 * n1[:, None])
    grad = np.stack([-dm0, dm0 - dm1, dm1], axis=1)
    t0 = e0 / n0[:, None]
    t1 = e1 / n1[:, None]
    chi = 1.0 + np.einsum("ij,ij->i", t0, t1)
    tt = (t0 + t1) / chi[:, None]
    h00 = (-0.25 / a)[:, None, None] * _sym_outer(kb, t0 + tt)
    h11 = (-0.25 / b)[:, None, None] * _sym_outer(kb, t1 + tt)
    h01 = (0.5 / nn)[:, None, None] * ((2.0 / chi)[:, None, None] * _skew(t0)
                                       - np.einsum("ri,rj->rij", kb, tt))
    h10 = np.transpose(h01, (0, 2, 1))
    # edge space (e0, e1) to the vertices: x_before -e0, x_at e0 - e1, x_after e1
    blocks = [[h00, -h00 + h01, -h01],
              [-h00 + h10, h00 - h01 - h10 + h11, h01 - h11],
              [-h10, h10 - h11, h11]]
    hess = np.concatenate([np.concatenate(row, axis=2) for row in blocks], axis=1)
    return grad, hess


@dataclass
class TwistParts:
    """An energy's derivatives in the end twists m_e of the edges (module docstring).

    Attributes:
        first: dE/dm_e [J] per edge (E,).
        col_edge, col_dof, col_value: the entries of C_e = d2E/(dm_e dy) [J per unit of y]
            as (edge, extended dof, value); repeated entries add up.
        pair_edge, pair_value: the entries of M_ef [J] as edge pairs (P, 2) and values;
            repeated entries add up.
    """

    first: np.ndarray
    col_edge: np.ndarray
    col_dof: np.ndarray
    col_value: np.ndarray
    pair_edge: np.ndarray
    pair_value: np.ndarray

    @staticmethod
    def join(parts: list[TwistParts]) -> TwistParts:
        """The parts of a sum of energies."""
        return TwistParts(sum(p.first for p in parts),
                          np.concatenate([p.col_edge for p in parts]),
                          np.concatenate([p.col_dof for p in parts]),
                          np.concatenate([p.col_value for p in parts]),
                          np.concatenate([p.pair_edge for p in parts]),
                          np.concatenate([p.pair_value for p in parts]))


class TwistChain:
    """The chain rule through the end twists of a model's section edges (module docstring).

    Args:
        edge_joint: the joint after each edge (-1: none, or the edge's section is rigid).
        joint_vertex: each joint's vertices (J, 3).
        vertex_dof: each vertex's first position dof among the model's dofs.
        node_dofs: each node's extended dofs (:class:`tightknot.rods.term.BlockHessian`).
        ext_count: the number of extended dofs (the model's and the term's).
    """

    def __init__(self, edge_joint: np.ndarray, joint_vertex: np.ndarray,
                 vertex_dof: np.ndarray, node_dofs: np.ndarray, ext_count: int) -> None:
        self.edges = np.flatnonzero(np.asarray(edge_joint) >= 0)
        self.joint_vertex = np.asarray(joint_vertex, dtype=np.int64)[
            np.asarray(edge_joint)[self.edges]]
        self.node_dofs = node_dofs
        self.ext_count = int(ext_count)
        self._row_of = np.full(np.asarray(edge_joint).size, -1, dtype=np.int64)
        self._row_of[self.edges] = np.arange(self.edges.size)
        pos = np.asarray(vertex_dof, dtype=np.int64)[self.joint_vertex][:, :, None] + np.arange(3)
        #: The extended dofs of each twist edge's joint positions (R, 9).
        self.joint_dofs = pos.reshape(-1, 9)
        #: Each extended dof's node and its index within the node's block (-1: none).
        self.dof_node = np.full(self.ext_count, -1, dtype=np.int64)
        self.dof_local = np.full(self.ext_count, -1, dtype=np.int64)
        nodes, width = node_dofs.shape
        has = node_dofs >= 0
        self.dof_node[node_dofs[has]] = np.repeat(np.arange(nodes), width).reshape(
            nodes, width)[has]
        self.dof_local[node_dofs[has]] = np.tile(np.arange(width), nodes).reshape(
            nodes, width)[has]

    def apply(self, x: np.ndarray, parts: TwistParts, g_x: np.ndarray,
              hess: BlockHessian | None) -> tuple[np.ndarray, BlockHessian | None]:
        """Add the chain terms of ``parts`` at positions ``x`` [m] to the gradient over the
        positions ``g_x`` (V, 3) [N] and to ``hess`` (the result's node pairs: ``hess``'s and
        those the terms add)."""
        r = self.edges.size
        if r == 0:
            return g_x, hess
        grad_m, hess_m = reference_twist_derivatives(x, self.joint_vertex)
        first = parts.first[self.edges]
        g_x = np.array(g_x, dtype=np.float64, copy=True)
        np.add.at(g_x, self.joint_vertex.ravel(),
                  (first[:, None, None] * grad_m).reshape(-1, 3))
        if hess is None:
            return g_x, None
        n = self.ext_count
        rows_g = np.repeat(np.arange(r), 9)
        big_g = sp.csr_matrix((grad_m.reshape(-1), (rows_g, self.joint_dofs.ravel())),
                              shape=(r, n))
        keep = self._row_of[parts.col_edge] >= 0
        big_c = sp.csr_matrix((parts.col_value[keep],
                               (self._row_of[parts.col_edge[keep]], parts.col_dof[keep])),
                              shape=(r, n))
        pe = self._row_of[parts.pair_edge]
        keep = (pe >= 0).all(axis=1)
        big_m = sp.csr_matrix((parts.pair_value[keep], (pe[keep, 0], pe[keep, 1])),
                              shape=(r, r))
        gc = (big_g.T @ big_c).tocsr()
        total = gc + gc.T + big_g.T @ (big_m @ big_g)
        # (dE/dm_e) Hess m_e over each joint's 9 position dofs
        jd = self.joint_dofs
        own = sp.csr_matrix(((first[:, None, None] * hess_m).ravel(),
                             (np.repeat(jd, 9, axis=1).ravel(), np.tile(jd, (1, 9)).ravel())),
                            shape=(n, n))
        coo = (total + own).tocoo()
        return g_x, self._merged(hess, coo.row.astype(np.int64), coo.col.astype(np.int64),
                                 coo.data)

    def _merged(self, hess: BlockHessian, rows: np.ndarray, cols: np.ndarray,
                vals: np.ndarray) -> BlockHessian:
        """``hess`` with the unique COO entries (rows, cols, vals) over the extended dofs
        added, its node pairs grown by theirs (every block of the result whole where
        ``hess``'s are: the chain's blocks reach past a node's position now and then, and a
        system's kept pattern is built again whenever a kept block grows; marked blocks,
        the bend shift's, keep their marks, grown by the entries added)."""
        nodes = self.node_dofs.shape[0]
        b = hess.blocks.shape[1]
        old = hess.keys[:, 0] * nodes + hess.keys[:, 1]
        new = self.dof_node[rows] * nodes + self.dof_node[cols]
        if nodes * nodes <= DENSE_KEYS:
            # node pairs marked in a dense table: sorted and unique without a sort
            mark = np.zeros(nodes * nodes, dtype=bool)
            mark[old] = True
            mark[new] = True
            keys = np.flatnonzero(mark)
            where = np.zeros(nodes * nodes, dtype=np.int64)
            where[keys] = np.arange(keys.size)
            at_old, at_new = where[old], where[new]
        else:
            keys, inverse = np.unique(np.concatenate([old, new]), return_inverse=True)
            at_old, at_new = inverse[:old.size], inverse[old.size:]
        blocks = np.zeros((keys.size, b, b))
        blocks[at_old] = hess.blocks
        # the entries are unique: a plain indexed add
        flat = blocks.reshape(-1)
        local_r, local_c = self.dof_local[rows], self.dof_local[cols]
        flat[(at_new * b + local_r) * b + local_c] += vals
        full_rows = full_cols = None
        if hess.full_rows is not None or hess.full_cols is not None:
            # marked blocks stay marked (rows and columns past a node's position that
            # may be nonzero): the input's marks and those of the entries added
            rows_in, cols_in = hess.masks()
            full_rows = np.zeros(keys.size, dtype=bool)
            full_cols = np.zeros(keys.size, dtype=bool)
            full_rows[at_old] = rows_in
            full_cols[at_old] = cols_in
            full_rows[at_new[local_r >= 3]] = True
            full_cols[at_new[local_c >= 3]] = True
        return BlockHessian(hess.node_dofs, np.stack([keys // nodes, keys % nodes], axis=1),
                            blocks, full_rows, full_cols, hess.low_rank)
