"""The contact radius thinned by each rod's mean stretch (ContactLayer(thinning="rod")):
exact gradient and Hessian through the rods' lengths, the system's low-rank path against
the dense one, and the consistency and refusals."""

import numpy as np
import pytest
import scipy.sparse as sp

from tightknot.contact.law import RadialComplianceLaw
from tightknot.contact.layer import ContactLayer
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material
from tightknot.rods.state import State
from tightknot.solvers.linear import LowRankHessian, SparseDirect
from tightknot.solvers.system import RodSystem

D0, E = 8.5e-3, 1.25e6


def _crossing(n: int = 36, gap: float = 0.88, nu: float = 0.5):
    """Two rods crossing at 90 degrees, overlapping by (1 - gap) D0, perturbed and
    stretched unevenly (so that the rods' mean stretches differ from their edges')."""
    b = RodBuilder(twist=False)
    mat = Material(E, nu, 1160.0)
    b.add_rod(np.linspace([0, 0, -1.5 * D0], [0, 0, 1.5 * D0], n + 1), D0, mat)
    b.add_rod(np.linspace([-1.5 * D0, gap * D0, 0], [1.5 * D0, gap * D0, 0], n + 1), D0, mat)
    m = b.finalize()
    rng = np.random.default_rng(0)
    x = m.vertex_initial_position + 0.01 * D0 * rng.standard_normal((m.vertex_count, 3))
    x[: n + 1, 2] *= 1.0 + 0.1 * np.linspace(0.0, 1.0, n + 1)
    return m, x, rng


@pytest.mark.parametrize("nu", [0.5, 0.3])
def test_gradient_and_hessian_are_exact(nu):
    m, x, rng = _crossing(nu=nu)
    rest = m.edge_rest_length.copy()
    layer = ContactLayer(m, thinning="rod")
    e, g, (r, c, v) = layer.evaluate(x, rest, True, True)
    assert e > 0
    h_mat = sp.coo_matrix((v, (r, c)), shape=(m.dof_count,) * 2).tocsr()
    d = rng.standard_normal(x.shape)
    h = 1e-7 * D0
    ep = layer.evaluate(x + h * d, rest, False, False)[0]
    em = layer.evaluate(x - h * d, rest, False, False)[0]
    # central differences of step 1e-7 D0: relative error ~1e-9; a missing chain-rule term
    # (the rod's length) is a percent or more
    assert (ep - em) / (2 * h) == pytest.approx(float((g * d).sum()), rel=1e-6)
    gp = layer.evaluate(x + h * d, rest, True, False)[1]
    gm = layer.evaluate(x - h * d, rest, True, False)[1]
    hd = (h_mat @ d.ravel()).reshape(-1, 3)
    err = np.abs(hd - (gp - gm) / (2 * h)).max() / np.abs(hd).max()
    assert err < 1e-6
    assert abs(h_mat - h_mat.T).max() <= 1e-12 * abs(h_mat).max()


def test_the_radius_is_the_rods_mean_stretch():
    m, x, _ = _crossing()
    rest = m.edge_rest_length
    layer = ContactLayer(m, thinning="rod")
    lam = layer.section_stretch(x, rest)
    ev = m.edge_vertex
    le = np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1)
    first = m.rods[0].edge_slice
    assert np.all(lam[first] == lam[first][0])
    assert lam[first][0] == pytest.approx(le[first].sum() / rest[first].sum(), rel=1e-14)
    # uneven along the first rod (its own edges' stretches span 1.0 to 1.1), one value here
    own = ContactLayer(m).section_stretch(x, rest)[first]
    assert own.max() - own.min() > 0.05


def test_uniform_stretch_gives_the_edge_radius():
    # a rod stretched uniformly: its mean stretch is each edge's, the same energy
    m, _, _ = _crossing(n=30, gap=0.9)
    x = m.vertex_initial_position.copy()
    x[:31, 2] *= 1.05
    rest = m.edge_rest_length
    e0 = ContactLayer(m).evaluate(x, rest, False, False)[0]
    e1 = ContactLayer(m, thinning="rod").evaluate(x, rest, False, False)[0]
    assert e0 > 0
    assert e1 == pytest.approx(e0, rel=1e-12)


def test_system_low_rank_path_equals_the_dense_hessian():
    # RodSystem keeps the dense update as U C U^T beside its sparse Hessian; products,
    # diagonal and the Newton solve must be those of the dense matrix
    m, x, rng = _crossing(n=24)
    layer = ContactLayer(m, thinning="rod")
    system = RodSystem(m, State.initial(m, x))
    system.add_term(layer)
    u = system.free_vector()
    _, g_sys, h_sys = system.evaluate(u, True, True)
    assert isinstance(h_sys, LowRankHessian)
    bare = RodSystem(m, State.initial(m, x))
    _, g_el, h_el = bare.evaluate(u, True, True)
    _, g_c, (r, c, v) = ContactLayer(m, thinning="rod").evaluate(x, m.edge_rest_length,
                                                                 True, True)
    h_c = sp.coo_matrix((v, (r, c)), shape=(m.dof_count,) * 2).tocsr()
    free = system.pattern.free_dofs
    ref = (h_el + h_c[free][:, free]).toarray()
    np.testing.assert_allclose(g_sys, g_el + g_c.ravel()[free], rtol=0,
                               atol=1e-12 * np.abs(g_sys).max())
    lin = SparseDirect()
    d = rng.standard_normal(u.size)
    scale = np.abs(ref).max()
    assert np.abs(lin.matrix(h_sys) @ d - ref @ d).max() <= 1e-11 * scale * np.abs(d).max()
    assert np.abs(lin.diagonal(h_sys) - np.diag(ref)).max() <= 1e-12 * scale
    diag = np.abs(np.diag(ref)) + 1.0
    step = lin.shifted_direction(h_sys, g_sys, 1e-3, diag)
    dense = np.linalg.solve(ref + 1e-3 * np.diag(diag), -g_sys)
    assert np.abs(step - dense).max() <= 1e-8 * np.abs(dense).max()


def test_bad_thinning_is_refused():
    m, _, _ = _crossing(n=8)
    with pytest.raises(ValueError, match="thinning must be one of"):
        ContactLayer(m, thinning="vertex")
    with pytest.raises(ValueError, match="takes no radius_window"):
        ContactLayer(m, thinning="rod", radius_window=1.0)
    with pytest.raises(ValueError, match="needs a compliant law"):
        ContactLayer(m, RadialComplianceLaw.from_json().rigid_tube(), thinning="rod")
