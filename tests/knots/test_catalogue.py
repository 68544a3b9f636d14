"""The built-in knots: start curves, open versions, default lengths (tightknot.knots.catalogue,
tightknot.knots.families, tightknot.knots.scenes)."""

import numpy as np
import pytest

from tightknot.knots import catalogue, curves, families, scenes
from tightknot.knots.topology import curve_knot_type, knot_type


@pytest.mark.parametrize("h,name", [(1, "3_1"), (2, "4_1"), (3, "5_2"), (4, "6_1"),
                                    (5, "7_2"), (6, "8_1")])
def test_twist_knots_are_the_named_knots(h, name):
    assert knot_type(families.twist_knot(h, 1500)) == name


def test_bad_family_parameters_are_refused():
    with pytest.raises(ValueError, match="coprime"):
        families.torus_knot(2, 4)
    with pytest.raises(ValueError, match="half_twists"):
        families.twist_knot(0)
    with pytest.raises(ValueError, match="valid: 3_1, 4_1"):
        catalogue.builtin("9_1")


@pytest.mark.parametrize("name", catalogue.KNOT_NAMES)
def test_builtin_curves_closed_and_open_have_their_type(name):
    assert knot_type(catalogue.builtin(name).curve(1500)) == name
    assert curve_knot_type(catalogue.open_curve(name, 1500), closed=False) == name


def test_the_estimated_ideal_length_errs_long():
    # The estimate's factor is the largest of the known knots': for each of them the
    # estimate is at least the known ideal L/D, so a default built on it is reachable.
    k = catalogue._estimate_factor()
    for name, value in catalogue.IDEAL_L_OVER_D.items():
        assert k * catalogue.builtin(name).crossings ** 0.75 >= value - 1e-12


@pytest.mark.parametrize("name", [k for k in catalogue.KNOT_NAMES if k not in ("3_1", "4_1")])
def test_default_scenes_start_free_of_overlap_above_the_ideal_length(name):
    closed = scenes.closed_knot(name)
    opened = scenes.open_knot(name)
    ideal, _ = catalogue.ideal_l_over_d(name)
    assert closed.rest_length / closed.diameter >= 1.05 * ideal
    for sc in (closed, opened):
        assert sc.knot_type == name and sc.start_length_ratio >= 1.0
        # The proximity tool's check: a tube of the full diameter D0 fits on the start.
        curves.check_no_overlap(sc.state.x, sc.diameter, sc.closed)
        assert curve_knot_type(sc.state.x, sc.closed) == name
    # The open knot's tails: a fifth of the rod each (the scene's tail_fraction).
    assert opened.rest_length > closed.rest_length


def test_the_trefoil_and_figure_eight_scenes_are_the_studys():
    a = scenes.closed_knot("3_1", nodes=60)
    b = scenes.closed_trefoil(nodes=60)
    assert a.name == b.name == "closed_trefoil"
    assert np.array_equal(a.state.x, b.state.x) and a.rest_length == b.rest_length
    c = scenes.open_knot("4_1", nodes=400)
    d = scenes.open_figure_eight(nodes=400)
    assert np.array_equal(c.state.x, d.state.x) and c.rest_length == d.rest_length == 0.30


def test_a_length_below_the_reach_is_refused():
    with pytest.raises(ValueError, match=r"l0_over_d0 must be >= \d+ \(the ideal 5_1 needs"):
        scenes.closed_knot("5_1", 12.0)


def test_a_closed_twist_knot_ties_and_keeps_its_type():
    from tightknot.loading.tie import tie

    # Coarse (80 vertices, edges ~0.5 D0) and a short path: the knot type is checked
    # after every load step, so a run that converges has kept it throughout.
    scene = scenes.closed_knot("5_2", nodes=80)
    res = tie(scene, tighten_steps=10, residual_tol=1e-3).run()
    assert res.converged, res.failure
    assert set(res.knot_types) == {"5_2"}
