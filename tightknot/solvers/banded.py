"""A banded Cholesky solve for the small Newton systems of the batched rods.

One closed 100-vertex knot has about 400 free dofs; its contact couples strands far apart
along the rod, so SuperLU (:func:`tightknot.solvers.linear.factorize`) fills in a third of
the dense matrix, and on so small a matrix the supernodal code's fixed overhead dominates.
Reordered by reverse Cuthill-McKee (Cuthill & McKee 1969; George & Liu 1981, sec. 4.3) the
same matrix has a half-bandwidth of about 80, and LAPACK's banded Cholesky ``dpbtrf``
factors it several times faster (docs/design_notes.md, batched rods).

The matrix is equilibrated symmetrically first (``S A S``, ``S = |diag A|^-1/2``), as
:class:`tightknot.solvers.linear.Factorization` does. A matrix that is not positive
definite (a floppy loose knot, or a Levenberg-Marquardt shift still too small: half of
the factorizations of a loose-to-tight tie) makes the Cholesky factorization fail; then
the same band is solved by LU with partial pivoting (:func:`banded_lu_solve`), which,
like the one-rod solver's SuperLU, solves the indefinite system. The ordering and the map from CSC
entries to band storage depend only on the sparsity pattern, so they are built once per
pattern (:class:`BandPlan`) and reused while the contact set stays within it.

LAPACK runs in OpenBLAS, which by default spreads every call over all cores; on a band
of 80 that is pure synchronisation, so the batch runs with one BLAS thread
(:func:`single_blas_thread`); the one-rod solver (SuperLU) is not affected by the setting.
"""

from __future__ import annotations

import contextlib
import ctypes
from collections.abc import Iterator

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.linalg import lapack
from scipy.sparse.csgraph import reverse_cuthill_mckee


class BandPlan:
    """Ordering and band-storage map of one symmetric CSC pattern.

    Args:
        indptr, indices: CSC structure of an n x n matrix with a symmetric pattern and
            every diagonal entry stored.
    """

    def __init__(self, indptr: np.ndarray, indices: np.ndarray) -> None:
        n = len(indptr) - 1
        self.n = n
        pattern = sp.csc_matrix((np.ones(len(indices)), indices, indptr), shape=(n, n))
        perm = reverse_cuthill_mckee(pattern, symmetric_mode=True).astype(np.int64)
        inv = np.empty(n, dtype=np.int64)
        inv[perm] = np.arange(n)
        self.perm = perm
        cols = np.repeat(np.arange(n, dtype=np.int64), np.diff(indptr))
        rows = indices.astype(np.int64)
        self.rows, self.cols = rows, cols
        pr, pc = inv[rows], inv[cols]
        upper = pr <= pc
        self.upper = np.flatnonzero(upper)
        self.bandwidth = int((pc - pr)[upper].max()) if self.upper.size else 0
        # Upper band storage (LAPACK 'U'): ab[bw + i - j, j] = a[i, j] for i <= j.
        self.flat = (self.bandwidth + pr[upper] - pc[upper]) * n + pc[upper]
        self.rows_upper, self.cols_upper = rows[upper], cols[upper]
        # Full band storage of dgbsv (every entry, kl = ku = bandwidth, kl rows on top).
        self.flat_full = (2 * self.bandwidth + pr - pc) * n + pc
        diag = np.full(n, -1, dtype=np.int64)
        on = rows == cols
        diag[cols[on]] = np.flatnonzero(on)
        if (diag < 0).any():
            raise ValueError("the pattern must store every diagonal entry")
        self.diag = diag


