"""Bad input to the rod builder (issue 8): any arguments give a model whose numbers are
finite and whose stiffnesses are positive, or a ValueError naming the parameter; never an
error from deep inside (IndexError, ZeroDivisionError, FloatingPointError, Warp errors)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material

PARAMS = ("positions", "diameter", "material", "rest_length", "edge_rest_lengths",
          "link_offset", "youngs_modulus", "poisson_ratio", "density", "rods")

#: Any float, the awkward ones included (NaN, inf, subnormal, huge).
any_float = st.floats(allow_nan=True, allow_infinity=True, allow_subnormal=True)
#: Plausible sizes with occasional extremes (most examples should reach finalize).
size = st.one_of(st.floats(1e-4, 1.0), any_float, st.integers(-3, 3),
                 st.sampled_from(["1", "a", None, [1.0]]))


def _positions():
    n = st.integers(0, 12)
    shapes = st.one_of(n.map(lambda k: (k, 3)), st.tuples(n, st.integers(0, 5)), n.map(
        lambda k: (k,)))
    elements = st.one_of(st.floats(-1.0, 1.0), any_float)
    return st.one_of(
        hnp.arrays(np.float64, shapes, elements=elements),
        hnp.arrays(np.float32, shapes, elements=st.floats(-1.0, 1.0, width=32)),
        st.lists(st.lists(st.floats(-1, 1), min_size=3, max_size=3), max_size=8),
        st.sampled_from([None, "xyz", [[1, 2, "a"]], np.zeros((4, 3), dtype=complex)]))


def _material():
    return st.one_of(st.none(), st.builds(dict, youngs_modulus=size, poisson_ratio=size,
                                          density=size), st.just("steel"))


def _check_error(err: ValueError) -> None:
    msg = str(err)
    assert msg.strip(), "empty error message"
    assert any(p in msg for p in PARAMS), f"error does not name a parameter: {msg}"


def _check_model(model) -> None:
    for name in ("vertex_initial_position", "edge_rest_length", "edge_mu_area",
                 "edge_radius", "joint_bend_stiffness", "joint_twist_stiffness",
                 "vertex_mass"):
        arr = getattr(model, name)
        assert np.isfinite(arr).all(), name
    # Zero stiffness or length would make the solver's scales (EI/L^2) zero: NaN later.
    assert (model.edge_rest_length > 0).all()
    assert (model.edge_mu_area > 0).all() and (model.edge_radius > 0).all()
    assert (model.joint_bend_stiffness > 0).all()


@settings(max_examples=100)
@given(positions=_positions(), diameter=size, material=_material(), closed=st.booleans(),
       rest_length=st.one_of(st.none(), size), link_offset=st.one_of(
           st.integers(-2, 2), st.floats(-2, 2), st.sampled_from([None, "1"])),
       twist=st.booleans())
def test_add_rod_and_finalize(positions, diameter, material, closed, rest_length,
                              link_offset, twist) -> None:
    b = RodBuilder(twist=twist)
    try:
        mat = Material(**material) if isinstance(material, dict) else material
        b.add_rod(positions, diameter, mat, closed=closed, rest_length=rest_length,
                  link_offset=link_offset)
        model = b.finalize()
    except ValueError as err:
        _check_error(err)
        return
    _check_model(model)


@given(n=st.integers(3, 10), scale=st.floats(1e-12, 1e12), diameter=st.floats(1e-12, 1e6),
       e=st.floats(1e-6, 1e15), closed=st.booleans())
def test_extreme_but_valid_scales_give_a_usable_model(n, scale, diameter, e, closed) -> None:
    # Physically odd but legal numbers: a model with finite, positive stiffnesses, or a
    # clear refusal; nothing that would hand NaN to the solver.
    k = np.arange(n)
    pts = scale * np.c_[np.cos(2 * np.pi * k / n), np.sin(2 * np.pi * k / n), 0.1 * k]
    assume(np.isfinite(pts).all())
    b = RodBuilder()
    try:
        b.add_rod(pts, diameter, Material(e, 0.3, 1000.0), closed=closed)
        model = b.finalize()
    except ValueError as err:
        _check_error(err)
        return
    _check_model(model)


@given(rest=hnp.arrays(np.float64, st.integers(0, 8), elements=any_float))
def test_edge_rest_lengths(rest) -> None:
    pts = np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)] * 0.01
    b = RodBuilder()
    try:
        b.add_rod(pts, 1e-3, edge_rest_lengths=rest)
        model = b.finalize()
    except ValueError as err:
        _check_error(err)
        return
    _check_model(model)


def test_finalize_without_rods_names_the_call() -> None:
    try:
        RodBuilder().finalize()
    except ValueError as err:
        assert "add_rod" in str(err)
    else:
        raise AssertionError("finalize() without rods must raise")


# -- found by fuzzing: D^4 or E I underflowed to 0 and the builder accepted a rod with zero
# bending stiffness (the solver's force scale EI/L^2 was then 0, residual NaN); fixed.
@pytest.mark.parametrize(("diameter", "youngs_modulus"), [(1e-100, 1.25e6), (1e-3, 1e-320)])
def test_underflowing_stiffness_is_refused(diameter: float, youngs_modulus: float) -> None:
    pts = np.c_[np.arange(5.0), np.zeros(5), np.zeros(5)] * 0.01
    b = RodBuilder()
    try:
        b.add_rod(pts, diameter, Material(youngs_modulus, 0.5, 1000.0))
        model = b.finalize()
    except ValueError as err:
        _check_error(err)
        return
    _check_model(model)
