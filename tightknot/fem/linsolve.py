"""Sparse symmetric linear solves for the FEM's Newton loops, with a choice of library.

The tangent of the nearly incompressible solid with barrier or penalty contact is symmetric
and mostly positive definite, but not always: the solid's tangent under contact and the
exact (unprojected) barrier Hessian can be indefinite (docs/fem_nip.md). The solvers, in
the order ``"auto"`` tries them:

- ``"pardiso"``: Intel MKL PARDISO (:class:`tightknot.solvers.pardiso.PardisoDirect`; pip:
  ``pypardiso`` and the ``mkl`` wheel, x86_64 only), matrix type -2 (real symmetric
  indefinite: supernodal Bunch-Kaufman LDL^T with pivot perturbation and iterative
  refinement, Schenk & Gaertner, FGCS 20 (2004) 475), so it takes the indefinite tangents
  too. A :class:`SymmetricSolver` keeps PARDISO's ordering and symbolic analysis from one
  solve to the next while the tangent's pattern stays (a Newton loop's iterations between
  changes of the contact set), so that such solves pay the numeric factorization only.
- ``"cholmod"``: CHOLMOD's supernodal Cholesky through ``scikit-sparse`` (Chen, Davis,
  Hager & Rajamanickam, ACM TOMS 35 (2008) 22), METIS ordering. It needs SuiteSparse's
  headers to build (Debian: ``libsuitesparse-dev``; PyPI has no wheel), and a positive
  definite matrix: an indefinite one falls back to SuperLU.
- ``"superlu"``: SciPy's SuperLU, symmetric mode, diagonal pivoting off (always there);
  where that meets a tiny pivot (an indefinite matrix), SuperLU with partial pivoting.

Every solution is checked: a relative residual above ``RESIDUAL_TOL`` (a perturbed pivot
that refinement did not repair) falls back to SuperLU. The environment variable
``TIGHTKNOT_FEM_SOLVER`` sets the default (one of :data:`SOLVERS`). PARDISO runs on MKL's
own thread count here (``MKL_NUM_THREADS``, else the cores), unlike the rod's one thread.
"""

from __future__ import annotations

import os
from functools import cache

import numpy as np
import scipy.sparse as sp
from scipy.sparse.linalg import splu

from tightknot.solvers.pardiso import PardisoDirect
from tightknot.solvers.pardiso import available as pardiso_available

SOLVERS: tuple[str, ...] = ("auto", "pardiso", "cholmod", "superlu")
"""Names of the linear solvers ("auto": the fastest installed one)."""

ENV_VAR: str = "TIGHTKNOT_FEM_SOLVER"
"""Environment variable that sets the default solver."""

RESIDUAL_TOL: float = 1e-8
"""Largest accepted relative residual |K x - b| / |b| of a solve. The direct solves give
1e-14 to 1e-13 on the FEM's tangents (8k to 17k dofs); 1e-8 still leaves the Newton loops'
convergence tests (relative residuals 1e-8 of the reaction) an accurate step."""


def check_solver(name: str) -> str:
    """``name`` if it is one of :data:`SOLVERS`, else ValueError naming the choices."""
    if name not in SOLVERS:
        raise ValueError(f"linear solver must be one of {SOLVERS}, got {name!r}")
    return name


def default_solver() -> str:
    """The solver named by ``TIGHTKNOT_FEM_SOLVER``, else ``"auto"``."""
    return check_solver(os.environ.get(ENV_VAR, "auto"))


@cache
def _cholmod_ok() -> bool:
    try:
        import sksparse.cholmod  # noqa: F401
    except ImportError:
        return False
    return True


def available() -> tuple[str, ...]:
    """The solvers installed here, fastest first ("superlu" always)."""
    return tuple(n for n, ok in (("pardiso", pardiso_available()), ("cholmod", _cholmod_ok()),
                                 ("superlu", True)) if ok)