def _equilibration(plan: BandPlan, data: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``S = |diag A|^-1/2`` (1 where the diagonal is zero) and the entries of S A S."""
    d = np.abs(data[plan.diag])
    s = 1.0 / np.sqrt(np.where(d > 0.0, d, 1.0))
    return s, data * s[plan.rows] * s[plan.cols]


class BandedCholesky:
    """Cholesky factorization of an SPD matrix given by its CSC ``data`` on ``plan``'s
    pattern; :meth:`try_factor` returns None when the matrix is not positive definite."""

    def __init__(self, plan: BandPlan, s: np.ndarray, factor: np.ndarray) -> None:
        self._plan = plan
        self._s = s
        self._c = factor

    @classmethod
    def try_factor(cls, plan: BandPlan, data: np.ndarray) -> BandedCholesky | None:
        """Factor the matrix with entries ``data`` (the plan's CSC order), or None."""
        return cls.factor_or_certificate(plan, data)[0]

    @classmethod
    def factor_or_certificate(cls, plan: BandPlan, data: np.ndarray
                              ) -> tuple[BandedCholesky | None, np.ndarray | None]:
        """The factorization, or None and a vector z with z.A z <= 0 (up to round-off),
        which proves A is not positive definite: where the factorization stops at column
        k, the leading block [[A11, a], [a^T, alpha]] has a non-positive Schur complement
        alpha - a^T A11^-1 a, attained by z = [-A11^-1 a, 1] (Golub & Van Loan 2013,
        sec. 4.2.8); A11^-1 a costs two band triangular solves with the factor of A11."""
        d = np.abs(data[plan.diag])
        s = 1.0 / np.sqrt(np.where(d > 0.0, d, 1.0))
        n, bw = plan.n, plan.bandwidth
        ab = np.zeros((bw + 1) * n)
        ab[plan.flat] = data[plan.upper] * s[plan.rows_upper] * s[plan.cols_upper]
        ab = ab.reshape(bw + 1, n)
        c, info = lapack.dpbtrf(ab, lower=0)
        if info == 0:
            return cls(plan, s, c), None
        if info < 0:
            raise RuntimeError(f"dpbtrf: argument {-info} is invalid")
        k = info - 1  # the failing column (0-based); columns < k hold the factor of A11
        lo = max(0, k - bw)
        z = np.zeros(n)
        z[k] = 1.0
        if k > 0:
            a = np.zeros(k)
            a[lo:] = ab[bw - (k - lo) : bw, k]  # A[lo:k, k] in band storage
            u = np.ascontiguousarray(c[:, :k])
            y, _ = lapack.dtbtrs(u, a[:, None], uplo="U", trans="T")
            w, _ = lapack.dtbtrs(u, y, uplo="U", trans="N")
            z[:k] = -w[:, 0]
        x = np.empty(n)
        x[plan.perm] = z
        return None, s * x

    def solve(self, b: np.ndarray) -> np.ndarray:
        """Solve A x = b for a vector b, or A X = B column by column for a matrix B."""
        p = self._plan.perm
        sc = self._s if np.ndim(b) == 1 else self._s[:, None]
        y = sla.cho_solve_banded((self._c, False), (sc * b)[p], check_finite=False)
        x = np.empty_like(y)
        x[p] = y
        return sc * x


def banded_lu_solve(plan: BandPlan, data: np.ndarray, b: np.ndarray) -> np.ndarray | None:
    """Solve A x = b (b a vector, or a matrix of right-hand sides) for the matrix with
    entries ``data`` on ``plan``'s pattern by banded LU with partial pivoting (LAPACK
    ``dgbsv``; for an indefinite matrix, where the Cholesky factorization fails); None when
    A is exactly singular."""
    s, scaled = _equilibration(plan, data)
    if np.ndim(b) == 2:
        s = s[:, None]
    n, bw = plan.n, plan.bandwidth
    # dgbsv's band storage: kl extra rows on top for the fill of the pivoting, then
    # ab[kl + ku + i - j, j] = a[i, j] (kl = ku = bw).
    ab = np.zeros((3 * bw + 1) * n)
    ab[plan.flat_full] = scaled
    _, _, x, info = lapack.dgbsv(bw, bw, ab.reshape(3 * bw + 1, n), (s * b)[plan.perm],
                                 overwrite_ab=True, overwrite_b=True)
    if info > 0:  # a zero pivot: exactly singular
        return None
    if info < 0:
        raise RuntimeError(f"dgbsv: argument {-info} is invalid")
    out = np.empty_like(x)
    out[plan.perm] = x
    return s * out


#: (get, set) entry points of the OpenBLAS builds numpy and scipy load.
_BLAS_THREAD_CALLS = (
    ("scipy_openblas_get_num_threads64_", "scipy_openblas_set_num_threads64_"),
    ("scipy_openblas_get_num_threads", "scipy_openblas_set_num_threads"),
    ("openblas_get_num_threads", "openblas_set_num_threads"),
)


def _openblas_libraries() -> list[tuple[ctypes.CDLL, str, str]]:
    """The loaded OpenBLAS libraries with their thread-count calls (Linux: read from
    /proc/self/maps; elsewhere none, and the threads stay as they are)."""
    try:
        with open("/proc/self/maps") as f:
            paths = sorted({name for name in (line.split()[-1] for line in f)
                            if "openblas" in name.lower() and ".so" in name})
    except OSError:
        return []
    libs = []
    for path in paths:
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for get, set_ in _BLAS_THREAD_CALLS:
            if hasattr(lib, get) and hasattr(lib, set_):
                libs.append((lib, get, set_))
                break
    return libs


@contextlib.contextmanager
def single_blas_thread() -> Iterator[None]:
    """Run the body with one OpenBLAS thread, then restore the previous counts."""
    libs = _openblas_libraries()
    saved = [int(getattr(lib, get)()) for lib, get, _ in libs]
    for lib, _, set_ in libs:
        getattr(lib, set_)(ctypes.c_int(1))
    try:
        yield
    finally:
        for (lib, _, set_), n in zip(libs, saved, strict=True):
            getattr(lib, set_)(ctypes.c_int(n))
