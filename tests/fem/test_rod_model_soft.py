"""The rod model's soft wrap and clasp (tightknot.fem.rod_model_soft): the contact level
is one parameter built by one helper, statics hold, the soft pair shares the overlap."""

import math

import numpy as np
import pytest

from tightknot.fem.material import ROD_DIAMETER as D0
from tightknot.fem.material import YOUNGS_MODULUS as E


def test_contact_term_levels():
    from tightknot.contact.layer import ContactLayer
    from tightknot.contact.sectioned import SectionedLayer
    from tightknot.fem.rod_model_soft import CONTACT_LEVELS, contact_term
    from tightknot.fem.rod_model_soft import check_contact as check
    from tightknot.knots.scenes import SMOOTHED_RADIUS_WINDOW
    from tightknot.rods.builder import RodBuilder

    b = RodBuilder(twist=False)
    b.add_rod(np.c_[np.linspace(0, 0.1, 11), np.zeros(11), np.zeros(11)], D0)
    model = b.finalize()
    assert CONTACT_LEVELS == ("compliant", "smoothed", "sectioned")
    compliant = contact_term(model, "compliant")
    smoothed = contact_term(model, "smoothed")
    # the knots' own levels: compliant thins by the rod's mean stretch, smoothed by a window
    assert isinstance(compliant, ContactLayer) and compliant.radius_window == 0.0
    assert compliant.settings.thinning == "rod"
    assert smoothed.radius_window == SMOOTHED_RADIUS_WINDOW
    assert isinstance(contact_term(model, "sectioned"), SectionedLayer)
    with pytest.raises(ValueError, match="contact must be one of"):
        check("soft")


@pytest.fixture(scope="module")
def soft_wrap_rod():
    from tightknot.fem.rod_model_soft import rod_soft_wrap

    tensions = [0.0069 * E * D0**2, 0.0278 * E * D0**2]
    return tensions, rod_soft_wrap(tensions)


def test_soft_wrap_statics_and_shared_overlap(soft_wrap_rod):
    # frictionless statics: the contact force on the wrapped rod is 2 T sin(theta) (1e-6:
    # the Newton tolerance); the soft pair splits the overlap evenly, so at the same
    # tension it overlaps more than a rod on a rigid cylinder (whose law is k 2^p); B is
    # held as the FEM's stack holds it: pressed from both sides, its axis straight, free
    # to stretch along it, so its pressed section thins further as the tension grows
    from tightknot.fem.rod_model import rod_wrap

    tensions, soft = soft_wrap_rod
    rigid = rod_wrap(tensions)
    for t, s, r in zip(tensions, soft["steps"], rigid["steps"], strict=True):
        assert s["converged"]
        assert s["contact_force_total"] == pytest.approx(2 * t * math.sin(math.pi / 4),
                                                         rel=1e-6)
        assert s["overlap_over_d0"] > r["overlap_over_d0"]
        assert s["area_ratio_mid"] < 1.0 and s["area_ratio_mid_b"] < 1.0
        assert s["profile_a"][0]["contact_fraction"] > 0.0
    assert soft["steps"][1]["area_ratio_mid_b"] < soft["steps"][0]["area_ratio_mid_b"]


def test_soft_wrap_reads_the_nominal_axis_as_the_fem_does(soft_wrap_rod):
    # The FEM's nominal axis is its far fibre moved in by the stretched radius. A compliant
    # section keeps its far side at that radius, so its centreline is that axis; a
    # sectioned level's far side moves with its modes, so its curvature is read on its far
    # fibre (as the rigid wrap's, rod_sectioned), the centreline's reported beside it.
    # Measured at the medium FEM's lightest two tensions: far fibre 0.13 and 0.65 of the
    # centreline's curvature, so a reading of the centreline fails the bound below.
    from tightknot.fem.rod_model_soft import rod_soft_wrap

    tensions, compliant = soft_wrap_rod
    for s in compliant["steps"]:
        assert s["kappa_d0_mid"] == s["kappa_d0_mid_centerline"] > 0.0
    sectioned = rod_soft_wrap(tensions, contact="sectioned")
    for s in sectioned["steps"]:
        assert s["converged"]
        assert 0.0 < s["kappa_d0_mid"] < 0.9 * s["kappa_d0_mid_centerline"]


