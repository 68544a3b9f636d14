"""Mesh continuation: a knot tied on a coarse rod and refined is the knot tied on the fine rod."""

from __future__ import annotations

import numpy as np
import pytest

from tightknot.knots.measure import analyze_centerline
from tightknot.knots.scenes import closed_trefoil, open_trefoil
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
