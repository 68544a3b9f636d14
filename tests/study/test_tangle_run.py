"""A pulled tangle's summary: per-rod measurements, and the clasp's contact turning
orthogonal as it tightens (Grandgeorge et al., PNAS 118 (2021) e2021684118: two filaments
in tight contact cross at right angles)."""

from __future__ import annotations

import pytest

from tightknot.knots.tangle_scenes import tangle_scene
from tightknot.study.tangle_run import run_tangle


@pytest.fixture(scope="module")
def clasps():
    return {f: run_tangle(tangle_scene("clasp", nodes=60), force=f) for f in (0.5, 10.0)}


def test_clasp_contact_turns_orthogonal(clasps):
    loose = clasps[0.5].summary["deepest_contact_between_rods"]
    tight = clasps[10.0].summary["deepest_contact_between_rods"]
    assert clasps[10.0].summary["converged"]
    # Tighter: a deeper contact at a larger crossing angle, near 90 deg at 10 N (2.3 EI/D0^2;
    # 86.7 deg at 20 N with 2 x 100 vertices, docs/tangles.md).
    assert tight["w_over_D0"] > loose["w_over_D0"]
    assert tight["crossing_angle_deg"] > loose["crossing_angle_deg"]
    assert tight["crossing_angle_deg"] > 80.0


def test_summary_covers_each_rod(clasps):
    s = clasps[10.0].summary
    assert [r["rod"] for r in s["rods"]] == ["A", "B"]
    for rod in s["rods"]:
        # Identical rods in a clasp symmetric but for the grips (A's clamped, B's ends
        # dead-loaded: its grip's neighbour vertex slides along x): nearly the same stretch
        # between the grips. The sections thin with each rod's mean stretch, grips included,
        # and A's clamped grips do not stretch: its sections are a little thicker (measured
        # 1.1e-5 apart at 10 N; 3.4e-6 with each edge's own stretch thinning it).
        assert rod["stretch"] == pytest.approx(s["rods"][0]["stretch"], rel=3e-5)
        assert rod["max_kappa_D0"] > 0.5  # a tight U-turn
        assert rod["contact_with_other_rod"]["vertices"] > 0
    assert s["tangle_type"]["kept"]
    assert s["force_extension"]["phase"][0] == "relax"
    assert s["force_extension"]["phase"][-1] == "force"
