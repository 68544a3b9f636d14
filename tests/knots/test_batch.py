"""Batched tying (tightknot.knots.batch): the joint solve equals the one-by-one solves."""

import numpy as np
import pytest

from tightknot.knots.batch import build_batch, tie_batch
from tightknot.knots.scenes import closed_trefoil, open_trefoil
from tightknot.knots.tie import tie
from tightknot.solvers.linear import factorize

#: Small, different cases (a sweep of L0/D0): 48 vertices keep the test a few seconds.
RATIOS = (17.0, 18.0, 20.0)
NODES = 48


def newton_correction(system) -> float:  # noqa: ANN001
    """Largest vertex move [m] of one more full Newton step from the system's state: how
    far the converged iterate may still be from the exact equilibrium."""
    u = system.free_vector()
    _, g, h = system.evaluate(u, True, True)
    du = factorize(h).solve(-g)
    return float(np.abs(system.positions(u + du) - system.positions(u)).max())


def test_batch_agrees_with_one_by_one():
    scenes = [closed_trefoil(l0_over_d0=r, nodes=NODES) for r in RATIOS]
    batch = tie_batch(scenes)
    assert batch.converged, batch.failure
    assert batch.knot_types == ["3_1"] * len(RATIOS)
    corr_b = newton_correction(batch.system)
    for r, x_b in zip(RATIOS, batch.positions, strict=True):
        scene = closed_trefoil(l0_over_d0=r, nodes=NODES)
        single = tie(scene)
        assert single.converged, single.failure
        corr_s = newton_correction(single.system)
        diff = float(np.abs(single.system.state.x - x_b).max())
        # Both runs stop within one Newton correction of the same equilibrium (the joint
        # system is block diagonal); the floor 1e-9 D0 covers the round-off of positions
        # when both corrections vanish (measured difference here: ~1e-13 D0).
        assert diff <= 2.0 * (corr_b + corr_s) + 1e-9 * scene.diameter, (r, diff, corr_b,
                                                                          corr_s)


def test_copies_never_touch_each_other():
    scenes = [closed_trefoil(l0_over_d0=17.0, nodes=NODES) for _ in range(2)]
    batch = tie_batch(scenes)
    assert batch.converged, batch.failure
    layer = batch.system.extra_terms[0]
    rods = batch.system.model.edge_rod
    pairs = layer.last_pairs
    assert len(pairs) > 0  # the tied knots are in self-contact
    assert (rods[pairs[:, 0]] == rods[pairs[:, 1]]).all()
    # Identical cases reach identical shapes, wherever their copy sits.
    for x in batch.positions[1:]:
        np.testing.assert_allclose(x, batch.positions[0], rtol=0, atol=1e-9 * 8.5e-3)


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
