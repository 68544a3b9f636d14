"""Knot type by the Alexander polynomial (tightknot.knots.topology)."""

import time

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from tightknot.knots import curves
from tightknot.knots.ideal import load_ideal_trefoil
from tightknot.knots.topology import (
    alexander_at_minus1,
    alexander_polynomial,
    close_open_curve,
    knot_type,
)


def torus_knot(p: int, q: int, n: int = 600) -> np.ndarray:
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 2 + np.cos(q * t)
    return np.stack([r * np.cos(p * t), r * np.sin(p * t), -np.sin(q * t)], axis=1)


def test_unknots():
    rng = np.random.default_rng(1)
    circle = curves.circle(200)
    noisy = circle + 0.05 * rng.standard_normal(circle.shape)  # small noise: still unknotted
    for pts in (circle, noisy):
        assert alexander_polynomial(pts) == [1]
        assert alexander_at_minus1(pts) == 1
        assert knot_type(pts) == "0_1"


def test_trefoil_figure_eight_and_mirror():
    tref = curves.trefoil(400)
    assert alexander_polynomial(tref) == [1, -1, 1]
    assert alexander_at_minus1(tref) == 3
    assert knot_type(tref) == "3_1"
    mirror = tref * np.array([1.0, 1.0, -1.0])
    assert alexander_at_minus1(mirror) == 3
    assert knot_type(mirror) == "3_1"
    fig8 = curves.figure_eight(400)
    assert alexander_polynomial(fig8) == [1, -3, 1]
    assert alexander_at_minus1(fig8) == 5
    assert knot_type(fig8) == "4_1"


def test_cinquefoil_is_named():
    # The (2,5) torus knot 5_1 has Delta = t^4 - t^3 + t^2 - t + 1, determinant 5 like 4_1:
    # the polynomial, not the determinant, must separate them.
    pts = torus_knot(2, 5, 800)
    assert alexander_polynomial(pts) == [1, -1, 1, -1, 1]
    assert knot_type(pts) == "5_1"


@pytest.mark.parametrize("maker,expected", [(curves.trefoil, 3), (curves.figure_eight, 5)])
def test_invariance(maker, expected):
    pts = maker(500)
    rng = np.random.default_rng(7)
    for k in range(3):
        rot = Rotation.random(random_state=k).as_matrix()
        moved = pts @ rot.T + rng.normal(size=3)
        assert alexander_at_minus1(moved) == expected
    assert alexander_at_minus1(curves.resample_uniform(pts, 333, closed=True)) == expected
    assert alexander_at_minus1(pts[::-1]) == expected
    assert alexander_at_minus1(np.roll(pts, 123, axis=0)) == expected
    assert alexander_at_minus1(pts, seed=99) == expected


def test_ideal_trefoil():
    assert alexander_polynomial(load_ideal_trefoil()) == [1, -1, 1]


def test_open_knots_closed_far_away():
    for maker, name in ((curves.open_trefoil, "3_1"), (curves.open_figure_eight, "4_1")):
        open_pts = maker()
        # Open curve itself: the chord between the ends closes it; the closure must agree.
        assert knot_type(close_open_curve(open_pts, method="axis")) == name
        assert knot_type(close_open_curve(open_pts, method="radial")) == name
    # An open straight-tailed unknot (a U) stays unknotted.
    t = np.linspace(0, np.pi, 50)
    u = np.stack([np.cos(t), np.sin(t), 0 * t], axis=1)
    assert knot_type(close_open_curve(u, method="radial")) == "0_1"


def test_large_polygons_are_fast():
    pts = curves.trefoil(10000)
    alexander_at_minus1(pts)  # compile (numba cache) outside the timing
    t0 = time.perf_counter()
    assert alexander_at_minus1(pts) == 3
    assert alexander_polynomial(curves.figure_eight(10000)) == [1, -3, 1]
    # Sweep-line crossing search is ~N log N: well under a second for 2 x 10^4 vertices
    # (measured ~0.03 s); 2 s leaves room for slow CI machines.
    assert time.perf_counter() - t0 < 2.0
