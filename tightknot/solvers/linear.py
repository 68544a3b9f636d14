"""Sparse linear algebra: the direct solve of the Newton systems.

The matrices come in the patterns of :mod:`tightknot.solvers.pattern`. On CPU the solve
is scipy's SuperLU (sparse direct). The Newton loop only needs ``factorize(A).solve(b)``,
so a GPU path can plug in Warp's sparse CG behind the same call.
"""

from __future__ import annotations

from collections.abc import Callable

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
        """Solve A x = b for a vector b, or A X = B column by column for a matrix B."""
        s = self._s if np.ndim(b) == 1 else self._s[:, None]
        return s * self._lu.solve(s * b)


def factorize(a: sp.spmatrix) -> Factorization:
    """Factorize ``a``; raises RuntimeError when it is exactly singular."""
    return Factorization(a)


class LowRankHessian:
    """A Hessian ``H = B + U C U^T``: a sparse part ``base`` (what the linear solver
    factors) and a dense update of low rank (a contact radius thinned by a rod's mean
    stretch couples every vertex of the rod: :mod:`tightknot.contact.rod_mean_radius`).

    Args:
        base: the sparse part (a CSC matrix, or a batch rod's Hessian data).
        u: (n, m) [units of the dofs' gradients per unit s] columns of the update.
        c: (m, m) symmetric core of the update.
    """

    def __init__(self, base: object, u: np.ndarray, c: np.ndarray) -> None:
        self.base = base
        self.u = np.ascontiguousarray(u, dtype=np.float64)
        self.c = np.ascontiguousarray(c, dtype=np.float64)

    def toarray(self) -> np.ndarray:
        """The whole Hessian as a dense array (tests, diagnostics)."""
        base = self.base.toarray() if hasattr(self.base, "toarray") else (
            self.base.matrix().toarray())
        return base + self.u @ self.c @ self.u.T

    def diagonal_update(self) -> np.ndarray:
        """The update's diagonal, rows of (U C) . U."""
        return np.einsum("ij,ij->i", self.u @ self.c, self.u)

    def product(self, matrix: object) -> LowRankProduct:
        """The operator ``d -> matrix @ d + U C U^T d`` for the base's ``matrix``."""
        return LowRankProduct(matrix, self.u, self.c)


class LowRankProduct:
    """Products with ``A + U C U^T`` (A a sparse matrix): ``op @ d``."""

    def __init__(self, a: object, u: np.ndarray, c: np.ndarray) -> None:
        self.a, self.u, self.c = a, u, c

    def __matmul__(self, d: np.ndarray) -> np.ndarray:
        return self.a @ d + self.u @ (self.c @ (self.u.T @ d))


def woodbury_solve(solve: object, u: np.ndarray, c: np.ndarray, b: np.ndarray
                   ) -> np.ndarray | None:
    """Solve ``(A + U C U^T) x = b`` given ``solve``, the solution of ``A X = B`` for a
    vector or a matrix B, by the Woodbury identity (Golub & Van Loan 2013, sec. 2.1.4):
    ``x = y - Z (C^-1 + U^T Z)^-1 U^T y`` with ``y = A^-1 b``, ``Z = A^-1 U``, written
    without C^-1 as ``x = y - Z C (I + U^T Z C)^-1 U^T y`` (C may be singular). None when
    the small system is singular or the result not finite."""
    y = solve(b)
    z = solve(u)
    if z.ndim == 1:
        z = z[:, None]
    small = np.eye(c.shape[0]) + (u.T @ z) @ c
    try:
        v = np.linalg.solve(small, u.T @ y)
    except np.linalg.LinAlgError:
        return None
    x = y - z @ (c @ v)
    return x if np.isfinite(x).all() else None


class SparseDirect:
    """The Newton loop's linear algebra for a Hessian held as a scipy CSC matrix: shifted
    systems ``(H + mu D) d = -g`` solved by :func:`factorize` (SuperLU)."""

    #: The solver's name in run summaries.
    name = "superlu"
    #: Whether the last :meth:`shifted_direction` returned None because the shifted matrix
    #: has a negative eigenvalue (a solver that reads the factorization's inertia).
    refused_indefinite = False

    @staticmethod
    def matrix(h: sp.csc_matrix | LowRankHessian) -> object:
        """The Hessian as an operator for products (a sparse matrix, or with a low-rank
        update :class:`LowRankProduct`)."""
        if isinstance(h, LowRankHessian):
            return h.product(h.base)
        return h

    @staticmethod
    def diagonal(h: sp.csc_matrix | LowRankHessian) -> np.ndarray:
        """The Hessian's diagonal."""
        if isinstance(h, LowRankHessian):
            return h.base.diagonal() + h.diagonal_update()
        return h.diagonal()

    @staticmethod
    def shifted_direction(h: sp.csc_matrix | LowRankHessian, g: np.ndarray, mu: float,
                          diag: np.ndarray) -> np.ndarray | None:
        """Solve (H + mu D) d = -g with D = diag(``diag``) by SuperLU
        (:func:`shifted_solve`)."""
        return shifted_solve(h, g, mu, diag)


#: factor(B, mu, diag): the solution operator b -> A^-1 b of A = B + mu diag(diag), B
#: sparse, None when singular.
ShiftedFactor = Callable[[sp.spmatrix, float, np.ndarray],
                         Callable[[np.ndarray], np.ndarray] | None]


def _superlu_solver(a: sp.spmatrix) -> Callable[[np.ndarray], np.ndarray] | None:
    try:
        return factorize(a).solve
    except RuntimeError:  # exactly singular
        return None


def _summed_shift(base: sp.spmatrix, mu: float, diag: np.ndarray
                  ) -> Callable[[np.ndarray], np.ndarray] | None:
    """SuperLU's factorization of ``base + mu diag(diag)``, the shift added by a sparse
    sum."""
    return _superlu_solver(base if mu == 0.0 else (base + sp.diags(mu * diag, format="csc")))


def shifted_solve(h: sp.csc_matrix | LowRankHessian, g: np.ndarray, mu: float,
                  diag: np.ndarray,
                  factor: ShiftedFactor = _summed_shift) -> np.ndarray | None:
    """Solve (H + mu D) d = -g with D = diag(``diag``), the sparse part B and its shift
    factored by ``factor(B, mu, diag)``; None when singular or not finite. A low-rank
    update is solved by :func:`woodbury_solve` around the factorization of the sparse
    part."""
    base = h.base if isinstance(h, LowRankHessian) else h
    solve = factor(base, mu, diag)
    if solve is None:
        return None
    if isinstance(h, LowRankHessian):
        return woodbury_solve(solve, h.u, h.c, -g)
    d = solve(-g)
    return d if np.isfinite(d).all() else None
