"""Curves, resampling, non-local distance and scaling to a rod diameter."""

import numpy as np
import pytest

from tightknot.knots import curves
from tightknot.knots._arclength import edge_lengths, total_length
from tightknot.knots.curvature import bergou_curvature


def test_resample_uniform_spacing_and_length():
    pts = curves.trefoil(300)
    q = curves.resample_uniform(pts, 1000, closed=True)
    lengths = edge_lengths(q, closed=True)
    # Interpolating along the polygon puts vertices at equal arc length along the *old*
    # polygon; chords of the new one cut corners, by at most a relative (turning angle)^2/8
    # ~ (2 pi * 3 / 300)^2 / 8 ~ 5e-4 here.
    assert np.ptp(lengths) / lengths.mean() < 2e-3
    assert total_length(q, True) == pytest.approx(total_length(pts, True), rel=1e-3)
    line = np.array([[0.0, 0, 0], [1.0, 0, 0], [3.0, 0, 0]])
    r = curves.resample_uniform(line, 4, closed=False)
    np.testing.assert_allclose(r[:, 0], [0, 1, 2, 3], atol=1e-12)  # straight: exact


def hairpin(gap: float, n: int = 400) -> np.ndarray:
    """Two parallel strands 10 long, ``gap`` apart, joined by a semicircle of radius gap/2."""
    a = np.linspace(0, 10, n)
    t = np.linspace(0, np.pi, 60)[1:-1]
    bend = np.stack([10 + 0.5 * gap * np.sin(t), 0.5 * gap * (1 - np.cos(t)), 0 * t], 1)
    s1 = np.stack([a, 0 * a, 0 * a], 1)
    s2 = np.stack([a[::-1], gap + 0 * a, 0 * a], 1)
    return np.vstack([s1, bend, s2])


def test_min_nonlocal_distance_hairpin():
    gap = 2.0
    pts = hairpin(gap)
    # Window for D = gap: the joining half-turn has radius gap/2 = D/2, the tightest bend,
    # whose pairs stay local (a smaller D would see the bend itself as a closer contact).
    d, sa, sb = curves.min_nonlocal_distance(pts, False, curves.exclusion_arc_length(gap))
    assert d == pytest.approx(gap, rel=1e-9)  # parallel straight strands: exact
    assert sa < 10.0 < sb


def test_scale_for_diameter_has_no_overlap():
    for closed, pts in ((True, curves.trefoil(400)), (False, curves.open_trefoil())):
        diam = 0.0085
        q = curves.scale_for_diameter(pts, diam, closed, clearance=1.1)
        d, _, _ = curves.min_nonlocal_distance(q, closed, curves.exclusion_arc_length(diam))
        assert d >= 1.1 * diam * (1 - 1e-6)
        assert bergou_curvature(q, closed).max() <= 2 / (1.1 * diam) * (1 + 1e-9)
        curves.check_no_overlap(q, diam, closed)  # does not raise


def test_check_no_overlap_says_where():
    pts = hairpin(0.5)
    with pytest.raises(ValueError, match=r"arc length S = .* and .* are 0\.5 apart"):
        curves.check_no_overlap(pts, 1.0, closed=False)


def test_exclusion_window_ignores_tight_bend():
    # A half-turn of radius D/2: the chord stays below D within the window, so it is local.
    diam = 1.0
    t = np.linspace(0, np.pi * 0.99, 100)
    arc = np.stack([0.5 * np.cos(t), 0.5 * np.sin(t), 0 * t], 1)
    d, _, _ = curves.min_nonlocal_distance(arc, False, curves.exclusion_arc_length(diam))
    assert not np.isfinite(d)


def test_resample_equal_chords_gives_equal_edges_on_the_curve() -> None:
    from tightknot.knots.curves import open_trefoil, resample_equal_chords

    raw = open_trefoil(4000, 1.0, 3.0)  # tails of 3 size units, sharp corners
    q = resample_equal_chords(raw, 150)
    e = np.linalg.norm(np.diff(q, axis=0), axis=1)
    # Equal to round-off (each step solves |a + tau u - cur| = c; measured 1.3e-15).
    assert np.ptp(e) <= 1e-12 * e.mean()
    assert np.array_equal(q[0], raw[0])
    # The last point stops short of the end by the bisection's tolerance (1e-13 of the
    # length per step; measured 2e-10 of the curve's size).
    assert np.linalg.norm(q[-1] - raw[-1]) <= 1e-8
    # Every point lies on the polygon: within round-off of one of its segments.
    a, b = raw[:-1], raw[1:]
    u = b - a
    t = np.clip(np.einsum("ijk,jk->ij", q[:, None] - a[None], u) / (u * u).sum(1), 0, 1)
    dist = np.linalg.norm(q[:, None] - (a[None] + t[..., None] * u[None]), axis=2).min(1)
    assert dist.max() <= 1e-12
    with pytest.raises(ValueError, match="at least 2"):
        resample_equal_chords(raw, 1)