def resolve(name: str | None = None) -> str:
    """The solver that ``name`` (default :func:`default_solver`) runs: "auto" gives the
    first of :func:`available`; a named one that is not installed raises ImportError."""
    name = check_solver(default_solver() if name is None else name)
    if name == "auto":
        return available()[0]
    if name not in available():
        raise ImportError(f"linear solver {name!r} is not installed (installed: "
                          f"{', '.join(available())}); pypardiso comes with tightknot[fem] "
                          "on x86_64, scikit-sparse needs SuiteSparse's headers")
    return name


def _accurate(k: sp.csc_matrix, x: np.ndarray | None, rhs: np.ndarray) -> bool:
    """Whether ``x`` solves K x = rhs to :data:`RESIDUAL_TOL` (relative)."""
    if x is None or not np.all(np.isfinite(x)):
        return False
    norm = float(np.linalg.norm(rhs))
    return norm == 0.0 or float(np.linalg.norm(k @ x - rhs)) <= RESIDUAL_TOL * norm


def _superlu(k: sp.csc_matrix, rhs: np.ndarray) -> np.ndarray:
    # symmetric mode without pivoting is the fast path on the FEM's tangents; an
    # indefinite matrix can meet a tiny pivot there, and partial pivoting repairs it
    x = splu(k, diag_pivot_thresh=0.0, options=dict(SymmetricMode=True)).solve(rhs)
    if _accurate(k, x, rhs):
        return x
    return splu(k).solve(rhs)


def _cholmod(k: sp.csc_matrix, rhs: np.ndarray) -> np.ndarray | None:
    from sksparse.cholmod import CholmodNotPositiveDefiniteError, cholesky

    try:
        return cholesky(k, mode="supernodal", ordering_method="metis")(rhs)
    except CholmodNotPositiveDefiniteError:
        return None  # indefinite: the caller falls back to SuperLU


class SymmetricSolver:
    """Solves a sequence of sparse symmetric systems K x = rhs [any units] (a Newton loop's
    tangents) by ``solver`` (one of :data:`SOLVERS`, default :func:`default_solver`), with
    SuperLU where the chosen library cannot (indefinite K for CHOLMOD) or its residual is
    above :data:`RESIDUAL_TOL`. With PARDISO the analysis of the last pattern is kept.

    Attributes:
        requested: ``solver`` as given; name: the library that solves (:func:`resolve`).
    """

    def __init__(self, solver: str | None = None) -> None:
        self.requested = solver
        self.name = resolve(solver)
        self._pardiso: PardisoDirect | None = None

    @property
    def analyses(self) -> int:
        """PARDISO's symbolic analyses so far (0 for the other libraries)."""
        return 0 if self._pardiso is None else self._pardiso.analyses

    def __call__(self, k: sp.spmatrix, rhs: np.ndarray) -> np.ndarray:
        """x with K x = rhs."""
        k = sp.csc_matrix(k)
        rhs = np.asarray(rhs, dtype=float)
        x = None
        if self.name == "pardiso":
            x = self._solve_pardiso(k, rhs)
        elif self.name == "cholmod":
            x = _cholmod(k, rhs)
        if _accurate(k, x, rhs):
            return x
        return _superlu(k, rhs)

    def _solve_pardiso(self, k: sp.csc_matrix, rhs: np.ndarray) -> np.ndarray | None:
        if self._pardiso is None:
            # indefinite tangents are solved as they are (the Newton loops test descent)
            self._pardiso = PardisoDirect(convex=False, threads=None)
        solve = self._pardiso.factor(k)
        return None if solve is None else solve(rhs)


def solve_symmetric(k: sp.spmatrix, rhs: np.ndarray, solver: str | None = None
                    ) -> np.ndarray:
    """x with K x = rhs for one symmetric sparse K [any units] (:class:`SymmetricSolver`,
    nothing kept)."""
    return SymmetricSolver(solver)(k, rhs)
