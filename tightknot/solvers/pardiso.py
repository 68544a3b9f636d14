"""Intel MKL PARDISO for the sectioned level's Newton systems: a supernodal symmetric
indefinite LDL^T whose ordering and symbolic analysis are kept while the matrix's pattern
stays.

The sectioned level's Hessians are made of dense node blocks (a node's position and section
dofs, coupled to its neighbours' and its contact partners'), where a supernodal
factorization runs on dense kernels: MKL PARDISO, matrix type -2 (real symmetric
indefinite, Bunch-Kaufman pivoting within supernodes and pivot perturbation; Schenk &
Gaertner, FGCS 20 (2004) 475), factors them several times faster than SciPy's SuperLU
(docs/sectioned_level.md, "Cost"). Its analysis (nested-dissection ordering and symbolic
factorization) costs several factorizations, so :class:`PardisoDirect` keeps it while the
pattern of the matrix is unchanged, and keeps the ordering when only contact blocks come
and go (the symbolic factorization is then redone on that ordering). The Newton loop's
shift goes on the stored diagonal, so shifted and unshifted solves share the pattern. The
factorization's inertia refuses a shifted matrix with a negative eigenvalue, so that the
loop raises its shift until it steps on a convex model (inertia correction).

PARDISO runs on one thread here: its result then does not depend on the thread count
(MKL's conditional numerical reproducibility), and the workers of a sweep or a test run
each have a core. The FEM's Newton loops (:mod:`tightknot.fem.linsolve`) keep the analysis
the same way on MKL's own thread count. ``pypardiso`` (BSD) comes with MKL's runtime (the
``mkl`` wheel, x86_64 only; both in the ``pardiso`` and ``fem`` extras); without it the
sectioned level solves with SuperLU as the others do
(:class:`tightknot.solvers.linear.SparseDirect`).
"""

from __future__ import annotations

import ctypes
import glob
import importlib.util
import os
import sys
import weakref
from collections.abc import Callable
from functools import cache

import numpy as np
import scipy.sparse as sp

from tightknot.solvers.linear import LowRankHessian, SparseDirect, shifted_solve

#: Environment variable that picks the sectioned level's linear solver.
ENV_VAR = "TIGHTKNOT_SECTION_SOLVER"
#: Its values: "auto" (PARDISO where installed, else SuperLU), "pardiso", "superlu".
SOLVERS = ("auto", "pardiso", "superlu")


@cache
def mkl_runtime_path() -> str | None:
    """The path of MKL's runtime library ``libmkl_rt.so*`` that the ``mkl`` wheel puts in
    the environment's lib/ and that loads here; None where there is none (pypardiso may
    still find one elsewhere)."""
    # pypardiso looks for MKL in every PyPardisoSolver it builds, by walking the whole
    # environment when ctypes.util.find_library does not know the wheel's library; the
    # wheel's library sits in lib/.
    for path in sorted(glob.glob(os.path.join(sys.prefix, "lib", "libmkl_rt.so*"))):
        try:
            ctypes.CDLL(path)
        except OSError:
            continue
        return path
    return None


@cache
def _library() -> ctypes.CDLL | None:
    """MKL's runtime (the ``mkl`` wheel's, else where pypardiso finds it), with the
    pardiso entry point typed; None when pypardiso or MKL is not installed."""
    # pypardiso's presence says MKL's (the supported way in); it is found, not imported:
    # its import builds a solver, whose search for MKL :func:`mkl_runtime_path` spares.
    if importlib.util.find_spec("pypardiso") is None:
        return None
    path = mkl_runtime_path()
    lib = None if path is None else ctypes.CDLL(path)
    if lib is None:
        try:
            import pypardiso

            lib = pypardiso.PyPardisoSolver().libmkl
        except (ImportError, OSError):
            return None
    f = lib.pardiso
    i32 = ctypes.POINTER(ctypes.c_int32)
    f.argtypes = [ctypes.POINTER(ctypes.c_int64), i32, i32, i32, i32, i32,
                  ctypes.c_void_p, i32, i32, i32, i32, i32, i32, ctypes.c_void_p,
                  ctypes.c_void_p, i32]
    f.restype = None
    lib.MKL_Set_Num_Threads_Local.argtypes = [ctypes.c_int]
    lib.MKL_Set_Num_Threads_Local.restype = ctypes.c_int
    return lib


