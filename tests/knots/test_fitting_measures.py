"""Measurements that fit the knot: the trefoil's 3-fold measures only on trefoils, and the
ideal knot of a knot's own type placed on its s axis (tightknot.knots.ideal_overlay)."""

import json

import numpy as np
import pytest

from tightknot.knots import curves, families
from tightknot.knots.ideal import load_ideal
from tightknot.knots.ideal_overlay import aligned, ideal_report
from tightknot.knots.measure import analyze_centerline


@pytest.mark.parametrize("curve,name", [
    (curves.figure_eight(400, 0.01), "4_1"),
    (families.torus_knot(2, 5, 500, 0.01), "5_1"),
])
def test_no_threefold_measures_off_a_trefoil(curve, name):
    rep = analyze_centerline(curve, 0.004, True)
    assert rep["knot_type"] == name
    assert rep["threefold"]["applied"] is False and name in rep["threefold"]["reason"]
    for key in ("rho", "z", "X_over_D0", "Y_over_D0", "axis", "inner_segments_s",
                "outer_segments_s", "inplane_spread_ratio"):
        assert rep[key] is None, key
    # s runs from vertex 0 over L0/D0, in vertex order; curvature and contacts keep it.
    s = np.asarray(rep["s"])
    assert s[0] == 0.0 and np.all(np.diff(s) > 0)
    assert s[-1] < rep["rest_length_L0"] / 0.004
    assert rep["vertex_order"] == list(range(len(s)))
    assert len(rep["contact_s"]) == len(rep["contact_sigma"])
    json.dumps(rep, allow_nan=False)


def test_trefoil_keeps_its_threefold_measures():
    rep = analyze_centerline(curves.trefoil(400, 0.01), 0.004, True)
    assert rep["threefold"]["applied"] is True
    assert len(rep["rho"]) == len(rep["s"]) and len(rep["inner_segments_s"]) == 3


def test_ideal_is_placed_where_its_curvature_matches():
    ideal = ideal_report("4_1", 1.0)
    # The same knot with another vertex 0 and the other direction: the overlay finds the
    # placement back, so the two curvature profiles coincide.
    p = np.roll(load_ideal("4_1", 1.0), 137, axis=0)[::-1]
    rep = analyze_centerline(p, 1.0, True)
    moved = aligned(rep, ideal)
    assert moved["aligned"]["reversed"] is True and moved["aligned"]["correlation"] > 0.99
    period = rep["rest_length_L0"]
    back = np.interp(rep["s"], moved["s"], moved["kappa_D0_sorted"], period=period)
    # Within the 1/1024 grid of the correlation: the profile's steepest flanks move by
    # about 0.1 in kappa D per grid step.
    assert np.median(np.abs(back - np.asarray(rep["kappa_D0_sorted"]))) < 0.01
    assert np.max(np.abs(back - np.asarray(rep["kappa_D0_sorted"]))) < 0.15
    # A trefoil's ideal is placed by symmetry, not moved.
    tref = ideal_report("3_1", 1.0)
    assert aligned(tref, tref)["aligned"] is None
    assert ideal_report("5_2", 1.0) is None  # no ideal 5_2 shipped
