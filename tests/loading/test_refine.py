"""Mesh continuation: a knot tied on a coarse rod and refined is the knot tied on the fine rod."""

from __future__ import annotations

import numpy as np
import pytest

from tightknot.knots.measure import analyze_centerline
from tightknot.knots.scenes import closed_trefoil, minimum_nodes, open_trefoil
from tightknot.loading.refine import carry, refinements, tie_refined
from tightknot.loading.tie import tie


def test_refinements_double_up_to_the_fine_count() -> None:
    assert refinements(100, 400) == [200, 400]
    assert refinements(300, 1682) == [533, 947, 1682]
    with pytest.raises(ValueError, match="coarse_nodes < nodes"):
        refinements(400, 400)


def test_a_carried_open_centerline_keeps_its_ends_and_has_equal_chords() -> None:
    x = open_trefoil(nodes=90).state.x
    y = carry(x, False, 301)
    assert np.array_equal(y[0], x[0]) and np.allclose(y[-1], x[-1], atol=1e-12)
    e = np.linalg.norm(np.diff(y, axis=0), axis=1)
    assert np.ptp(e) <= 1e-9 * e.mean()


def test_a_refined_closed_trefoil_is_the_one_tied_fine() -> None:
    # 100 vertices tied, then 200 and 400 solved from the carried shape: the same
    # equilibrium as tying the 400-vertex rod (stretch and L/D to the Newton tolerance's
    # effect, 1e-5; kappa D0 at most 0.01 off: the closed knot may settle a fraction of an
    # edge along itself), in fewer Newton iterations of the fine rod.
    fine = closed_trefoil(nodes=400)
    refined = tie_refined(fine, 100, tighten_steps=40).run()
    assert refined.converged, refined.failure
    assert set(refined.knot_types) == {"3_1"} and refined.system.model is fine.model
    direct = tie(closed_trefoil(nodes=400), tighten_steps=40).run()
    a = analyze_centerline(refined.system.state.x, fine.diameter, True,
                           rest_length=fine.rest_length)
    b = analyze_centerline(direct.system.state.x, fine.diameter, True,
                           rest_length=fine.rest_length)
    assert a["stretch_L_over_L0"] == pytest.approx(b["stretch_L_over_L0"], abs=1e-5)
    assert a["L_over_D"] == pytest.approx(b["L_over_D"], abs=1e-4)
    assert abs(a["kappa_D0_max"] - b["kappa_D0_max"]) <= 0.01


def test_the_coarse_stage_never_goes_below_what_the_start_allows() -> None:
    # The 185 mm start at 200 vertices is a path of about 85 D0: with contact its edges must
    # stay within pi/4 D0, so a coarse stage needs at least minimum_nodes (121) vertices. A
    # coarse count of 50 was refused by the scene ("nodes must be about >= ...", naming a
    # count the user never gave; `tie open --length 2` failed so by default); it is raised.
    fine = open_trefoil(0.185, nodes=200)
    need = minimum_nodes(fine.state.x, False, fine.diameter)
    assert 50 < need < 200
    with pytest.raises(ValueError, match="nodes must be about >="):
        fine.rebuild(50)
    res = tie_refined(fine, 50, pull_force=1.0).run()
    assert res.converged, res.failure
    assert set(res.knot_types) == {"3_1"} and res.system.model is fine.model
    assert f"refine_{fine.model.vertex_count}" in res.phases
    # where the minimum is the scene's own count there is no coarser stage
    plain = tie_refined(open_trefoil(0.185, nodes=80), 50, pull_force=1.0).run()
    assert plain.converged and not any(k.startswith("refine_") for k in plain.phases)


def test_a_failed_coarse_stage_is_reported_on_the_scenes_own_rod() -> None:
    # A coarse stage that fails (here its relaxation, held to 3 Newton iterations) returns
    # the scene's rod (its last equilibrium carried, not solved), so that a run saves and
    # measures that rod and says which stage failed.
    fine = open_trefoil(0.185, nodes=200)
    res = tie_refined(fine, 121, pull_force=1.0, relax_iterations=3).run()
    assert not res.converged
    assert res.failure.startswith("at 121 vertices (mesh continuation): relax")
    assert "raise relax_iterations, 3 now" in res.failure  # what to do about it
    assert res.system.model is fine.model
    assert res.system.state.x.shape == (fine.model.vertex_count, 3)
    assert np.isfinite(res.system.state.x).all()
