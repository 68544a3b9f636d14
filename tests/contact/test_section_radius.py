"""The stretch-smoothed contact radius (ContactLayer(radius_window=...)): exact gradient and
Hessian through the window, both assembly paths, and the consistency and refusals."""

import math

import numpy as np
import pytest
import scipy.sparse as sp

from tightknot.contact.law import RadialComplianceLaw
from tightknot.contact.layer import ContactLayer
from tightknot.contact.report import contact_report
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material
from tightknot.rods.state import State
from tightknot.solvers.system import RodSystem

D0, E = 8.5e-3, 1.25e6


def _crossing(n: int = 36, gap: float = 0.88, closed_second: bool = False):
    """Two rods crossing at 90 degrees, overlapping by (1 - gap) D0, slightly perturbed."""
    b = RodBuilder(twist=False)
    mat = Material(E, 0.5, 1160.0)
    b.add_rod(np.linspace([0, 0, -1.5 * D0], [0, 0, 1.5 * D0], n + 1), D0, mat)
    b.add_rod(np.linspace([-1.5 * D0, gap * D0, 0], [1.5 * D0, gap * D0, 0], n + 1), D0, mat)
    m = b.finalize()
    rng = np.random.default_rng(0)
    x = m.vertex_initial_position + 0.01 * D0 * rng.standard_normal((m.vertex_count, 3))
    return m, x, rng


@pytest.mark.parametrize("window", [0.5, 1.0])
def test_gradient_and_hessian_are_exact(window):
    m, x, rng = _crossing()
    rest = m.edge_rest_length.copy()
    layer = ContactLayer(m, radius_window=window)
    e, g, (r, c, v) = layer.evaluate(x, rest, True, True)
    assert e > 0
    h_mat = sp.coo_matrix((v, (r, c)), shape=(m.dof_count,) * 2).tocsr()
    d = rng.standard_normal(x.shape)
    h = 1e-7 * D0
    ep = layer.evaluate(x + h * d, rest, False, False)[0]
    em = layer.evaluate(x - h * d, rest, False, False)[0]
    # central differences of step 1e-7 D0: relative error ~1e-9 (measured 7e-11 to 3e-9);
    # a missing chain-rule term is a percent or more
    assert (ep - em) / (2 * h) == pytest.approx(float((g * d).sum()), rel=1e-6)
    gp = layer.evaluate(x + h * d, rest, True, False)[1]
    gm = layer.evaluate(x - h * d, rest, True, False)[1]
    hd = (h_mat @ d.ravel()).reshape(-1, 3)
    err = np.abs(hd - (gp - gm) / (2 * h)).max() / np.abs(hd).max()
    assert err < 1e-6  # measured 4e-10 to 1.3e-9
    assert abs(h_mat - h_mat.T).max() <= 1e-12 * abs(h_mat).max()


def test_system_path_equals_coo_path():
    # RodSystem adds the kernel's part into its CSC (evaluate_into) and the window terms as
    # COO: its Hessian must equal the layer's own COO Hessian plus the elastic one
    m, x, _ = _crossing(n=24)
    layer = ContactLayer(m, radius_window=1.0)
    system = RodSystem(m, State.initial(m, x))
    system.add_term(layer)
    u = system.free_vector()
    _, g_sys, h_sys = system.evaluate(u, True, True)
    bare = RodSystem(m, State.initial(m, x))
    _, g_el, h_el = bare.evaluate(u, True, True)
    _, g_c, (r, c, v) = ContactLayer(m, radius_window=1.0).evaluate(x, m.edge_rest_length,
                                                                    True, True)
    h_c = sp.coo_matrix((v, (r, c)), shape=(m.dof_count,) * 2).tocsr()
    free = system.pattern.free_dofs
    ref = (h_el + h_c[free][:, free]).toarray()
    assert np.abs(h_sys.toarray() - ref).max() <= 1e-12 * np.abs(ref).max()
    np.testing.assert_allclose(g_sys, g_el + g_c.ravel()[free], rtol=0, atol=1e-12 * np.abs(
        g_sys).max())


def test_uniform_stretch_gives_the_edge_radius():
    # under a uniform stretch the window mean is the edge's own stretch: the same energy
    m, x, _ = _crossing(n=30, gap=0.9)
    x = m.vertex_initial_position.copy()
    x[:31, 2] *= 1.05  # the first rod stretched uniformly by 5 %
    rest = m.edge_rest_length
    e0 = ContactLayer(m).evaluate(x, rest, False, False)[0]
    e1 = ContactLayer(m, radius_window=1.0).evaluate(x, rest, False, False)[0]
    assert e0 > 0
    assert e1 == pytest.approx(e0, rel=1e-12)
    rep0 = contact_report(ContactLayer(m), x, rest)
    rep1 = contact_report(ContactLayer(m, radius_window=1.0), x, rest)
    np.testing.assert_allclose(rep1.area_ratio, rep0.area_ratio, rtol=1e-12)


def test_window_spreads_the_thinning():
    # one edge stretched: its own radius thins, the window spreads it over about 25 edges
    m, x, _ = _crossing(n=36)
    x = m.vertex_initial_position.copy()
    x[19:37, 2] += 0.02 * D0  # edge 18 stretched by 0.02 D0 / (D0/12) = 24 %
    layer = ContactLayer(m, radius_window=1.0)
    lam = layer.section_stretch(x, m.edge_rest_length)
    own = ContactLayer(m).section_stretch(x, m.edge_rest_length)
    assert own[18] == pytest.approx(1.24)
    assert layer.section_radius.window_edges[0] == 12  # 1 D0 at 12 edges per D0
    assert lam[18] == pytest.approx(1.0 + 0.24 / 25)  # a window of 25 edges
    assert lam[:36].sum() == pytest.approx(own[:36].sum(), rel=0.02)  # cut at the ends


@pytest.mark.parametrize("window", [-0.1, 10.5, math.nan, math.inf])
def test_bad_window_is_refused(window):
    m, _, _ = _crossing(n=8)
    with pytest.raises(ValueError, match="radius_window must be in"):
        ContactLayer(m, radius_window=window)


def test_rigid_tube_refuses_a_window():
    m, _, _ = _crossing(n=8)
    with pytest.raises(ValueError, match="needs a compliant law"):
        ContactLayer(m, RadialComplianceLaw.from_json().rigid_tube(), radius_window=1.0)
