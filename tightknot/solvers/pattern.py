"""The sparsity patterns of a rod system's Hessian, owned by the system.

The elastic Hessian's pattern is fixed by the model's stencils and the set of free dofs, so
it is built once (:class:`SparsePattern`) together with, for every local stencil entry, its
slot in the CSC data array; the Warp kernels add straight into that data array
(``hess_slot`` arguments), and assembly costs no sort.

With contact the pattern is the elastic one plus 3 x 3 vertex blocks, kept from one Newton
iteration to the next (:class:`ContactPattern`).

Contact couples the positions of vertices that are far apart along the rod, so its entries
change with the contact set. Sending them as COO triplets (144 per edge pair) for scipy
to sort and sum would cost many times the elastic assembly. Here the pattern is a union of
vertex blocks that only grows while the contact set moves within it: the contact kernel
adds each block straight into the CSC data array through a sorted block table (binary
search in the kernel), and the pattern is rebuilt only when a block is missing (a new
contact), which is rare within a load step.

A block (vr, vc) is the 3 x 3 coupling of the positions of vertex vr (rows) and vc
(columns), restricted to the free components; blocks whose vertices are fully fixed stay in
the table with no slots, so that the kernel finds them.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import warp as wp

from tightknot.rods.model import Model


class SparsePattern:
    """CSC pattern of the elastic Hessian restricted to the free dofs.

    Attributes:
        free_dofs: global indices of the free dofs, shape (n,).
        free_index: free index of each global dof, -1 for fixed ones, shape (dof_count,).
        indptr, indices: CSC structure of the n x n matrix (symmetric, so also CSR).
        nnz: number of stored entries.
        joint_slot: data slot of each local joint entry (joint_count, 121), -1 if dropped.
        edge_slot: data slot of each local edge entry (edge_count, 36), -1 if dropped.
    """

    def __init__(self, model: Model, free_mask: np.ndarray) -> None:
        free_mask = np.asarray(free_mask, dtype=bool)
        if free_mask.shape != (model.dof_count,):
            raise ValueError(f"free_mask must have shape ({model.dof_count},)")
        self.free_dofs = np.flatnonzero(free_mask)
        n = self.free_dofs.size
        self.n = n
        self.free_index = np.full(model.dof_count, -1, dtype=np.int64)
        self.free_index[self.free_dofs] = np.arange(n)

        def local_keys(dofs: np.ndarray) -> np.ndarray:
            fi = np.where(dofs >= 0, self.free_index[np.maximum(dofs, 0)], -1)
            k = dofs.shape[1]
            rows = np.broadcast_to(fi[:, :, None], (fi.shape[0], k, k))
            cols = np.broadcast_to(fi[:, None, :], (fi.shape[0], k, k))
            # Column-major key, so that sorted unique keys are in CSC order.
            keys = np.where((rows >= 0) & (cols >= 0), cols * n + rows, -1)
            return keys.reshape(fi.shape[0], k * k)

        jk = local_keys(model.joint_dofs.astype(np.int64))
        ek = local_keys(model.edge_dofs.astype(np.int64))
        allk = np.concatenate([jk.ravel(), ek.ravel()])
        valid = allk >= 0
        uniq, inv = np.unique(allk[valid], return_inverse=True)
        slots = np.full(allk.shape, -1, dtype=np.int64)
        slots[valid] = inv
        self.joint_slot = np.ascontiguousarray(slots[: jk.size].reshape(jk.shape), np.int32)
        self.edge_slot = np.ascontiguousarray(slots[jk.size :].reshape(ek.shape), np.int32)
        cols = uniq // max(n, 1)
        self.indices = (uniq % max(n, 1)).astype(np.int32)
        self.indptr = np.searchsorted(cols, np.arange(n + 1)).astype(np.int32)
        self.nnz = int(uniq.size)
        diag_pos = np.full(n, -1, dtype=np.int64)
        rows = self.indices
        colsi = cols
        on_diag = rows == colsi
        diag_pos[colsi[on_diag]] = np.flatnonzero(on_diag)
        self.diag_slot = diag_pos

    def matrix(self, data: np.ndarray) -> sp.csc_matrix:
        """The n x n CSC matrix with this pattern and ``data`` (length nnz)."""
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))


class ContactPattern:
    """CSC pattern = elastic pattern U contact vertex blocks, with the kernel's block table.

    Attributes:
        n: free dof count.
        indptr, indices: CSC structure (symmetric).
        nnz: stored entries.
        elastic_slot: slot in this pattern of each entry of the elastic pattern.
        diag_slot: slot of each free dof's diagonal entry.
        block_keys: sorted keys vr * V + vc of the blocks, int64.
        block_cols: (K, 3) slot of the first free row of vr in the column of component j of
            vc, -1 where that component is fixed.
        vertex_rank: (V, 3) offset of each component among its vertex's free components,
            -1 where fixed.
    """

    def __init__(self, model: Model, elastic: SparsePattern,
                 blocks: np.ndarray | None = None) -> None:
        self.model = model
        self.elastic = elastic
        n = elastic.n
        self.n = n
        nv = model.vertex_count
        self.vertex_count = nv
        pos = model.position_dofs.astype(np.int64)                     # (V, 3) global
        fpos = elastic.free_index[pos]                                 # (V, 3) free or -1
        self._fpos = fpos
        free = fpos >= 0
        rank = np.cumsum(free, axis=1) - 1
        self.vertex_rank = np.where(free, rank, -1).astype(np.int32)
        self._first_row = np.where(free.any(axis=1),
                                   np.where(free, fpos, np.iinfo(np.int64).max).min(axis=1), -1)
        # Elastic entries as column-major keys col * n + row (sorted: CSC order).
        ecols = np.repeat(np.arange(n, dtype=np.int64), np.diff(elastic.indptr))
        self._elastic_keys = ecols * n + elastic.indices.astype(np.int64)
        self.block_keys = np.zeros(0, dtype=np.int64)
        self._build(np.zeros(0, dtype=np.int64) if blocks is None else
                    np.unique(np.asarray(blocks, dtype=np.int64)))

    # -- construction -----------------------------------------------------------------
    def _block_entries(self, keys: np.ndarray) -> np.ndarray:
        """Column-major dof keys of the free entries of vertex blocks ``keys``."""
        nv, n = self.vertex_count, self.n
        vr, vc = keys // nv, keys % nv
        rows = self._fpos[vr]                                          # (K, 3)
        cols = self._fpos[vc]
        r = np.broadcast_to(rows[:, :, None], (keys.size, 3, 3))
        c = np.broadcast_to(cols[:, None, :], (keys.size, 3, 3))
        ok = (r >= 0) & (c >= 0)
        return (c[ok] * n + r[ok]).astype(np.int64)

    def _build(self, keys: np.ndarray) -> None:
        n, nv = self.n, self.vertex_count
        allk = np.union1d(self._elastic_keys, self._block_entries(keys))
        cols = allk // max(n, 1)
        self.indices = (allk % max(n, 1)).astype(np.int32)
        self.indptr = np.searchsorted(cols, np.arange(n + 1)).astype(np.int32)
        self.nnz = int(allk.size)
        self.elastic_slot = np.searchsorted(allk, self._elastic_keys)
        diag = np.full(n, -1, dtype=np.int64)
        on = self.indices == cols
        diag[cols[on]] = np.flatnonzero(on)
        self.diag_slot = diag
        vr, vc = keys // nv, keys % nv
        first = self._first_row[vr]                                    # (K,)
        ccols = self._fpos[vc]                                         # (K, 3)
        ok = (first[:, None] >= 0) & (ccols >= 0)
        slot_keys = np.where(ok, ccols * n + first[:, None], 0)
        slots = np.searchsorted(allk, slot_keys)
        self.block_keys = keys
        self.block_cols = np.where(ok, slots, -1).astype(np.int32)

    def grow(self, needed: np.ndarray) -> None:
        """Add the vertex blocks ``needed`` (keys vr * V + vc) to the pattern."""
        keys = np.union1d(self.block_keys, np.asarray(needed, dtype=np.int64))
        self._build(keys)
        self._warp = None

    def reset(self, needed: np.ndarray) -> None:
        """Rebuild the pattern with exactly the blocks ``needed`` (drops stale ones)."""
        self._build(np.unique(np.asarray(needed, dtype=np.int64)))
        self._warp = None

    # -- kernel arguments and matrices -------------------------------------------------
    _warp: tuple[wp.array, wp.array, wp.array] | None = None

    def warp_tables(self, device: str) -> tuple[wp.array, ...]:
        """The block table as Warp arrays (keys, row ranges, cols, vertex ranks), cached;
        row vr's keys are keys[rows[vr]:rows[vr + 1]]."""
        if self._warp is None:
            keys = self.block_keys if self.block_keys.size else np.full(1, -1, np.int64)
            cols = self.block_cols if self.block_cols.size else np.full((1, 3), -1, np.int32)
            nv = self.vertex_rank.shape[0]
            rows = np.searchsorted(self.block_keys, np.arange(nv + 1, dtype=np.int64) * nv)
            self._warp = (wp.array(keys, dtype=wp.int64, device=device),
                          wp.array(rows.astype(np.int32), dtype=wp.int32, device=device),
                          wp.array(np.ascontiguousarray(cols), dtype=wp.vec3i, device=device),
                          wp.array(self.vertex_rank, dtype=wp.vec3i, device=device))
        return self._warp

    def matrix(self, data: np.ndarray) -> sp.csc_matrix:
        """The n x n CSC matrix with this pattern and ``data`` (length nnz)."""
        return sp.csc_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))