def available() -> bool:
    """Whether MKL PARDISO can be loaded here."""
    return _library() is not None


def section_solver(name: str | None = None) -> str:
    """The solver the sectioned level uses: ``name`` or the environment's
    ``TIGHTKNOT_SECTION_SOLVER`` (default "auto": "pardiso" where installed, else
    "superlu"); ValueError for an unknown name, ImportError for "pardiso" without MKL."""
    name = os.environ.get(ENV_VAR, "auto") if name is None else name
    if name not in SOLVERS:
        raise ValueError(f"{ENV_VAR} must be one of {SOLVERS}, got {name!r}")
    if name == "auto":
        return "pardiso" if available() else "superlu"
    if name == "pardiso" and not available():
        raise ImportError("the sectioned level's solver 'pardiso' needs pypardiso and MKL "
                          "(pip install 'tightknot[pardiso]' on x86_64)")
    return name


def section_linear() -> SparseDirect:
    """The linear algebra of a rod system with section dofs: :class:`PardisoDirect` or
    SuperLU's :class:`~tightknot.solvers.linear.SparseDirect` (:func:`section_solver`)."""
    return PardisoDirect() if section_solver() == "pardiso" else SparseDirect()


class _Handle:
    """One PARDISO instance (its internal memory ``pt``), freed with the object."""

    def __init__(self, lib: ctypes.CDLL, threads: int | None = 1) -> None:
        self.lib = lib
        self.threads = threads
        self.pt = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        ip = self.iparm
        ip[0] = 1    # these settings, not the defaults
        ip[1] = 2    # nested dissection (METIS) ordering
        ip[7] = 2    # at most two steps of iterative refinement after perturbed pivots
        ip[9] = 8    # perturb pivots below 1e-8 of the norm (the default for type -2)
        ip[20] = 1   # Bunch-Kaufman 1x1 and 2x2 pivoting (the default for type -2)
        ip[23] = 0   # the classic factorization, whose result is the same on any threads
        ip[34] = 1   # zero-based ia and ja
        self.n = 0
        self._finalizer = weakref.finalize(self, _release, lib, self.pt)

    def call(self, phase: int, a: sp.csr_matrix, perm: np.ndarray, b: np.ndarray,
             x: np.ndarray) -> int:
        """PARDISO ``phase`` on the upper triangle ``a``; its error code (0: none)."""
        if self.threads is None:  # MKL's own setting (MKL_NUM_THREADS, else the cores)
            return _pardiso(self.lib, self.pt, self.iparm, phase, a, perm, b, x)
        # the thread count for this call only (a thread-local setting, restored after it)
        previous = self.lib.MKL_Set_Num_Threads_Local(self.threads)
        try:
            return _pardiso(self.lib, self.pt, self.iparm, phase, a, perm, b, x)
        finally:
            self.lib.MKL_Set_Num_Threads_Local(previous)


def _pardiso(lib: ctypes.CDLL, pt: np.ndarray, iparm: np.ndarray, phase: int,
             a: sp.csr_matrix, perm: np.ndarray, b: np.ndarray, x: np.ndarray) -> int:
    """One call of MKL's ``pardiso`` (one matrix, type -2, one right-hand side, silent)."""
    i32 = ctypes.c_int32
    p32 = ctypes.POINTER(i32)
    err = i32(0)
    lib.pardiso(pt.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)), ctypes.byref(i32(1)),
                ctypes.byref(i32(1)), ctypes.byref(i32(-2)), ctypes.byref(i32(phase)),
                ctypes.byref(i32(a.shape[0])), a.data.ctypes.data,
                a.indptr.ctypes.data_as(p32), a.indices.ctypes.data_as(p32),
                perm.ctypes.data_as(p32), ctypes.byref(i32(1)), iparm.ctypes.data_as(p32),
                ctypes.byref(i32(0)), b.ctypes.data, x.ctypes.data, ctypes.byref(err))
    return int(err.value)


