"""Bad input to the knot scenes (issue 8): any arguments give a scene whose model and
state are finite and whose start does not intersect itself, or a ValueError naming the
parameter (before any solve)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tightknot.knots.scenes import closed_trefoil, open_trefoil
from tightknot.rods.material import Material

any_float = st.floats(allow_nan=True, allow_infinity=True)
#: Mostly plausible values, sometimes anything but the known bugs below (tiny diameters).
diameter = st.one_of(st.floats(1e-4, 0.05), st.floats(1e-12, 1e12), st.sampled_from(
    [0, -1, math.nan, math.inf, -math.inf, "8.5e-3", None, "x"]))
#: Vertex counts kept small (a scene's start costs O(N^2) distance checks); None, NaN and
#: inf are known bugs (tested below).
nodes = st.one_of(st.integers(-5, 150), st.floats(-5, 150), st.sampled_from(
    ["100", 40.5, True]))


def _check_error(err: ValueError, params: tuple[str, ...]) -> None:
    msg = str(err)
    assert msg.strip()
    assert any(p in msg for p in params), f"error names no parameter: {msg}"


def _check_scene(scene) -> None:
    m = scene.model
    assert np.isfinite(scene.state.x).all() and np.isfinite(scene.state.theta).all()
    assert np.isfinite(m.edge_rest_length).all() and (m.edge_rest_length > 0).all()
    assert scene.start_length_ratio >= 1.0 and np.isfinite(scene.start_length_ratio)
    # The start must be usable by the solver: no self-intersection (SelfIntersectionError
    # is a ValueError, but at this point it would come from deep inside the contact layer).
    scene.contact.check_no_intersection(scene.state.x)


@settings(max_examples=40)
@given(ratio=st.one_of(st.floats(5, 60), any_float, st.sampled_from(["16", None])),
       d=diameter, n=nodes, twist=st.booleans(),
       e=st.one_of(st.floats(1e3, 1e12), any_float))
def test_closed_trefoil_parameters(ratio, d, n, twist, e) -> None:
    params = ("l0_over_d0", "diameter", "nodes", "youngs_modulus", "twist")
    try:
        mat = Material(e, 0.5, 1160.0)
        scene = closed_trefoil(ratio, d, n, mat, twist=twist)
    except ValueError as err:
        _check_error(err, params)
        return
    _check_scene(scene)


@settings(max_examples=40)
@given(length=st.one_of(st.floats(0.01, 1.0), any_float, st.sampled_from([None, "0.1"])),
       d=diameter, n=nodes, tail=st.one_of(st.floats(0.0, 0.5), any_float))  # numbers only
def test_open_trefoil_parameters(length, d, n, tail) -> None:
    params = ("rest_length", "diameter", "nodes", "tail_fraction")
    try:
        scene = open_trefoil(length, d, n, tail_fraction=tail)
    except ValueError as err:
        _check_error(err, params)
        return
    _check_scene(scene)


# -- found by fuzzing, fixed: each now gives a ValueError naming the parameter ---------------
KNOWN_BUGS = [
    # (scene, arguments): the error is not a ValueError, or does not name the parameter.
    ("closed", dict(nodes=math.inf)),        # OverflowError
    ("closed", dict(nodes=math.nan)),        # ValueError "cannot convert float NaN..."
    ("closed", dict(clearance=0.0)),         # ZeroDivisionError
    ("open", dict(tail_fraction=None)),      # TypeError from the range comparison
    ("closed", dict(diameter=1e-300)),       # "points contain NaN or inf", from the curve
]


@pytest.mark.parametrize(("which", "kw"), KNOWN_BUGS,
                         ids=[f"{w}-{next(iter(k))}={next(iter(k.values()))}"
                              for w, k in KNOWN_BUGS])
def test_known_scene_argument_bugs(which: str, kw: dict) -> None:
    fn = closed_trefoil if which == "closed" else open_trefoil
    name = next(iter(kw))
    with pytest.raises(ValueError, match=name):
        fn(**kw)
