"""Knot names from the Alexander polynomial (tightknot.knots.knot_table)."""

import numpy as np
import pytest

from tightknot.knots import curves
from tightknot.knots.families import torus_knot
from tightknot.knots.knot_table import (
    ALEXANDER_TABLE,
    PRIME_ALEXANDER,
    candidates,
    crossings,
    determinant,
    knot_name,
)
from tightknot.knots.topology import alexander_polynomial, close_open_curve, knot_type


def test_table_entries_are_knot_polynomials():
    # Every Alexander polynomial of a knot is palindromic and has Delta(1) = +-1
    # (Rolfsen, Knots and Links, 1976, ch. 8): a mistyped coefficient breaks one of them.
    for name, poly in ALEXANDER_TABLE.items():
        assert poly == poly[::-1], name
        assert abs(sum(poly)) == 1, name
        assert poly[0] > 0 and poly[-1] > 0, name
        assert determinant(poly) % 2 == 1, name  # a knot's determinant is odd


def test_prime_table_is_complete_through_eight_crossings():
    # 1 + 1 + 2 + 3 + 7 + 21 prime knots of 3..8 crossings (Rolfsen's table).
    counts = {c: sum(crossings(k) == c for k in PRIME_ALEXANDER) for c in range(3, 9)}
    assert counts == {3: 1, 4: 1, 5: 2, 6: 3, 7: 7, 8: 21}


def test_ambiguous_polynomials_list_every_candidate():
    # Delta(8_20) = Delta(3_1)^2 and Delta(8_21) = Delta(3_1) Delta(4_1) (KnotInfo): the
    # only coincidences through 8 crossings, primes and sums together.
    shared = {names for names in map(candidates, set(ALEXANDER_TABLE.values()))
              if len(names) > 1}
    assert shared == {("8_20", "3_1#3_1"), ("8_21", "3_1#4_1")}
    assert knot_name([1, -2, 3, -2, 1]) == "8_20|3_1#3_1"
    assert knot_name([1, -1, 0, 1, -1, 1, 0, -1, 1]) == "unknown(det=1)"  # T(3,5), 10_124


@pytest.mark.parametrize("p,q,name", [(2, 3, "3_1"), (2, 5, "5_1"), (2, 7, "7_1"),
                                      (3, 4, "8_19")])
def test_torus_knots_are_named(p, q, name):
    pts = torus_knot(p, q, 1200)
    assert knot_type(pts) == name
    assert knot_type(pts * np.array([1.0, 1.0, -1.0])) == name  # the mirror image too


def test_figure_eight_is_named():
    assert knot_type(curves.figure_eight(400)) == "4_1"


def test_granny_knot_reads_both_candidates():
    # Two overhand knots one after the other on one rod, closed far away: 3_1#3_1, whose
    # polynomial is 8_20's.
    a = curves.open_trefoil(600, tail=2.0)
    b = a - a[0] + a[-1] + (a[-1] - a[0]) * 0.05
    pts = close_open_curve(np.vstack([a, b]))
    assert alexander_polynomial(pts) == [1, -2, 3, -2, 1]
    assert knot_type(pts) == "8_20|3_1#3_1"
