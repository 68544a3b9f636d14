"""MKL PARDISO for the sectioned level's Newton systems (tightknot.solvers.pardiso): the
same directions as SuperLU, the analysis kept while the pattern stays, the choice of
solver by the environment."""

from __future__ import annotations

import glob
import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse as sp

from tightknot.solvers import pardiso
from tightknot.solvers.linear import LowRankHessian, SparseDirect

needs_mkl = pytest.mark.skipif(not pardiso.available(), reason="pypardiso and MKL not installed")


def _blocks(n_nodes: int, block: int, pairs: list[tuple[int, int]], seed: int = 0,
            indefinite: bool = False) -> sp.csc_matrix:
    """A symmetric matrix of dense node blocks along a chain plus the node pairs ``pairs``
    (the sectioned level's pattern in small), positive definite unless ``indefinite``."""
    rng = np.random.default_rng(seed)
    n = n_nodes * block
    links = [(i, i + 1) for i in range(n_nodes - 1)] + list(pairs)
    a = sp.lil_matrix((n, n))
    for i, j in links:
        c = 0.3 * rng.standard_normal((block, block))
        a[i * block:(i + 1) * block, j * block:(j + 1) * block] = c
        a[j * block:(j + 1) * block, i * block:(i + 1) * block] = c.T
    a = a.tocsc()
    a = a + a.T
    # diagonal dominance makes it definite; one negative block makes it indefinite
    d = np.abs(a).sum(axis=1).A.ravel() + 1.0
    if indefinite:
        d[:block] *= -1.0
    a = a + sp.diags(d)
    # scaled symmetrically by decades, as positions and section amplitudes are (S A S
    # keeps the inertia)
    s = sp.diags(10.0 ** (0.5 * rng.integers(-3, 4, n_nodes).repeat(block)))
    return sp.csc_matrix(s @ a @ s)


@needs_mkl
@pytest.mark.parametrize("indefinite", [False, True])
@pytest.mark.parametrize("mu", [0.0, 1e-3])
def test_the_direction_is_superlus(indefinite: bool, mu: float) -> None:
    a = _blocks(30, 6, [(2, 20), (5, 17), (9, 25)], indefinite=indefinite)
    g = np.random.default_rng(1).standard_normal(a.shape[0])
    diag = np.abs(a.diagonal())
    d = pardiso.PardisoDirect(convex=False).shifted_direction(a, g, mu, diag)
    ref = SparseDirect.shifted_direction(a, g, mu, diag)
    # both direct: round-off of a well-conditioned system (condition ~1e6 from the
    # decades of scale, removed by the equilibration)
    assert np.linalg.norm(d - ref) <= 1e-10 * np.linalg.norm(ref)


@needs_mkl
def test_a_matrix_with_a_negative_eigenvalue_is_refused_until_shifted() -> None:
    # PARDISO's inertia: a convex solver refuses H + mu D while it has a negative
    # eigenvalue, so that the Newton loop raises mu (here the first block's diagonal is
    # negative: a shift of twice its size makes the matrix definite again)
    a = _blocks(30, 6, [(2, 20), (5, 17)], indefinite=True)
    g = np.random.default_rng(1).standard_normal(a.shape[0])
    diag = np.abs(a.diagonal())
    solver = pardiso.PardisoDirect()
    assert np.linalg.eigvalsh(a.toarray()).min() < 0.0
    assert solver.shifted_direction(a, g, 0.0, diag) is None
    assert solver.indefinite == 1
    shifted = a + sp.diags(3.0 * diag)
    assert np.linalg.eigvalsh(shifted.toarray()).min() > 0.0
    d = solver.shifted_direction(a, g, 3.0, diag)
    assert d is not None
    assert np.linalg.norm(shifted @ d + g) <= 1e-10 * np.linalg.norm(g)
    assert solver.indefinite == 1
    # without the test (a low-rank update's solver) the indefinite direction is returned
    assert pardiso.PardisoDirect(convex=False).shifted_direction(a, g, 0.0, diag) is not None


