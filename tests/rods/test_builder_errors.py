"""Bad input to the rod builder and material raises ValueError naming the parameter and its
valid range, in ``add_rod`` / ``Material(...)``, i.e. before ``finalize`` and any kernel."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material

NAN, INF = math.nan, math.inf


def line(n: int = 4) -> np.ndarray:
    """n vertices 1 cm apart on the x axis [m]."""
    return np.c_[0.01 * np.arange(n), np.zeros(n), np.zeros(n)]


def zigzag(n: int = 5) -> np.ndarray:
    """n non-collinear vertices (a valid open or closed rod) [m]."""
    k = np.arange(n)
    return np.c_[0.01 * np.cos(2 * np.pi * k / n), 0.01 * np.sin(2 * np.pi * k / n), 0 * k]


def add(pts=None, diameter=1e-3, **kw) -> RodBuilder:
    b = RodBuilder()
    b.add_rod(zigzag() if pts is None else pts, diameter, **kw)
    return b


def test_valid_input_builds() -> None:
    # The error tests below vary one argument of this call, so it must itself be valid.
    b = add(material=Material(youngs_modulus=2e6, poisson_ratio=0.5), rest_length=0.05)
    b.add_rod(zigzag(6), 2e-3, Material(poisson_ratio=-0.99), closed=True, link_offset=-2)
    model = b.finalize()
    assert model.edge_count == 4 + 6 and model.joint_count == 3 + 6


@pytest.mark.parametrize("d", [0.0, -1e-3, NAN, INF, -INF])
def test_diameter_must_be_finite_positive(d: float) -> None:
    with pytest.raises(ValueError, match=r"diameter must be finite and > 0 m"):
        add(diameter=d)


def test_diameter_must_be_a_number() -> None:
    with pytest.raises(ValueError, match=r"diameter must be a number > 0 m"):
        add(diameter="thick")


@pytest.mark.parametrize("e", [0.0, -1.0, NAN, INF])
def test_youngs_modulus_must_be_finite_positive(e: float) -> None:
    with pytest.raises(ValueError, match=r"youngs_modulus must be finite and > 0 Pa"):
        Material(youngs_modulus=e)


@pytest.mark.parametrize("nu", [0.51, -1.0, -1.5, NAN, INF])
def test_poisson_ratio_range(nu: float) -> None:
    with pytest.raises(ValueError, match=r"poisson_ratio must be in \(-1, 0\.5\]"):
        Material(poisson_ratio=nu)


@pytest.mark.parametrize("nu", [0.5, 0.0, -0.999])
def test_poisson_ratio_range_ends_accepted(nu: float) -> None:
    assert Material(poisson_ratio=nu).thinning_exponent == pytest.approx(4 * nu + 1)


@pytest.mark.parametrize("rho", [-1.0, NAN, INF])
def test_density_range(rho: float) -> None:
    with pytest.raises(ValueError, match=r"density must be a finite value >= 0 kg/m\^3"):
        Material(density=rho)


def test_material_type() -> None:
    with pytest.raises(ValueError, match=r"material must be a tightknot\.rods\.Material"):
        add(material={"youngs_modulus": 1e6})


@pytest.mark.parametrize("l0", [0.0, -0.1, NAN, INF])
def test_rest_length_must_be_finite_positive(l0: float) -> None:
    with pytest.raises(ValueError, match=r"rest_length must be finite and > 0 m"):
        add(rest_length=l0)


@pytest.mark.parametrize("rest", [[0.01, 0.0, 0.01, 0.01], [0.01, NAN, 0.01, 0.01],
                                  [0.01, -0.01, 0.01, 0.01], [INF, 0.01, 0.01, 0.01]])
def test_edge_rest_lengths_must_be_finite_positive(rest: list[float]) -> None:
    with pytest.raises(ValueError, match=r"edge_rest_lengths must be finite and > 0 m"):
        add(edge_rest_lengths=np.array(rest))


@pytest.mark.parametrize("shape", [(3,), (4, 1), (5,)])
def test_edge_rest_lengths_shape(shape: tuple[int, ...]) -> None:
    # An open rod of 5 vertices has 4 edges.
    with pytest.raises(ValueError, match=r"edge_rest_lengths must have shape \(4,\)"):
        add(edge_rest_lengths=np.full(shape, 0.01))


@pytest.mark.parametrize("closed", [False, True])
@pytest.mark.parametrize("n", [0, 1, 2])
def test_fewer_than_three_vertices(n: int, closed: bool) -> None:
    with pytest.raises(ValueError, match=rf"at least 3 vertices.*got {n}"):
        add(line(n), closed=closed)


@pytest.mark.parametrize("shape", [(5, 2), (5, 4), (5, 3, 1), (15,), ()])
def test_positions_shape(shape: tuple[int, ...]) -> None:
    with pytest.raises(ValueError, match=r"positions must have shape \(N, 3\)"):
        add(np.ones(shape))


@pytest.mark.parametrize("bad", [NAN, INF, -INF])
def test_non_finite_coordinates_name_the_vertex(bad: float) -> None:
    pts = zigzag()
    pts[3, 1] = bad
    with pytest.raises(ValueError, match=r"positions must be finite; vertex 3"):
        add(pts)


def test_coincident_vertices_named() -> None:
    pts = zigzag(6)
    pts[3] = pts[2]
    with pytest.raises(ValueError, match=r"coincident vertices 2 and 3"):
        add(pts)
    # Closed: the closing edge joins the last vertex to the first.
    pts = zigzag(6)
    pts[5] = pts[0]
    with pytest.raises(ValueError, match=r"coincident vertices 5 and 0"):
        add(pts, closed=True)
    # All vertices in one point (mean edge length zero).
    with pytest.raises(ValueError, match=r"coincident vertices 0 and 1"):
        add(np.zeros((4, 3)))


def test_nearly_coincident_vertices_relative_to_the_mean_edge() -> None:
    # The threshold is 1e-6 x the mean edge (builder._COINCIDENT_FRACTION): 1e-8 of a 1 cm
    # edge is coincident, 1e-4 of it is not.
    pts = line(5)
    pts[2, 0] = pts[1, 0] + 1e-10
    with pytest.raises(ValueError, match=r"coincident vertices 1 and 2"):
        add(pts)
    pts[2, 0] = pts[1, 0] + 1e-6
    add(pts)


def test_link_offset_open_rod_and_fraction() -> None:
    with pytest.raises(ValueError, match=r"link_offset applies to closed rods only"):
        add(link_offset=1)
    with pytest.raises(ValueError, match=r"link_offset must be a whole number of turns"):
        add(closed=True, link_offset=0.5)


def test_failed_add_rod_adds_nothing() -> None:
    # The checks come before anything is stored: a builder whose only add_rod failed has
    # no rods, so finalize (the only place arrays reach Warp) refuses to run.
    b = RodBuilder()
    with pytest.raises(ValueError):
        b.add_rod(line(2), 1e-3)
    with pytest.raises(ValueError, match=r"no rods"):
        b.finalize()


@pytest.mark.parametrize("link", [INF, None, NAN])
def test_non_finite_link_offset_is_a_value_error(link) -> None:
    with pytest.raises(ValueError) as info:
        add(closed=True, link_offset=link)
    assert "link_offset" in str(info.value)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # the overflow this test is about
def test_overflowing_rest_length_is_rejected() -> None:
    b = RodBuilder()
    try:
        b.add_rod(zigzag() * 1e-150, 1e-3, rest_length=1e300)
    except ValueError:
        return
    assert np.isfinite(b.finalize().edge_rest_length).all()


def test_huge_diameter_is_a_value_error() -> None:
    b = RodBuilder()
    try:
        b.add_rod(zigzag(), 1e100)
    except ValueError:
        return
    with pytest.raises(ValueError, match="diameter"):
        b.finalize()


# -- property: arbitrary arrays either build or raise ValueError ---------------------------

FLOATS = st.floats(allow_nan=True, allow_infinity=True, width=64)


def mostly(valid: st.SearchStrategy, bad: st.SearchStrategy) -> st.SearchStrategy:
    """``valid`` about 3 times in 4, else ``bad``: every argument is often valid, so that
    the checks of the others are reached."""
    return st.one_of(valid, valid, valid, bad)


# Mostly ordinary magnitudes, with NaN, +-inf, huge and tiny values and exact zeros mixed in.
COORD = st.one_of(st.floats(-1.0, 1.0), FLOATS, st.sampled_from([0.0, 1e308, -1e308, 1e-310]))


@st.composite
def positions(draw) -> np.ndarray:
    kind = draw(st.sampled_from(["any_shape", "n_by_3", "valid_rod", "valid_rod"]))
    if kind == "valid_rod":
        # A valid rod, so that the other arguments' checks are reached too, with at most
        # one coordinate replaced by a special value.
        pts = zigzag(draw(st.integers(3, 8)))
        if draw(st.booleans()):
            pts[draw(st.integers(0, pts.shape[0] - 1)), draw(st.integers(0, 2))] = draw(COORD)
    else:
        shape = (draw(hnp.array_shapes(min_dims=0, max_dims=3, max_side=6))
                 if kind == "any_shape" else (draw(st.integers(0, 8)), 3))
        pts = draw(hnp.arrays(np.float64, shape, elements=COORD))
    if pts.ndim == 2 and pts.shape[0] >= 2 and draw(st.booleans()):
        i, j = draw(st.integers(0, pts.shape[0] - 1)), draw(st.integers(0, pts.shape[0] - 1))
        pts[i] = pts[j]  # duplicate rows: coincident vertices, adjacent or not
    return pts


@settings(max_examples=300, deadline=None)
@given(
    pts=positions(),
    # Any float, huge finite diameters (D^4 overflows above ~1e77 m) included.
    diameter=mostly(st.floats(1e-4, 1e-2), st.one_of(FLOATS, st.sampled_from([INF, NAN]))),
    closed=st.booleans(),
    rest_length=mostly(st.one_of(st.none(), st.floats(0.01, 1.0)), FLOATS),
    edge_rest=mostly(st.none(), hnp.arrays(np.float64, st.integers(0, 8), elements=FLOATS)),
    nu=mostly(st.floats(-1.0, 0.5), FLOATS),
    # Whole turns, and also fractions, NaN and infinities that must be refused cleanly.
    link=mostly(st.integers(-3, 3), FLOATS),
)
@pytest.mark.filterwarnings("ignore::RuntimeWarning")  # numpy overflow in huge coordinates
def test_random_input_builds_or_raises_value_error(
    pts, diameter, closed, rest_length, edge_rest, nu, link
) -> None:
    b = RodBuilder(twist=True)
    try:
        mat = Material(poisson_ratio=nu)
        b.add_rod(pts, diameter, mat, closed=closed, rest_length=rest_length,
                  edge_rest_lengths=edge_rest, link_offset=link)
        model = b.finalize()
    except ValueError:
        return
    # Built: what the builder promises to have checked holds.
    n = pts.shape[0]
    assert np.isfinite(model.vertex_initial_position).all()
    assert model.edge_count == (n if closed else n - 1)
    assert (model.edge_rest_length > 0).all()


def test_held_components_follow_the_load_and_refuse_bad_values() -> None:
    """A vertex held on a moving plane: its held coordinate is written at each load
    parameter; a function giving the wrong number of values, or a non-finite one, is
    refused with the vertex and components named."""
    from tightknot.rods.boundary import BoundaryConditions

    b = RodBuilder(twist=False)
    b.add_rod(line(4), 0.001)
    model = b.finalize()
    bcs = BoundaryConditions(model)
    bcs.hold_components(0, 1, (1,), lambda t: np.array([0.002 * t]))
    bcs.hold_components(0, 2, (0, 2), (0.5, 0.25))
    x = line(4)
    bcs.prescribe_positions(0.5, x)
    assert x[1, 1] == 0.001 and list(x[2, [0, 2]]) == [0.5, 0.25]
    assert bcs.fixed_mask()[model.vertex_dof[1] + 1]
    bad = BoundaryConditions(model)
    bad.hold_components(0, 1, (1, 2), lambda t: np.array([t]))
    with pytest.raises(ValueError, match=r"held components \(1, 2\) of vertex 1"):
        bad.prescribe_positions(0.5, line(4))
    worse = BoundaryConditions(model)
    worse.hold_components(0, 1, (1,), lambda t: np.array([math.nan]))
    with pytest.raises(ValueError, match="finite"):
        worse.prescribe_positions(0.5, line(4))
    with pytest.raises(ValueError, match="values must be 2 finite numbers"):
        BoundaryConditions(model).hold_components(0, 1, (1, 2), (0.0,))
