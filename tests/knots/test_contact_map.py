"""Contact map symmetry and the open-knot length Lambda_OC."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from tightknot.knots.contact_map import contact_pairs
from tightknot.knots.ideal import load_ideal_trefoil
from tightknot.knots.measure import analyze_centerline


def test_contact_map_is_symmetric_and_point_symmetric():
    rep = analyze_centerline(load_ideal_trefoil(1.0)[::2], 1.0, closed=True, contact_tol=0.01)
    s = np.array(rep["contact_s"])
    sig = np.array(rep["contact_sigma"])
    assert s.size > 1000
    pairs = set(zip(s.round(9), sig.round(9), strict=True))
    assert pairs == set(zip(sig.round(9), s.round(9), strict=True))  # s <-> sigma, exact
    # Point symmetry about (0, 0) (the 2-fold axis through s = 0; Johanns et al. 2021): the
    # image of every contact is within a few vertex spacings (0.014 D here) of a contact.
    period = 16.372
    box = period + 1e-6
    tree = cKDTree(np.stack([s, sig], 1) % box, boxsize=box)
    d, _ = tree.query(np.stack([-s, -sig], 1) % box)
    assert np.quantile(d, 0.99) < 0.05


def test_radii_per_vertex():
    # Two parallel strands 1 apart: in contact only where radii add to >= 1.
    x = np.linspace(0, 10, 101)
    a = np.stack([x, 0 * x, 0 * x], 1)
    b = np.stack([x[::-1], 0 * x + 1.0, 0 * x], 1)
    pts = np.vstack([a, b])
    radii = np.full(pts.shape[0], 0.45)
    radii[:50] = 0.6  # x < 5 on strand a
    i, j = contact_pairs(pts, False, radii, tol=0.0, exclusion=3.0)
    # a_i + a_j = 1.05 reaches across the gap of 1 within |dx| <= sqrt(1.05^2 - 1) = 0.32.
    on_a = i < 101
    assert on_a.sum() > 40 and np.all(pts[i[on_a], 0] < 5.0)
    assert np.all(pts[j[on_a], 0] < 5.0 + 0.33)


def crossing_rod(D: float = 1.0, n_per: int = 2001):
    """Rod along x at z = 0, a far loop, then along y at z = D crossing over x = y = 0."""
    t = np.linspace(-10, 10, n_per)
    first = np.stack([t, 0 * t, 0 * t], 1)
    loop = np.array([[15.0, 0, 0], [15.0, -15.0, D], [0, -15.0, D]])
    second = np.stack([0 * t, t, 0 * t + D], 1)
    return np.vstack([first, loop, second])


def test_lambda_oc_on_crossing():
    D = 1.0
    pts = crossing_rod(D)
    rep = analyze_centerline(pts, D, closed=False, contact_tol=0.01)
    S = np.array(rep["S"])
    s_cross_1 = 10.0  # strand 1 passes the crossing at x = 0, 10 from the start
    k = 2001 + 3 + 1000  # the vertex of strand 2 at y = 0
    s_cross_2 = S[k]
    # Contact within (1 + tol) D of a perpendicular strand at distance D extends
    # sqrt((1 + tol)^2 - 1) D = 0.142 D each side of the crossing. The entrance and exit
    # are interpolated along their edges (0.01 D): the gap is smooth there, so linear
    # interpolation and the other strand's vertex spacing leave errors of order
    # h^2 / D = 1e-4 D, far below an edge.
    half = np.sqrt(1.01**2 - 1) * D
    assert rep["contact_S1"] == pytest.approx(s_cross_1 - half, abs=1e-3)
    assert rep["contact_S2"] == pytest.approx(s_cross_2 + half, abs=1e-3)
    assert rep["Lambda_OC"] == pytest.approx((s_cross_2 - s_cross_1 + 2 * half) / D, abs=2e-3)
    s = np.array(rep["s"])
    mid = 0.5 * (rep["contact_S1"] + rep["contact_S2"])  # s = 0 at the middle of the knot
    np.testing.assert_allclose(s, (S - mid) / D, atol=1e-12)


def test_no_contact_gives_none():
    x = np.linspace(0, 10, 50)
    rep = analyze_centerline(np.stack([x, 0 * x, 0 * x], 1), 1.0, closed=False)
    assert rep["Lambda_OC"] is None and rep["contact_s"] == []
    assert rep["knot_type"] == "0_1"