def test_clasp_rod_model_is_clamped_where_the_fem_clamps():
    # the FEM scene starts its Rivlin-bent sections with their inner fibres a gap g0
    # apart, so its centrelines start 2 b' + g0 apart, not D0; the rod model's U's must
    # end at the same clamp points, or a pull of the clamps means another clasp
    # (docs/fem_nip.md, "Where the clamps are")
    from tightknot.fem.rod_model_soft import clasp_centrelines
    from tightknot.fem.scenes.clasp import inner_fibre_offset

    rho, leg, gap = 1.5 * D0, 1.5 * D0, 0.004 * D0
    curves, s = clasp_centrelines(rho, leg, D0, initial_gap=gap)
    b_inner = inner_fibre_offset(rho, 0.5 * D0)
    assert b_inner == pytest.approx(0.634 * D0, rel=1e-3)  # 3 R (1 - sqrt(1/3))
    clamp_x = b_inner + 0.5 * gap - rho - leg
    assert curves[0][0] == pytest.approx([clamp_x, -rho, 0.0], abs=1e-12)
    assert curves[0][-1] == pytest.approx([clamp_x, rho, 0.0], abs=1e-12)
    apex = curves[0][len(s) // 2]
    assert apex[0] - curves[1][len(s) // 2][0] == pytest.approx(2.0 * b_inner + gap)


def test_clasp_rod_model_is_symmetric_and_pulls():
    from tightknot.fem.rod_model_soft import clasp_centrelines, rod_clasp
    from tightknot.fem.scenes.clasp import rotate_to_b

    curves, s = clasp_centrelines(1.5 * D0, 1.5 * D0, D0)
    assert np.allclose(curves[1], rotate_to_b(curves[0]))
    assert s[len(s) // 2] == pytest.approx(0.0)  # a vertex at the apex
    res = rod_clasp([0.7 * D0, 0.9 * D0])
    assert res["relaxed"]
    a, b = res["steps"]
    assert a["converged"] and b["converged"]
    # the round sections start 0.27 D0 apart and the U's open as they relax: touching
    # from about 0.55 D0 of clamp travel, pulled harder at 0.9
    assert 0.0 < a["force"] < b["force"]
    # the two U's are images of each other under the half turn: same profiles (the
    # solver's tolerance leaves 1e-6)
    for pa, pb in zip(b["profile_a"], b["profile_b"], strict=True):
        assert pa["area_ratio"] == pytest.approx(pb["area_ratio"], rel=1e-6)


def test_soft_crossing_stack_is_symmetric_and_its_neighbours_cross_alike():
    """The soft crossing's stack (every rod pressed from both sides, each held on its
    mid-plane): the rods above A push it as hard as those below (the force measured is
    one crossing's), and rod B's crossing section thins as A's does (they differ only
    by the stack's ends, six rods away)."""
    from tightknot.fem.rod_model_soft import rod_soft_crossing, soft_crossing_scene

    system, load, edges, levels = soft_crossing_scene(D0, E, 3.0)
    assert levels == (0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5, 6, -6)
    load.hold(0.01 * D0)
    system.set_load(1.0)
    x = system.state.x
    # held on their mid-planes, the neighbours 2 w closer on each side
    assert x[system.model.rods[1].vertex_start:system.model.rods[2].vertex_start, 1] == \
        pytest.approx(0.98 * D0, abs=1e-15)
    with pytest.raises(ValueError, match="depth"):
        soft_crossing_scene(D0, E, 3.0, depth=0)
    ws = [0.006 * D0, 0.024 * D0]
    for contact in ("sectioned", "compliant"):
        res = rod_soft_crossing(ws, contact=contact)
        for row in res["steps"]:
            assert row["converged"] and row["force"] > 0.0
            assert row["force_from_below"] == pytest.approx(row["force"], rel=1e-6)
            assert row["area_ratio_mid_b"] == pytest.approx(row["area_ratio_mid"], abs=1e-3)
        # a deeper crossing presses harder
        assert res["steps"][1]["force"] > res["steps"][0]["force"]
