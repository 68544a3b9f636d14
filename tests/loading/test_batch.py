"""Batched tying (tightknot.loading.batch and its batch_* modules): each rod of the batch
reaches its own tie's equilibrium; the joint evaluation equals one rod's; the banded solves
equal SuperLU's."""

import numpy as np
import pytest
import scipy.sparse as sp

from tightknot.contact.layer import ContactLayer
from tightknot.knots.scenes import closed_trefoil, gauge, open_trefoil
from tightknot.loading.batch import _layer_settings, build_batch, tie_batch
from tightknot.loading.tie import tie
from tightknot.solvers.banded import (
    BandedCholesky,
    BandPlan,
    _openblas_libraries,
    banded_lu_solve,
    single_blas_thread,
)
from tightknot.solvers.batch_eval import BatchEvaluator, EvalRequest, batch_contact_layer
from tightknot.solvers.linear import SparseDirect, factorize
from tightknot.solvers.pattern import SparsePattern

#: Small, different cases (a sweep of L0/D0): 48 vertices keep the test a few seconds.
RATIOS = (17.0, 18.0, 20.0)
NODES = 48


def newton_correction(system) -> float:  # noqa: ANN001
    """Largest vertex move [m] of one more full Newton step from the system's state: how
    far the converged iterate may still be from the exact equilibrium."""
    u = system.free_vector()
    _, g, h = system.evaluate(u, True, True)
    du = SparseDirect.shifted_direction(h, g, 0.0, np.ones(u.size))  # (a low-rank update)
    return float(np.abs(system.positions(u + du) - system.positions(u)).max())


def test_batch_agrees_with_one_by_one():
    scenes = [closed_trefoil(l0_over_d0=r, nodes=NODES) for r in RATIOS]
    batch = tie_batch(scenes, tighten_steps=20)
    assert batch.converged, batch.failure
    assert batch.knot_types == ["3_1"] * len(RATIOS)
    singles = []
    for k, (r, x_b) in enumerate(zip(RATIOS, batch.positions, strict=True)):
        scene = closed_trefoil(l0_over_d0=r, nodes=NODES)
        single = tie(scene, tighten_steps=20).run()
        assert single.converged, single.failure
        singles.append(single)
        # Each rod's own system evaluates on its own (its scene's contact layer).
        corr_b = newton_correction(batch.rods[k].system)
        corr_s = newton_correction(single.system)
        diff = float(np.abs(single.system.state.x - x_b).max())
        # Both runs stop within one Newton correction of the same equilibrium (each rod
        # runs tie()'s solver; the evaluations differ by round-off only); the floor 1e-9 D0
        # covers the round-off of positions when both corrections vanish (measured
        # difference here: ~1e-14 D0).
        assert diff <= 2.0 * (corr_b + corr_s) + 1e-9 * scene.diameter, (r, diff, corr_b,
                                                                          corr_s)
    # The rods do not hold each other back: each takes about its own tie's Newton
    # iterations (measured: equal here; round-off may change a few iterations of a
    # 100-vertex rod), not the several-fold count of one shared load path.
    n_single = sum(s.newton_iterations for s in singles)
    assert abs(batch.newton_iterations - n_single) <= 0.05 * n_single
    # A round answers every rod's pending question: the rounds are those of the slowest
    # rod, not the sum over rods (measured: 182 rounds for 363 iterations in all).
    assert batch.rounds < 0.7 * n_single


def test_copies_never_touch_each_other():
    scenes = [closed_trefoil(l0_over_d0=17.0, nodes=NODES) for _ in range(2)]
    batch = tie_batch(scenes, tighten_steps=20)
    assert batch.converged, batch.failure
    # All candidate pairs of the joint model at the result: none joins two copies.
    joint = build_batch(scenes)
    x = np.concatenate([xb + off for xb, off in zip(batch.positions, joint.offsets,
                                                    strict=True)])
    rest = np.concatenate([o.system.rest for o in batch.rods])
    e, _, _ = joint.contact.evaluate(x, rest, True, False)
    pairs = joint.contact.last_pairs
    rods = joint.model.edge_rod
    assert len(pairs) > 0 and e > 0.0  # the tied knots are in self-contact
    assert (rods[pairs[:, 0]] == rods[pairs[:, 1]]).all()
    # Identical cases reach the same shape, wherever their copy sits (the copies' offsets
    # change the round-off of the joint evaluation only; measured difference 0).
    np.testing.assert_allclose(batch.positions[1], batch.positions[0], rtol=0,
                               atol=1e-9 * scenes[0].diameter)