@needs_mkl
def test_a_low_rank_update_is_solved_around_the_sparse_part() -> None:
    a = _blocks(20, 4, [(3, 15)])
    rng = np.random.default_rng(2)
    u = rng.standard_normal((a.shape[0], 2))
    c = np.array([[2.0, 1.0], [1.0, 0.0]])
    h = LowRankHessian(a, u, c)
    g = rng.standard_normal(a.shape[0])
    d = pardiso.PardisoDirect().shifted_direction(h, g, 0.0, np.ones(a.shape[0]))
    assert np.allclose(h.toarray() @ d, -g, rtol=0.0, atol=1e-10 * np.abs(g).max())


@needs_mkl
def test_the_analysis_is_kept_while_the_pattern_stays() -> None:
    solver = pardiso.PardisoDirect()
    a = _blocks(30, 6, [(2, 20)], seed=3)
    g = np.ones(a.shape[0])
    diag = np.abs(a.diagonal())
    solver.shifted_direction(a, g, 0.0, diag)
    solver.shifted_direction(a, g, 1e-3, diag)  # a shift: the same pattern
    solver.shifted_direction(_blocks(30, 6, [(2, 20)], seed=4), g, 0.0, diag)
    assert (solver.analyses, solver.orderings, solver.factorizations) == (1, 1, 3)
    # a contact block more: a new analysis on the kept ordering (a few % more entries)
    b = _blocks(30, 6, [(2, 20), (7, 23)], seed=5)
    d = solver.shifted_direction(b, g, 0.0, diag)
    assert (solver.analyses, solver.orderings) == (2, 1)
    assert np.linalg.norm(b @ d + g) <= 1e-10 * np.linalg.norm(g)
    # many more: a new ordering
    c = _blocks(30, 6, [(i, i + 10) for i in range(20)], seed=6)
    d = solver.shifted_direction(c, g, 0.0, diag)
    assert (solver.analyses, solver.orderings) == (3, 2)
    assert np.linalg.norm(c @ d + g) <= 1e-10 * np.linalg.norm(g)
    # another size: a new ordering
    e = _blocks(10, 6, [], seed=7)
    d = solver.shifted_direction(e, g[:60], 0.0, diag[:60])
    assert solver.orderings == 3
    assert np.linalg.norm(e @ d + g[:60]) <= 1e-10 * np.linalg.norm(g[:60])


def test_the_environment_picks_the_solver(monkeypatch) -> None:
    monkeypatch.setenv(pardiso.ENV_VAR, "superlu")
    assert pardiso.section_solver() == "superlu"
    assert type(pardiso.section_linear()) is SparseDirect
    monkeypatch.setenv(pardiso.ENV_VAR, "auto")
    assert pardiso.section_solver() == ("pardiso" if pardiso.available() else "superlu")
    monkeypatch.setenv(pardiso.ENV_VAR, "mumps")
    with pytest.raises(ValueError, match=pardiso.ENV_VAR):
        pardiso.section_solver()
    if not pardiso.available():
        with pytest.raises(ImportError, match="pypardiso"):
            pardiso.section_solver("pardiso")


@needs_mkl
def test_a_sectioned_system_solves_with_pardiso_and_the_others_with_superlu(monkeypatch
                                                                           ) -> None:
    from tightknot.knots.scenes import closed_trefoil, gauge
    from tightknot.solvers.system import RodSystem

    monkeypatch.delenv(pardiso.ENV_VAR, raising=False)
    for contact, kind in (("compliant", SparseDirect), ("sectioned", pardiso.PardisoDirect)):
        scene = closed_trefoil(17.0, nodes=40, contact=contact)
        system = RodSystem(scene.model, scene.state.copy(), gauge(scene))
        system.add_term(scene.contact)
        assert type(system.linear) is kind


@needs_mkl
@pytest.mark.skipif(not glob.glob(os.path.join(sys.prefix, "lib", "libmkl_rt.so*")),
                    reason="MKL's runtime is not the environment's mkl wheel")
def test_mkl_is_loaded_without_importing_pypardiso() -> None:
    # pypardiso's import builds a solver whose search for MKL walks the whole environment
    # (most of a second per process): the wheel's runtime is loaded directly, pypardiso
    # only found.
    code = ("import sys; from tightknot.solvers import pardiso; "
            "print(pardiso.available(), 'pypardiso' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.split() == ["True", "False"]
