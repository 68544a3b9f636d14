"""Profiles along the contact, FEM against the rod model (tightknot.fem.profile_compare) and
their place in the soft scenes' comparison (tightknot.fem.crosscheck_soft.compare)."""

import numpy as np
import pytest

from tightknot.fem.profile_compare import along_contact, circle_profile, spread_summary


def _profile(s, width, area=None, pressure=None):
    n = len(s)
    area = [1.0] * n if area is None else area
    pressure = [0.0] * n if pressure is None else pressure
    return [{"s_over_d0": a, "contact_fraction": w, "area_ratio": b,
             "peak_pressure_over_e": p} for a, w, b, p in zip(s, width, area, pressure,
                                                              strict=True)]


def test_the_same_profile_differs_nowhere_and_no_contact_is_none():
    fem = _profile([0.0, 0.1, 0.2], [0.3, 0.1, 0.0], [0.9, 0.95, 1.0])
    out = along_contact(fem, fem)
    assert out["layers"] == 2  # the unloaded layer is not along the contact
    assert out["width_fraction_max"] == 0.0 and out["area_points_max"] == 0.0
    assert out["contact_end_reference_over_d0"] == out["contact_end_other_over_d0"] == 0.1
    assert along_contact(_profile([0.0, 0.1], [0.0, 0.0]), _profile([0.0, 0.1], [0.0, 0.0])) \
        is None


def test_the_other_profile_is_read_at_the_reference_layers_by_linear_interpolation():
    # the rod's vertices at 0.05 D0, the FEM's layers at 0.1 D0 and one between vertices
    rod = _profile([0.0, 0.05, 0.1, 0.15, 0.2], [0.4, 0.3, 0.2, 0.1, 0.0],
                   [0.80, 0.85, 0.90, 0.95, 1.0])
    fem = _profile([0.0, 0.075, 0.2], [0.35, 0.3, 0.0], [0.8, 0.9, 1.0])
    out = along_contact(fem, rod)
    # at 0.075: rod L_c 0.25 (halfway between 0.3 and 0.2), A/A0 0.875
    row = out["rows"][1]
    assert row["s_over_d0"] == 0.075
    assert row["other_contact_fraction"] == pytest.approx(0.25)
    assert row["width_fraction"] == pytest.approx(-0.05)
    assert row["area_points"] == pytest.approx(-0.025)
    assert out["width_fraction_max"] == pytest.approx(0.05)
    assert out["width_fraction_signed"] == pytest.approx(0.05)  # at s = 0: 0.4 - 0.35
    assert out["width_fraction_at_s_over_d0"] == 0.0
    assert out["area_points_max"] == pytest.approx(0.025)
    assert out["area_points_signed"] == pytest.approx(-0.025)
    assert out["layers"] == 2  # neither side is loaded at 0.2
    assert out["other_width_fraction_peak"] == pytest.approx(0.4)
    assert out["reference_area_ratio_min"] == pytest.approx(0.8)


def test_a_contact_one_side_spreads_further_counts_where_it_adds_layers():
    fem = _profile([0.0, 0.1, 0.2, 0.3], [0.3, 0.2, 0.0, 0.0])
    rod = _profile([0.0, 0.1, 0.2, 0.3], [0.3, 0.2, 0.15, 0.0])
    out = along_contact(fem, rod)
    assert out["layers"] == 3
    assert out["width_fraction_max"] == pytest.approx(0.15)
    assert out["width_fraction_at_s_over_d0"] == 0.2
    assert out["contact_end_reference_over_d0"] == 0.1
    assert out["contact_end_other_over_d0"] == 0.2
    # and the other way round: the FEM's contact the rod model does not reach
    back = along_contact(rod, fem)
    assert back["width_fraction_signed"] == pytest.approx(-0.15)


def test_reference_layers_beyond_the_other_profile_are_not_compared():
    fem = _profile([0.0, 0.1, 0.2, 0.5], [0.3, 0.2, 0.1, 0.4])
    rod = _profile([0.0, 0.1, 0.2], [0.3, 0.2, 0.1])
    out = along_contact(fem, rod)
    assert out["layers"] == 3 and out["width_fraction_max"] == 0.0
    assert spread_summary(out) == {"width_fraction_max": 0.0, "area_points_max": 0.0}
    assert spread_summary(None) is None


