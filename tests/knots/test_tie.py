"""Tying the study's trefoils: the knot type holds at every load step, and the results
have the physics of section 3 of physics.md where this coarse resolution can show it."""

import numpy as np

from tightknot.knots.scenes import closed_trefoil, open_trefoil
from tightknot.knots.tie import tie


def _length(x: np.ndarray, closed: bool) -> float:
    e = (np.roll(x, -1, axis=0) - x) if closed else np.diff(x, axis=0)
    return float(np.linalg.norm(e, axis=1).sum())


def test_closed_trefoil_ties_and_stretches() -> None:
    scene = closed_trefoil(nodes=100)
    res = tie(scene, tighten_steps=40)
    assert res.converged, res.failure
    assert set(res.knot_types) == {"3_1"}
    x = res.system.state.x
    stretch = _length(x, True) / scene.rest_length
    # The ideal trefoil is the tightest rigid tube (L/D = 16.37); at L0/D0 = 16.37 the
    # elastic rod must stretch to close (physics.md sec. 3: "a few percent"); measured
    # 7.4 % at 100 vertices. Bounds: it stretches (> 1 %) but not absurdly (< 20 %).
    assert 1.01 < stretch < 1.2
    dmin, _, _ = scene.contact.min_distance(x)
    # Sections are squeezed, not passed through: 0.874 D0 measured; the hard limit is 0.05.
    assert 0.7 * scene.diameter < dmin < scene.diameter


def test_open_trefoil_tightens_to_its_rest_length() -> None:
    # Tightening by shrinking the rest length to L0 = 185 mm with the ends following:
    # the knot type holds at every step and the knot ends tight. Pulling further (above
    # the ~3 N this leaves at the end) does not converge yet (see the issue notes), so it
    # is not asserted here.
    scene = open_trefoil(nodes=150)
    res = tie(scene, tighten_steps=40)
    assert res.converged, res.failure
    assert set(res.knot_types) == {"3_1"}
    x = res.system.state.x
    dmin, _, _ = scene.contact.min_distance(x)
    # Squeezed, never passed through (hard limit 0.05 D0): measured 0.72..0.87 D0.
    assert 0.5 * scene.diameter < dmin < scene.diameter
    from tightknot.knots.contact_map import contact_pairs
    from tightknot.knots.open_measures import open_knot_measures

    i, j = contact_pairs(x, False, np.full(len(x), scene.diameter / 2), tol=0.0)
    S = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))]
    lam = open_knot_measures(np.unique(np.r_[i, j]), S, scene.diameter)["Lambda_OC"]
    # A tight open trefoil: the ideal (rigid) one has Lambda_OC = 12.4 (Pieranski et al.
    # 2001); the compliant knot can be slightly shorter by squeezing (measured 12.6 at
    # the end of tightening); 11..15 brackets tight knots, a loose one would be longer.
    assert 11.0 < lam < 15.0
