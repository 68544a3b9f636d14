"""The FEM judges the sectioned contact level: the rod model of the indent and the wrap
(tightknot.fem.rod_sectioned, N = 8, the squeeze-calibrated penalty) against the coarse FEM,
and the cross-check report at the sectioned level.

Measured against the medium mesh (docs/sectioned_level.md, ``tightknot fem crosscheck
--contact sectioned``): indent force -7.5 to -1.3 % from an approach of 0.027 D0 on
(+17.7 % at 0.012, +43.5 % at 0.003, where the patch is narrower than the shortest mode),
A/A0 within 0.3 points, L_c within 0.04; wrap line load -6.9 to -1.9 % from the third level
on (-43.6 and -15.9 % at the first two, the lightest contacts; -40.4 and -9.4 % while a
bent partner's weights summed to more than one), A/A0 within 1.9 points, L_c within 0.05. The
coarse mesh differs from the medium one by up to 5 % in force at these levels (its own
spread), inside the 10 % targets' margin used below.
"""

import pytest

pytest.importorskip("felupe")

from tightknot.fem.crosscheck import _compare, _rod_indent_like, _rod_wrap_like  # noqa: E402
from tightknot.fem.rod_sectioned import rod_indent_sectioned, rod_wrap_sectioned  # noqa: E402

#: The first Gauss circle's place along an edge (two-point Gauss-Legendre on [0, 1]).
G0 = 0.5 - 0.5 / 3.0**0.5


def test_the_sectioned_indent_meets_the_targets_past_the_smallest_approaches(
        indent_coarse: dict) -> None:
    rod = _rod_indent_like(indent_coarse, rod_indent_sectioned)
    comp = _compare(indent_coarse["steps"], rod["steps"], ("force", "force"), None,
                    width_scene="indent")
    compared = [row for row in comp["levels"] if row["approach_over_d0"] >= 0.027 - 1e-9]
    assert len(compared) >= 6
    for row in compared:
        assert row["rod_converged"]
        # the targets: force 10 %, A/A0 5 points, L_c 0.1
        assert abs(row["force_rel"]) <= 0.10, row
        assert abs(row["area_points"]) <= 0.05, row
        assert abs(row["width_fraction"]) <= 0.10, row
    # straight partners: each contact sample's weights sum to one (the bias of a bent
    # partner, docs/sectioned_level.md, is absent; measured 0.999 to 1.001, the indenters'
    # ends and the rod's slight bend)
    for step in rod["steps"][1:]:
        assert step["contact_weight_sum_mean"] == pytest.approx(1.0, abs=0.005)


def test_the_sectioned_wrap_carries_the_line_load_and_the_width(wrap_coarse: dict) -> None:
    rod = _rod_wrap_like(wrap_coarse, rod_wrap_sectioned)
    comp = _compare(wrap_coarse["steps"], rod["steps"],
                    ("force_per_length_mid_nominal", "force_per_length_mid"),
                    "kappa_d0_mid_nominal", width_scene="wrap")
    rows = comp["levels"]
    assert len(rows) >= 4
    for row in rows[1:]:
        assert row["rod_converged"]
        assert abs(row["area_points"]) <= 0.05, row
        assert abs(row["width_fraction"]) <= 0.10, row
    # the line load from the third level on (the first two light contacts are missed:
    # module docstring)
    for row in rows[2:]:
        assert abs(row["force_rel"]) <= 0.15, row  # 10 % target, 5 % the coarse mesh's own
    # the compliant level misses this line load by 15 to 31 % (docs/fem_crosscheck.md): the
    # sections carry it
    assert sum(abs(r["force_rel"]) <= 0.10 for r in rows[1:]) >= len(rows) - 2
    # the wrapped rod bends: the straight cylinder's samples lie on its concave side, where
    # the partner's weights still sum to one (they telescope over its chords; the
    # projection hats they replaced summed to 1.05 to 1.23 here)
    sums = [s["contact_weight_sum_mean"] for s in rod["steps"]]
    assert all(x == pytest.approx(1.0, abs=1e-3) for x in sums)
    # and along the contact, layer by layer against the FEM's profile, the rod read at its
    # Gauss circles (2026-12-08: L_c within 0.069, A/A0 within 2.5 points on the coarse
    # mesh; the targets; on the medium mesh the two deepest tensions miss L_c by
    # 0.12 and 0.13, docs/sectioned_level.md)
    for row in rows:
        assert row["profile_a"]["width_fraction_max"] <= 0.10, row["profile_a"]
        assert row["profile_a"]["area_points_max"] <= 0.05, row["profile_a"]
    # the rod's profile is read at its Gauss circles from the edge before the middle on:
    # the middle vertex's L_c is the largest of its two edges' four circles, its area
    # between theirs
    h = 1.0 / 12.0  # the cross-check's rod: 12 edges per D0
    for step in rod["steps"]:
        four = step["profile_a"][:4]
        assert [r["s_over_d0"] for r in four] == pytest.approx(
            [-(1.0 - G0) * h, -G0 * h, G0 * h, (1.0 - G0) * h], abs=1e-12)
        assert max(r["contact_fraction"] for r in four) == step["contact_width_fraction_mid"]
        areas = [r["area_ratio"] for r in four]
        assert min(areas) - 1e-12 <= step["area_ratio_mid"] <= max(areas) + 1e-12


def test_bad_section_modes_are_refused_before_the_fem_runs() -> None:
    from tightknot.fem.crosscheck import crosscheck

    with pytest.raises(ValueError, match="section_modes"):
        crosscheck(mesh="coarse", contact="sectioned", section_modes=3)
    with pytest.raises(ValueError, match="contact must be one of"):
        crosscheck(mesh="coarse", contact="soft")
    with pytest.raises(ValueError, match="thinning"):
        crosscheck(mesh="coarse", contact="sectioned", thinning="mean")
    with pytest.raises(ValueError, match="edges_per_d0"):
        crosscheck(mesh="coarse", contact="sectioned", rod_edges_per_d0=2)
    with pytest.raises(ValueError, match="rod_edges_per_d0"):
        crosscheck(mesh="coarse", contact="compliant", rod_edges_per_d0=24)