def test_joint_evaluation_equals_one_rod():
    """Energy parts, gradient and Hessian of a tight knot, asked of the batch evaluator,
    equal those of its own RodSystem (contact included)."""
    scene = closed_trefoil(l0_over_d0=17.0, nodes=NODES)
    single = tie(scene, tighten_steps=20).run().system
    st = single.state
    scenes = [closed_trefoil(l0_over_d0=r, nodes=NODES) for r in (17.0, 19.0)]
    joint = build_batch(scenes)
    patterns = [SparsePattern(sc.model, ~gauge(sc).fixed_mask()) for sc in scenes]
    ev = BatchEvaluator(joint.model, joint.contact, joint.offsets,
                        [sc.model for sc in scenes], patterns)
    ev.set_rest(1, single.rest)
    # Rod 0 stays at its loose start; rod 1 carries the tight state.
    # Off the equilibrium (a small random move of every free dof), so that the gradient
    # is not just round-off.
    u = single.free_vector()
    u = u + 1e-3 * np.random.default_rng(5).normal(size=u.size) * np.where(
        single.free_is_theta, 1.0, scene.diameter)
    q = single.full_dofs()
    q[single.pattern.free_dofs] = u
    x, theta = single.positions(u), q[single.model.edge_dof]
    ans = ev.evaluate([EvalRequest(1, x, theta, st.d1_ref, st.t_ref, st.m_ref)])[1]
    e, g, h = single.evaluate(u, True, True)
    split = single.last_split
    assert split.extra["contact"] > 0.0
    scale = split.magnitude
    # Sums over edges, joints and pairs in another order (and coordinates shifted by the
    # copy's offset): round-off of the energy, ~1e-16 of its magnitude; 1e-12 is far
    # below any physical change and far above that round-off.
    for got, want in ((ans.stretch, split.stretch), (ans.bend, split.bend),
                      (ans.twist, split.twist), (ans.contact, split.extra["contact"])):
        assert abs(got - want) <= 1e-12 * scale
    free = patterns[1].free_dofs
    np.testing.assert_allclose(ans.grad[free], g, rtol=0, atol=1e-9 * np.abs(g).max())
    hb = ans.hess.matrix().toarray()
    if ans.low_rank is not None:  # the rod-mean contact radius's dense update
        u_lr, c_lr = ans.low_rank
        hb = hb + u_lr @ c_lr @ u_lr.T
    hs = h.toarray()
    np.testing.assert_allclose(hb, hs, rtol=0, atol=1e-9 * np.abs(hs).max())


def _symmetric(n: int, seed: int, shift: float) -> sp.csc_matrix:
    """A random sparse symmetric matrix: a chain (like a rod's stencils) plus scattered
    couplings (like contacts), with ``shift`` on the diagonal."""
    rng = np.random.default_rng(seed)
    a = sp.random(n, n, density=0.03, random_state=rng)
    off = rng.uniform(1, 2, n - 1)
    a = a + a.T + sp.diags(np.full(n, shift)) + sp.diags(off, 1) + sp.diags(off, -1)
    return sp.csc_matrix(a)


@pytest.mark.parametrize("shift, definite", [(12.0, True), (0.1, False)])
def test_banded_solves_equal_superlu(shift: float, definite: bool):
    a = _symmetric(120, 3, shift)
    a.sort_indices()
    if not definite:
        assert np.linalg.eigvalsh(a.toarray()).min() < 0.0
    plan = BandPlan(a.indptr, a.indices)
    b = np.random.default_rng(4).normal(size=120)
    want = factorize(a).solve(b)
    chol, z = BandedCholesky.factor_or_certificate(plan, a.data)
    assert (chol is not None) == definite
    if not definite:
        # The certificate of indefiniteness: a direction of negative curvature.
        assert z @ (a @ z) < 0.0
    for got in ([chol.solve(b)] if chol else []) + [banded_lu_solve(plan, a.data, b)]:
        # Both direct solves of a well-conditioned system: agreement to ~1e-12 relative.
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-10 * np.abs(want).max())


def test_single_blas_thread_restores_the_thread_counts():
    before = [getattr(lib, get)() for lib, get, _ in _openblas_libraries()]
    with single_blas_thread():
        assert all(getattr(lib, get)() == 1 for lib, get, _ in _openblas_libraries())
    assert [getattr(lib, get)() for lib, get, _ in _openblas_libraries()] == before


def test_a_failed_rod_is_named():
    scenes = [closed_trefoil(l0_over_d0=20.0, nodes=NODES)]
    batch = tie_batch(scenes, tighten_steps=20, relax_iterations=2)
    assert not batch.converged
    assert batch.failure.startswith("rod 0 (closed_trefoil, L0/D0 20)")
    assert "relax: Newton max_iterations" in batch.failure


def test_batch_layer_keeps_the_scene_layer_settings():
    sc = closed_trefoil(nodes=NODES)
    like = ContactLayer(sc.model, sc.contact.law, gauss_points=3, hard_fraction=0.1,
                        core_stiffness=2.0, local_thickness=True)
    joint = build_batch([sc])
    assert _layer_settings(batch_contact_layer(joint.model, like)) == _layer_settings(like)
    assert _layer_settings(joint.contact) == _layer_settings(sc.contact)


def test_bad_input():
    with pytest.raises(ValueError, match="at least one"):
        build_batch([])
    with pytest.raises(ValueError, match="open"):
        build_batch([open_trefoil(nodes=120)])
    scenes = [closed_trefoil(nodes=NODES), closed_trefoil(nodes=NODES, twist=False)]
    with pytest.raises(ValueError, match="twist"):
        build_batch(scenes)
    with pytest.raises(ValueError, match="residual_tol"):
        tie_batch([closed_trefoil(nodes=NODES)], residual_tol=float("nan"))
    with pytest.raises(ValueError, match="relax_iterations"):
        tie_batch([closed_trefoil(nodes=NODES)], relax_iterations=0)
