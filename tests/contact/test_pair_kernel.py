"""The pair kernel's variants: each takes only the arrays it uses, and they agree bit for bit
on what they share (energy, gradient); the Hessian added into CSC data equals the per-pair
one."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import warp as wp

from tests.contact.test_contact import D, two_rods
from tightknot.contact.layer import ContactLayer, ContactSettings
from tightknot.contact.pair_kernel import VARIANTS, Hessian, pair_kernel
from tightknot.solvers.pattern import ContactPattern, SparsePattern

#: Arguments only some variants take.
_OPTIONAL = {"edge_radius_in", "block_keys_in", "block_rows_in", "block_cols_in",
             "vertex_rank_in", "grad_out", "hess_out", "csc_out", "missing_out", "dR_out"}


@pytest.mark.parametrize("variant", VARIANTS)
def test_each_variant_takes_only_the_arrays_it_uses(variant) -> None:
    gradient, hessian, given = variant
    names = {a.label for a in pair_kernel(*variant).adj.args}
    expect = set()
    if given:
        expect.add("edge_radius_in")
    if hessian == Hessian.CSC:
        expect |= {"block_keys_in", "block_rows_in", "block_cols_in", "vertex_rank_in",
                   "csc_out", "missing_out"}
    if gradient:
        expect.add("grad_out")
    if hessian == Hessian.PER_PAIR:
        expect.add("hess_out")
    if given and gradient:
        expect.add("dR_out")
    assert names & _OPTIONAL == expect
    assert {"x_in", "pairs_in", "law", "energy_out", "overlap_out"} <= names


def test_a_hessian_needs_the_gradient() -> None:
    with pytest.raises(ValueError, match="needs the gradient"):
        pair_kernel(False, Hessian.CSC, False)


def _csc_hessian(layer: ContactLayer, x: np.ndarray, rest: np.ndarray):
    """evaluate_into on a pattern grown until no block is missing: energy, gradient and
    the Hessian over all position dofs (dense)."""
    m = layer.model
    cp = ContactPattern(m, SparsePattern(m, np.ones(m.dof_count, dtype=bool)))
    while True:
        data = wp.zeros(max(cp.nnz, 1), dtype=wp.float64, device=m.device)
        out = layer.evaluate_into(x, rest, cp.warp_tables(m.device), data)
        if out[1] is not None:
            break
        cp.grow(layer.missing_blocks())
    h = cp.matrix(data.numpy()[: cp.nnz]).toarray()
    if len(out) > 2:  # the smoothed radius's terms outside the pair blocks
        r, c, v = out[2]
        h = h + sp.coo_matrix((v, (r, c)), shape=h.shape).toarray()
    return out[0], out[1], h


@pytest.mark.parametrize("window", [0.0, 1.0])
def test_the_variants_agree(window: float) -> None:
    m = two_rods(60.0, 0.8 * D, n=21, noise=0.01)
    layer = ContactLayer(m, radius_window=window)
    x = m.vertex_initial_position.copy()
    rest = m.edge_rest_length * 1.02
    e0, _, _ = layer.evaluate(x, rest, False, False)
    e1, g1, _ = layer.evaluate(x, rest, True, False)
    e2, g2, coo = layer.evaluate(x, rest, True, True)
    e3, g3, h3 = _csc_hessian(layer, x, rest)
    assert e0 > 0.0 and e0 == e1 == e2 == e3
    np.testing.assert_array_equal(g1, g2)
    np.testing.assert_array_equal(g1, g3)
    h2 = sp.coo_matrix((coo[2], (coo[0], coo[1])), shape=h3.shape).toarray()
    assert np.abs(h2 - h3).max() <= 1e-13 * np.abs(h2).max()


def test_settings_are_one_record() -> None:
    m = two_rods(90.0, 2.0 * D, n=5)
    layer = ContactLayer(m, hard_fraction=0.1, local_thickness=True)
    law = layer.law  # the core comes from the law's calibration
    assert layer.settings == ContactSettings(
        hard_fraction=0.1, local_thickness=True, core_fraction=law.core_fraction,
        hard_relative=law.core_hard_relative, core_stiffness=law.core_stiffness)
    assert layer.settings.candidate_window == 0.5
    assert ContactLayer(m, layer.law, **layer.settings.as_kwargs()).settings == layer.settings
    rigid = ContactLayer(m, layer.law.rigid_tube())
    assert (rigid.core_fraction, rigid.hard_relative) == (1.0, 0.98)