def _release(lib: ctypes.CDLL, pt: np.ndarray) -> None:
    """PARDISO phase -1: free all its memory of the instance ``pt``."""
    if not pt.any():
        return
    one = sp.csr_matrix(np.ones((1, 1)))
    one.indptr, one.indices = one.indptr.astype(np.int32), one.indices.astype(np.int32)
    dummy = np.zeros(1)
    _pardiso(lib, pt, np.zeros(64, dtype=np.int32), -1, one, np.zeros(1, dtype=np.int32),
             dummy, dummy.copy())


class PardisoDirect(SparseDirect):
    """The Newton loop's linear algebra (as :class:`~tightknot.solvers.linear.SparseDirect`)
    with the shifted systems ``(H + mu D) d = -g`` factored by MKL PARDISO.

    The matrix is equilibrated symmetrically, ``S A S`` with ``S = |diag A|^-1/2``, as
    :class:`~tightknot.solvers.linear.Factorization` does, and PARDISO reads its upper
    triangle. Its analysis is redone only when the pattern changes, on the kept ordering
    while the size stays and the number of stored entries grew by less than
    :attr:`REORDER_GROWTH` since the ordering was made.

    Attributes:
        analyses: symbolic analyses made; orderings: of them, with a new ordering;
            factorizations: numeric factorizations; indefinite: of them, refused for a
            negative eigenvalue (for benchmarks and tests).

    Args:
        convex: refuse a shifted matrix with a negative eigenvalue (PARDISO's inertia), so
            that the Newton loop raises its shift until the model it steps on is convex
            (inertia correction, Waechter & Biegler 2006); False: return the direction
            of an indefinite matrix too, as SuperLU does.
        threads: MKL threads per PARDISO call (default one: see the module docstring);
            None leaves MKL's own setting.
    """

    name = "pardiso"

    #: Relative growth of the upper triangle's entries past which the ordering is renewed
    #: (a kept ordering of a denser pattern fills in more).
    REORDER_GROWTH = 0.1

    def __init__(self, convex: bool = True, threads: int | None = 1) -> None:
        lib = _library()
        if lib is None:
            raise ImportError("MKL PARDISO is not installed (pypardiso and mkl)")
        self._h = _Handle(lib, threads)
        self._key: tuple | None = None
        self._upper_of: tuple | None = None
        self._perm = np.zeros(0, dtype=np.int32)
        self._perm_nnz = 0
        self.analyses = 0
        self.orderings = 0
        self.factorizations = 0
        self.indefinite = 0
        self._convex = bool(convex)

    def shifted_direction(self, h: sp.csc_matrix | LowRankHessian, g: np.ndarray, mu: float,
                          diag: np.ndarray) -> np.ndarray | None:
        """Solve (H + mu D) d = -g with D = diag(``diag``) by PARDISO
        (:func:`~tightknot.solvers.linear.shifted_solve`); None where H + mu D is not
        positive definite, so that the Newton loop raises mu. A low-rank update's inertia
        is not the factored part's: there only the Newton loop's own test judges."""
        convex = self._convex and not isinstance(h, LowRankHessian)
        self.refused_indefinite = False
        return shifted_solve(h, g, mu, diag,
                             lambda b, m, dg: self._factorize(b, m, dg, convex))

    def factor(self, matrix: sp.spmatrix) -> Callable[[np.ndarray], np.ndarray] | None:
        """The solution operator of the symmetric sparse ``matrix`` (its analysis kept from
        the last call while the pattern is the same); None where PARDISO fails, or (with
        ``convex``) where the matrix has a negative eigenvalue."""
        return self._factorize(matrix, 0.0, np.zeros(0), self._convex)

    def _upper(self, base: sp.spmatrix) -> tuple:
        """The upper triangle of the symmetric ``base`` in CSR, read from its lower one in
        CSC (rows >= column): (indptr, indices, the rows of the entries, which of
        ``base``'s entries they are, each row's diagonal entry among them, whether every
        diagonal entry is stored, ``base`` in CSC) and the pattern's key. The index arrays
        are kept while ``base``'s pattern is the same (a load step's Newton iterations)."""
        a = base if (sp.isspmatrix_csc(base) and base.has_canonical_format) else \
            sp.csc_matrix(base, copy=True)
        a.sum_duplicates()
        n = a.shape[0]
        key = (n, a.indptr.tobytes(), a.indices.tobytes())
        if self._upper_of is not None and self._upper_of[0] == key:
            return (*self._upper_of[1], a), self._upper_of[2]
        cols = np.repeat(np.arange(n, dtype=np.int32), np.diff(a.indptr))
        keep = np.flatnonzero(a.indices >= cols)
        indices = a.indices[keep].astype(np.int32)
        rows = cols[keep]
        indptr = np.zeros(n + 1, dtype=np.int32)
        np.cumsum(np.bincount(rows, minlength=n), out=indptr[1:])
        # each CSR row of the upper triangle starts at its diagonal where it is stored
        first = np.minimum(indptr[:-1], max(indices.size - 1, 0))
        all_diag = bool(indices.size) and bool(np.all(indices[first] == np.arange(n)))
        out = (indptr, indices, rows, keep, first, all_diag)
        up_key = (n, indptr.tobytes(), indices.tobytes())
        self._upper_of = (key, out, up_key)
        return (*out, a), up_key

    def _factorize(self, base: sp.spmatrix, mu: float, shift: np.ndarray,
                   convex: bool = True) -> Callable[[np.ndarray], np.ndarray] | None:
        """The solution operator of ``base + mu diag(shift)``, the shift added on the
        stored diagonal so that the pattern, and with it PARDISO's analysis, stays through
        a load step's Newton iterations (a sparse sum would drop the pattern's stored
        zeros, another pattern); None when PARDISO fails, or (with ``convex``) when the
        matrix has a negative eigenvalue."""
        (indptr, indices, rows, keep, first, all_diag, a), key = self._upper(base)
        n = a.shape[0]
        if mu != 0.0 and not all_diag:
            # a diagonal entry not stored: the shift adds it (another pattern)
            return self._factorize(a + sp.diags(mu * shift, format="csc"), 0.0, shift,
                                   convex)
        data = a.data[keep]
        if mu != 0.0:
            data[first] += mu * shift
        d = np.abs(data[first]) if all_diag else np.abs(a.diagonal())
        s = 1.0 / np.sqrt(np.where(d > 0.0, d, 1.0))
        # symmetric equilibration S A S (linear.Factorization explains)
        up = sp.csr_matrix((data * s[indices] * s[rows], indices, indptr), shape=(n, n))
        h = self._h
        dummy = np.zeros(n)
        if key != self._key:
            fresh = (n != h.n or up.nnz > (1.0 + self.REORDER_GROWTH) * self._perm_nnz)
            if fresh:
                self._perm = np.zeros(n, dtype=np.int32)
                h.iparm[4] = 2  # make the ordering and return it in perm
            else:
                h.iparm[4] = 1  # the kept ordering
            if h.n:
                _release(h.lib, h.pt)
                h.pt[:] = 0
            if h.call(11, up, self._perm, dummy, dummy.copy()) != 0:
                self._key = None
                h.n = 0
                return None
            h.n = n
            self._key = key
            self.analyses += 1
            if fresh:
                self.orderings += 1
                self._perm_nnz = up.nnz
        if h.call(22, up, self._perm, dummy, dummy.copy()) != 0:
            return None
        self.factorizations += 1
        h.iparm[4] = 0
        if convex and h.iparm[22] > 0:
            # negative eigenvalues (PARDISO's inertia of the LDL^T): the shifted model is not
            # convex, so Newton raises the shift (inertia correction, Waechter & Biegler,
            # Math. Program. 106 (2006) 25, sec. 3.1)
            self.indefinite += 1
            self.refused_indefinite = True
            return None

        def solve(b: np.ndarray) -> np.ndarray:
            b = np.asarray(b, dtype=np.float64)
            if b.ndim == 2:
                return np.column_stack([solve(b[:, k]) for k in range(b.shape[1])])
            rhs = np.ascontiguousarray(s * b)
            x = np.zeros(n)
            if h.call(33, up, self._perm, rhs, x) != 0:
                return np.full(n, np.nan)
            return s * x

        return solve
