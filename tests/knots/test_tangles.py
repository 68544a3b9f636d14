"""Two-rod tangles: the linking number against closed-form links, the start curves'
invariants, and the scene's refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tightknot.knots import tangles


def torus_pair(k: int, n: int = 300, big: float = 3.0, small: float = 1.0):
    """Two parallel (1, k) curves on one torus, half a meridian turn apart: each an
    unknot, their linking number is 1 * k (parallel torus curves (p, q) link p q times;
    Rolfsen, Knots and Links, 1976, sec. 5.D)."""
    t = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    out = []
    for phase in (0.0, math.pi):
        r = big + small * np.cos(k * t + phase)
        out.append(np.c_[r * np.cos(t), r * np.sin(t), small * np.sin(k * t + phase)])
    return out


@pytest.mark.parametrize("k", [0, 1, 2, 3, 5])
def test_linking_number_of_torus_curves(k):
    a, b = torus_pair(k)
    assert abs(tangles.linking_number(a, b)) == k
    # Reversing one component's orientation flips the sign, a mirror image too.
    assert tangles.linking_number(a, b[::-1]) == -tangles.linking_number(a, b)
    mirror = np.array([1.0, 1.0, -1.0])
    assert tangles.linking_number(a * mirror, b * mirror) == -tangles.linking_number(a, b)


def test_linking_number_of_separated_circles_is_zero():
    t = np.linspace(0.0, 2.0 * math.pi, 60, endpoint=False)
    c = np.c_[np.cos(t), np.sin(t), 0 * t]
    assert tangles.linking_number(c, c + [5.0, 0.0, 0.0]) == 0


@pytest.mark.parametrize("kind", ["clasp", *tangles.BENDS])
def test_start_curves_have_their_invariants(kind):
    a, b = tangles.tangle_curves(kind)
    tt = tangles.tangle_type([a, b], [[-1, 0, 0], [1, 0, 0]], tangles.working_ends(kind))
    lk, comp, closure = tangles.EXPECTED[kind]
    assert abs(tt.linking_number) == lk
    assert tt.component_types == (comp, comp)
    if closure is not None:
        assert tt.closure_type == closure
    assert tt.matches(kind)
    # The tails lie in the z = 0 plane on the x axis lines: the ends point along x.
    assert a[0, 0] < 0 and a[-1, 0] < 0 and b[0, 0] > 0 and b[-1, 0] > 0
    gap = tangles.rod_overlaps([a, b], [0.5, 0.5])[0]
    assert gap > 0.0  # the two tubes of diameter 1 are apart at the start


def test_invariants_separate_the_tangles_they_can():
    types = {k: tangles.tangle_type(list(tangles.tangle_curves(k)), [[-1, 0, 0], [1, 0, 0]],
                                    tangles.working_ends(k)) for k in ("clasp", *tangles.BENDS)}
    # Linking number: clasp 1, reef/thief 0, granny/grief 3 (pretzel links P(n1, n2)).
    assert abs(types["reef"].linking_number) != abs(types["granny"].linking_number)
    assert abs(types["clasp"].linking_number) == 1
    # The labelled closure separates the thief from the reef, the grief from the granny.
    assert types["thief"].closure_type != types["reef"].closure_type
    assert types["grief"].closure_type != types["granny"].closure_type
    # What the tangle's own invariants leave: the kinds that share its linking number.
    for kind, cands in tangles.CANDIDATES.items():
        lks = {abs(types[c].linking_number) for c in cands}
        assert lks == {abs(types[kind].linking_number)}


def test_unknown_kind_is_refused():
    with pytest.raises(ValueError, match="tangle kind must be"):
        tangles.tangle_curves("bowline")


def test_rods_overlapping_at_the_start_name_the_pair():
    from tightknot.knots.tangle_scenes import tangle_scene

    # Legs half a diameter apart: the two tubes overlap.
    with pytest.raises(ValueError, match="rods A and B overlap at the start"):
        tangle_scene("clasp", nodes=60, geometry=tangles.TangleGeometry(helix_radius=0.3))


def test_scene_refuses_bad_parameters():
    from tightknot.knots.tangle_scenes import tangle_scene

    with pytest.raises(ValueError, match="nodes must be"):
        tangle_scene("clasp", nodes=10)
    with pytest.raises(ValueError, match="kind must be"):
        tangle_scene("bowline")
    with pytest.raises(ValueError, match="contact='off'"):
        tangle_scene("clasp", nodes=60, contact="off")
    # The reef's rods are ~39 D0 long: 40 vertices give edges of 1 D0, above pi/4 D0.
    with pytest.raises(ValueError, match="rod A: nodes=40 gives edges"):
        tangle_scene("reef", nodes=40)


def test_start_curves_of_another_type_are_refused():
    from tightknot.knots.tangle_scenes import tangle_scene

    # The reef's curves given as a clasp.
    with pytest.raises(ValueError, match="the start curves are not a clasp"):
        tangle_scene("clasp", nodes=100, curves_d0=tangles.tangle_curves("reef"))
