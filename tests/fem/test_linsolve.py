"""The FEM's sparse symmetric solvers (tightknot.fem.linsolve): every installed library
solves definite and indefinite systems, the choice is checked, SuperLU is the fallback."""

import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp

from tightknot.fem import linsolve
from tightknot.solvers.pardiso import mkl_runtime_path


def _laplacian_3d(n: int) -> sp.csc_matrix:
    """The 7-point Laplacian on an n^3 grid: symmetric positive definite, FEM-like fill."""
    one = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n))
    eye = sp.identity(n)
    return sp.csc_matrix(sp.kron(sp.kron(one, eye), eye) + sp.kron(sp.kron(eye, one), eye)
                         + sp.kron(sp.kron(eye, eye), one))


def _indefinite(n: int) -> sp.csc_matrix:
    """The Laplacian shifted by 3: symmetric with eigenvalues of both signs (its spectrum
    is (0, 12) on the grid), nonsingular for this n."""
    k = _laplacian_3d(n)
    return sp.csc_matrix(k - 3.0 * sp.identity(k.shape[0]))


@pytest.mark.parametrize("name", ["auto", *linsolve.available()])
@pytest.mark.parametrize("make", [_laplacian_3d, _indefinite])
def test_every_installed_solver_solves(name, make):
    # 1e-10: the direct solves reach 1e-13 on these 1000-dof systems; the tolerance
    # leaves room for the pivot perturbation of PARDISO's indefinite factorisation
    k = make(10)
    rng = np.random.default_rng(3)
    b = rng.standard_normal(k.shape[0])
    x = linsolve.solve_symmetric(k, b, name)
    assert np.linalg.norm(k @ x - b) <= 1e-10 * np.linalg.norm(b)


def test_auto_takes_the_fastest_installed():
    assert linsolve.resolve("auto") == linsolve.available()[0]
    assert linsolve.available()[-1] == "superlu"


def test_bad_solver_name():
    with pytest.raises(ValueError, match="linear solver must be one of"):
        linsolve.solve_symmetric(_laplacian_3d(3), np.ones(27), "umfpack")


def test_missing_solver_is_an_import_error(monkeypatch):
    monkeypatch.setattr(linsolve, "available", lambda: ("superlu",))
    with pytest.raises(ImportError, match="'pardiso' is not installed"):
        linsolve.resolve("pardiso")


def test_environment_sets_the_default(monkeypatch):
    monkeypatch.setenv(linsolve.ENV_VAR, "superlu")
    assert linsolve.default_solver() == "superlu"
    monkeypatch.setenv(linsolve.ENV_VAR, "nope")
    with pytest.raises(ValueError, match="linear solver"):
        linsolve.default_solver()


def test_a_bad_solution_falls_back_to_superlu(monkeypatch):
    # a library answer with a large residual (a perturbed pivot left unrepaired) must
    # not reach Newton: the residual check hands the system to SuperLU
    if "pardiso" not in linsolve.available():
        pytest.skip("pypardiso not installed")
    monkeypatch.setattr(linsolve.SymmetricSolver, "_solve_pardiso",
                        lambda self, k, b: np.zeros_like(b) + 1.0)
    k = _laplacian_3d(6)
    b = np.arange(k.shape[0], dtype=float)
    x = linsolve.solve_symmetric(k, b, "pardiso")
    assert np.linalg.norm(k @ x - b) <= 1e-12 * np.linalg.norm(b)


@pytest.mark.skipif(mkl_runtime_path() is None,
                    reason="MKL's runtime is not the environment's mkl wheel")
def test_pardiso_solves_do_not_search_the_environment_for_mkl():
    # pypardiso's solver walks the whole environment for MKL's runtime where
    # ctypes.util.find_library does not know the wheel's: the FEM loads the wheel's own
    code = (
        "import glob, os, sys\n"
        "calls = []\n"
        "walk = glob.glob\n"
        "glob.glob = lambda p, *a, **k: (calls.append(p), walk(p, *a, **k))[1]\n"
        "import numpy as np, scipy.sparse as sp\n"
        "from tightknot.fem import linsolve\n"
        "k = sp.diags([2.0, 3.0, 4.0]).tocsc()\n"
        "for _ in range(2):\n"
        "    x = linsolve.solve_symmetric(k, np.ones(3), 'pardiso')\n"
        "assert np.allclose(x, [1 / 2, 1 / 3, 1 / 4])\n"
        "print(sum('**' in p for p in calls))\n")
    env = {k: v for k, v in os.environ.items() if k != "PYPARDISO_MKL_RT"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=env)
    assert out.stdout.split() == ["0"]


@pytest.mark.skipif("pardiso" not in linsolve.available(), reason="MKL PARDISO not installed")
def test_pardiso_keeps_its_analysis_while_the_pattern_stays():
    # a Newton loop's tangents keep their pattern between changes of the contact set: those
    # solves must not redo the ordering and symbolic analysis, and a new pattern must
    rng = np.random.default_rng(5)
    k = _indefinite(10)
    solve = linsolve.SymmetricSolver("pardiso")
    for scale in (1.0, 2.0, 0.5):  # new values, the same pattern
        b = rng.standard_normal(k.shape[0])
        x = solve(scale * k, b)
        assert np.linalg.norm(scale * k @ x - b) <= 1e-10 * np.linalg.norm(b)
    assert solve.analyses == 1
    grown = sp.csc_matrix(k + sp.diags(0.1 * np.ones(k.shape[0] - 5), 5)
                          + sp.diags(0.1 * np.ones(k.shape[0] - 5), -5))
    b = rng.standard_normal(k.shape[0])
    x = solve(grown, b)
    assert np.linalg.norm(grown @ x - b) <= 1e-10 * np.linalg.norm(b)
    assert solve.analyses == 2