def test_the_soft_comparison_judges_the_profiles_along_the_contact():
    pytest.importorskip("felupe")
    from tightknot.fem.crosscheck_soft import compare
    from tightknot.fem.crosscheck_targets import TARGETS

    def step(width_tail, area_tail, rod=False, force=2.0):
        s = [0.0, 0.1, 0.2, 0.3]
        out = {"pull_over_d0": 0.6, "approach_over_d0": 0.1, "force": force,
               "area_ratio_apex": 0.9, "kappa_d0_apex": 0.5, "peak_pressure_over_e": 0.2,
               "profile_a": _profile(s, [0.3, 0.2, width_tail, 0.0],
                                     [0.9, 0.95, area_tail, 1.0]),
               # rod B of the clasp is A's image: not compared
               "profile_b": _profile(s, [0.9, 0.9, 0.9, 0.9])}
        return {**out, "converged": True} if rod else out

    fem, coarse = step(0.1, 0.97), step(0.12, 0.96)
    good = compare("clasp", [fem], [step(0.15, 0.99, rod=True)], [coarse])
    row = good["levels"][0]
    assert row["profile_a"]["width_fraction_max"] == pytest.approx(0.05)
    assert row["profile_a"]["area_points_max"] == pytest.approx(0.02)
    assert row["profile_a"]["fem_spread"] == {"width_fraction_max": pytest.approx(0.02),
                                              "area_points_max": pytest.approx(0.01)}
    assert "profile_b" not in row
    assert row["met"]["width_profile_a"] and row["met"]["area_profile_a"]
    assert good["worst"]["width_profile"] == pytest.approx(0.05)
    assert good["passed"]
    # the mid-section (apex) values agree, the contact's tail misses: the level fails
    wide = 0.1 + TARGETS["width_fraction"] + 0.01
    bad = compare("clasp", [fem], [step(wide, 0.97 + TARGETS["area_points"] + 0.01,
                                         rod=True)], None)
    row = bad["levels"][0]
    assert row["met"]["force"] and row["met"]["area"]
    assert not row["met"]["width_profile_a"] and not row["met"]["area_profile_a"]
    assert row["profile_a"]["fem_spread"] is None
    assert not bad["passed"]
    assert bad["worst"]["area_profile_points"] == pytest.approx(TARGETS["area_points"] + 0.01)


def _circles():
    # three edges 0-1, 2-1 (stored the other way round) and 2-3, two circles each, the
    # values naming edge and circle (10 e + g)
    width = np.array([[0.0, 1.0], [10.0, 11.0], [20.0, 21.0]])
    return {"circle_contact_width_fraction": width,
            "circle_peak_pressure_over_E": width + 100.0,
            "edge_area_ratio": np.array([0.9, 0.8, 0.7]),
            "circle_u": np.array([0.25, 0.75]),
            "edge_vertex": np.array([[0, 1], [2, 1], [2, 3]])}


def test_a_circle_profile_reads_each_circle_at_its_own_place_in_the_vertices_order():
    rows = circle_profile(_circles(), np.array([0, 1, 2, 3]), np.array([0.0, 1.0, 2.0, 3.0]),
                          2.0)
    assert [r["s_over_d0"] for r in rows] == pytest.approx(
        [0.125, 0.375, 0.625, 0.875, 1.125, 1.375])
    # the edge stored from 2 to 1 gives its second circle (nearer vertex 1) first
    assert [r["contact_fraction"] for r in rows] == [0.0, 1.0, 11.0, 10.0, 20.0, 21.0]
    assert [r["peak_pressure_over_e"] for r in rows] == [100.0, 101.0, 111.0, 110.0, 120.0,
                                                         121.0]
    assert [r["area_ratio"] for r in rows] == [0.9, 0.9, 0.8, 0.8, 0.7, 0.7]
    # read backwards, the same circles at the same places
    back = circle_profile(_circles(), np.array([3, 2, 1, 0]), np.array([3.0, 2.0, 1.0, 0.0]),
                          2.0)
    assert sorted((r["s_over_d0"], r["contact_fraction"]) for r in back) == sorted(
        (r["s_over_d0"], r["contact_fraction"]) for r in rows)


def test_a_circle_profile_refuses_vertices_that_share_no_edge():
    with pytest.raises(ValueError, match="share no edge"):
        circle_profile(_circles(), np.array([0, 2]), np.array([0.0, 1.0]), 1.0)
