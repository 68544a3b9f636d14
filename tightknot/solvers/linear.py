"""Sparse linear algebra: the direct solve of the Newton systems.

The matrices come in the patterns of :mod:`tightknot.solvers.pattern`. On CPU the solve
is scipy's SuperLU (sparse direct). The Newton loop only needs ``factorize(A).solve(b)``,
so a GPU path can plug in Warp's sparse CG behind the same call.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla


class Factorization:
    """Sparse LU of a symmetric matrix (SuperLU), with ``solve(b)``.

    The matrix is first equilibrated symmetrically, ``S A S`` with ``S = |diag A|^-1/2``:
    positions and twist angles have stiffnesses many decades apart (EA/l against GJ/l),
    and SuperLU without pivoting loses digits on them. A banded matrix (an open rod
    without contact) keeps its natural order, which is already optimal; otherwise the
    ordering is minimum degree on A^T + A (docs/design_notes.md, linear algebra).
    """

    #: Largest |row - col| for which the natural order is kept.
    BANDED_LIMIT = 64

    def __init__(self, a: sp.csc_matrix) -> None:
        a = sp.csc_matrix(a)
        a.sum_duplicates()
        d = np.abs(a.diagonal())
        d = np.where(d > 0.0, d, 1.0)
        self._s = 1.0 / np.sqrt(d)
        cols = np.repeat(np.arange(a.shape[1]), np.diff(a.indptr))
        rows = a.indices
        sa = sp.csc_matrix((a.data * self._s[rows] * self._s[cols], rows, a.indptr),
                           shape=a.shape)
        bandwidth = int(np.abs(rows - cols).max()) if a.nnz else 0
        spec = "NATURAL" if bandwidth <= self.BANDED_LIMIT else "MMD_AT_PLUS_A"
        # Diagonal pivots with a symmetric pattern are faster on symmetric matrices; pivot
        # when a diagonal entry is below 0.1 of its column's largest.
        self._lu = spla.splu(sa, permc_spec=spec, diag_pivot_thresh=0.1,
                             options=dict(SymmetricMode=True))

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solve A x = b."""
        return self._s * self._lu.solve(self._s * b)


def factorize(a: sp.spmatrix) -> Factorization:
    """Factorize ``a``; raises RuntimeError when it is exactly singular."""
    return Factorization(a)


class SparseDirect:
    """The Newton loop's linear algebra for a Hessian held as a scipy CSC matrix: shifted
    systems ``(H + mu D) d = -g`` solved by :func:`factorize` (SuperLU)."""

    @staticmethod
    def matrix(h: sp.csc_matrix) -> sp.csc_matrix:
        """The Hessian as a sparse matrix (for products)."""
        return h

    @staticmethod
    def diagonal(h: sp.csc_matrix) -> np.ndarray:
        """The Hessian's diagonal."""
        return h.diagonal()

    @staticmethod
    def shifted_direction(h: sp.csc_matrix, g: np.ndarray, mu: float,
                          diag: np.ndarray) -> np.ndarray | None:
        """Solve (H + mu D) d = -g with D = diag(``diag``); None when singular or not
        finite."""
        a = h if mu == 0.0 else (h + sp.diags(mu * diag, format="csc"))
        try:
            d = factorize(a).solve(-g)
        except RuntimeError:  # exactly singular
            return None
        return d if np.isfinite(d).all() else None
