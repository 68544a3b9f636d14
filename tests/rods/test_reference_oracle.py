"""The Warp elastic energies equal the slow NumPy oracle (tightknot.rods.reference).

Tolerance, everywhere below: relative 1e-12 per energy. Kernel and oracle evaluate the same
formulas in float64 with different operation orders (the kernel writes the stretch as
(lam-1)^2 (lam+2)/lam and |kb|^2 as 4 |e0 x e1|^2/S^2, takes the twist as theta difference
plus reference twist, and reads the model's stiffness arrays; the oracle uses the literal
formulas, the material frames and the rod's Material). Each per-edge or per-joint term then
carries a few 1e-16 of relative rounding, and sums of positive terms keep that bound; the
worst conditioned step is the oracle's lam^2 + 2/lam - 3 ~ 3 eps^2, whose relative error is
~1e-16/eps^2, kept below 1e-13 by giving every edge a strain |eps| >= 0.05. A twist that
differs by whole turns, a wrong stiffness factor or a wrong edge in a stencil shows up as an
O(1) relative difference.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tightknot.rods.builder import RodBuilder
from tightknot.rods.elastic import ElasticForces
from tightknot.rods.material import Material
from tightknot.rods.model import Model
from tightknot.rods.reference import reference_energies
from tightknot.rods.state import State

REL = 1e-12  # see the module docstring


def wavy_curve(rng: np.random.Generator, n: int, closed: bool, scale: float = 0.01) -> np.ndarray:
    """A non-straight, non-planar polygon of ``n`` vertices, edges ~``scale`` [m]."""
    s = np.linspace(0.0, 2.0 * np.pi, n, endpoint=not closed)
    radius = n * scale / (2.0 * np.pi)
    base = np.c_[np.cos(s), np.sin(s), 0.4 * np.sin(2.0 * s)] * radius
    return base + 0.15 * scale * rng.standard_normal((n, 3))


def strain_factors(rng: np.random.Generator, count: int) -> np.ndarray:
    """Rest-length factors 1/lam with |lam - 1| in [0.05, 0.3] (see the module docstring)."""
    lam = 1.0 + rng.choice([-1.0, 1.0], count) * rng.uniform(0.05, 0.3, count)
    return 1.0 / lam


def assert_energies_match(model: Model, x, theta, d1, m_ref, rest) -> dict[str, float]:
    """Kernel energies equal the oracle's within REL; returns the oracle's."""
    e, _ = ElasticForces(model).evaluate(x, theta, m_ref, rest, want_grad=False)
    ref = reference_energies(model, x, theta, d1, rest)
    got = dict(stretch=e.stretch, bend=e.bend, twist=e.twist)
    for k in ("stretch", "bend", "twist"):
        assert got[k] == pytest.approx(ref[k], rel=REL, abs=0.0), (k, got[k], ref[k])
    return ref


CASES = [
    # (closed, twist, nu, link_offset)
    (False, True, 0.5, 0),
    (False, True, 0.0, 0),
    (False, False, 0.3, 0),
    (True, True, 0.3, 0),
    (True, True, 0.5, 2),
    (True, True, 0.0, -1),
    (True, False, 0.5, 0),
]


@pytest.mark.parametrize("closed, twist, nu, link", CASES)
def test_single_rod_matches_oracle(closed: bool, twist: bool, nu: float, link: int) -> None:
    rng = np.random.default_rng(hash((closed, twist, nu, link)) % 2**32)
    n = 9
    pts = wavy_curve(rng, n, closed)
    b = RodBuilder(twist=twist)
    ne = n if closed else n - 1
    lengths = np.linalg.norm(np.diff(np.vstack([pts, pts[:1]]) if closed else pts, axis=0), axis=1)
    b.add_rod(pts, 2e-3, Material(poisson_ratio=nu), closed=closed,
              edge_rest_lengths=lengths * strain_factors(rng, ne), link_offset=link)
    model = b.finalize()
    st = State.initial(model)
    theta = rng.uniform(-np.pi, np.pi, model.edge_count)
    ref = assert_energies_match(model, st.x, theta, st.d1_ref, st.m_ref, model.edge_rest_length)
    # Every energy the model has must be exercised, or the comparison proves nothing.
    assert ref["stretch"] > 0 and ref["bend"] > 0
    assert (ref["twist"] > 0) == twist
    # A rest-length override at evaluation time (load continuation) is used by both.
    rest2 = model.edge_rest_length * strain_factors(rng, ne)
    assert_energies_match(model, st.x, theta, st.d1_ref, st.m_ref, rest2)


def test_several_rods_in_one_model() -> None:
    rng = np.random.default_rng(7)
    b = RodBuilder(twist=True)
    specs = [
        (8, False, 0.5, 1e-3, 0),
        (7, True, 0.3, 2e-3, 1),
        (6, False, 0.0, 3e-3, 0),
        (10, True, 0.45, 1.5e-3, -2),
    ]
    for n, closed, nu, d0, link in specs:
        pts = wavy_curve(rng, n, closed) + rng.uniform(-0.1, 0.1, 3)
        mat = Material(youngs_modulus=rng.uniform(1e5, 1e7), poisson_ratio=nu)
        b.add_rod(pts, d0, mat, closed=closed, rest_length=None, link_offset=link)
    model = b.finalize()
    st = State.initial(model)
    theta = rng.uniform(-np.pi, np.pi, model.edge_count)
    rest = model.edge_rest_length * strain_factors(rng, model.edge_count)
    assert_energies_match(model, st.x, theta, st.d1_ref, st.m_ref, rest)


@pytest.mark.parametrize("closed, twist, nu, link", CASES)
def test_after_moving_and_transporting_frames(
    closed: bool, twist: bool, nu: float, link: int
) -> None:
    """Positions move in 12 steps (random wiggles plus a rigid rotation by 1.2 rad); each
    step carries the frames from the previous one by time-parallel transport, as a solver
    does. The oracle sees only the transported d1; the kernels see the tracked m_ref."""
    rng = np.random.default_rng(1000 + hash((closed, twist, nu, link)) % 2**20)
    n = 8
    b = RodBuilder(twist=twist)
    b.add_rod(wavy_curve(rng, n, closed), 2e-3, Material(poisson_ratio=nu), closed=closed,
              link_offset=link)
    model = b.finalize()
    forces = ElasticForces(model)
    st = State.initial(model)
    rest = model.edge_rest_length * strain_factors(rng, model.edge_count)
    theta = rng.uniform(-np.pi, np.pi, model.edge_count)
    axis = rng.standard_normal(3)
    axis /= np.linalg.norm(axis)
    kx = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    step_rot = np.eye(3) + math.sin(0.1) * kx + (1 - math.cos(0.1)) * kx @ kx
    x, d1, t, m_ref = st.x, st.d1_ref, st.t_ref, st.m_ref
    for _ in range(12):
        x = x @ step_rot.T + 1e-3 * rng.standard_normal(x.shape)
        d1, t, m_ref = forces.transport_frames(x, d1, t, m_ref)
        ref = assert_energies_match(model, x, theta, d1, m_ref, rest)
        assert ref["bend"] > 0 and (ref["twist"] > 0) == twist
    if closed and twist:
        # The excess link stays at the closing joint: whole turns are never lost.
        assert abs(m_ref[0] - 2 * np.pi * link) < np.pi


def test_oracle_closed_form_polygon_and_uniform_twist() -> None:
    """The oracle itself on a case with a closed-form answer.

    Regular planar N-gon of edge l_e in the xy plane, at rest (l = l_bar): turning angle
    phi = 2 pi/N, |kb| = 2 tan(phi/2) (B08 eq. 1), so E_b = N EI0 (2 tan(pi/N))^2 / (2 l_e).
    Directors d1 = z are normal to every edge and parallel transport about z keeps them,
    so the reference twist is zero and theta_j = j tau gives m = tau at every joint but the
    closing one (m = -(N-1) tau + 2 pi k with link k): E_t = GJ0 sum m^2 / (2 l_e).
    """
    N, le, d0, k, tau = 7, 0.01, 2e-3, 1, 0.2
    mat = Material(youngs_modulus=2e6, poisson_ratio=0.4)
    r = le / (2.0 * math.sin(math.pi / N))
    s = 2.0 * math.pi * np.arange(N) / N
    pts = np.c_[r * np.cos(s), r * np.sin(s), np.zeros(N)]
    b = RodBuilder(twist=True)
    b.add_rod(pts, d0, mat, closed=True, link_offset=k)
    model = b.finalize()
    d1 = np.tile([0.0, 0.0, 1.0], (N, 1))
    theta = tau * np.arange(N)
    ref = reference_energies(model, pts, theta, d1)
    ei0 = mat.youngs_modulus * math.pi * d0**4 / 64.0
    gj0 = mat.shear_modulus * math.pi * d0**4 / 32.0
    # Closed forms in float64: relative 1e-13 covers the few roundings of the polygon.
    assert ref["stretch"] == pytest.approx(0.0, abs=1e-13 * ei0 / le)
    assert ref["bend"] == pytest.approx(N * ei0 * (2 * math.tan(math.pi / N)) ** 2 / (2 * le),
                                        rel=1e-13)
    m = np.full(N, tau)
    m[0] = -(N - 1) * tau + 2.0 * math.pi * k
    assert ref["twist"] == pytest.approx(gj0 * np.sum(m**2) / (2 * le), rel=1e-13)
    # ... and the kernels agree given the same reference twist (zero, plus the link).
    st = State.initial(model)
    assert_energies_match(model, pts, theta, d1, np.where(np.arange(N) == 0, 2 * np.pi * k, 0.0),
                          model.edge_rest_length)
    assert st.m_ref[0] == pytest.approx(2 * np.pi * k, abs=1e-12)  # planar: no holonomy


def test_oracle_sees_a_wrong_reference_twist() -> None:
    """The oracle is not fed m_ref: a kernel evaluated with a reference twist off by a
    small angle or by a whole turn disagrees with it."""
    rng = np.random.default_rng(3)
    b = RodBuilder(twist=True)
    b.add_rod(wavy_curve(rng, 7, True), 2e-3, closed=True, link_offset=1)
    model = b.finalize()
    st = State.initial(model)
    theta = rng.uniform(-1, 1, model.edge_count)
    ref = reference_energies(model, st.x, theta, st.d1_ref)
    for delta in (1e-3, 2 * np.pi):
        bad = st.m_ref.copy()
        bad[0] -= delta
        e, _ = ElasticForces(model).evaluate(st.x, theta, bad, model.edge_rest_length, False)
        assert abs(e.twist - ref["twist"]) > 1e3 * REL * ref["twist"]


def test_oracle_rejects_bad_directors() -> None:
    b = RodBuilder()
    b.add_rod(wavy_curve(np.random.default_rng(0), 5, False), 1e-3)
    model = b.finalize()
    st = State.initial(model)
    with pytest.raises(ValueError, match="d1_ref"):
        reference_energies(model, st.x, st.theta, st.t_ref)  # tangents are not normals
    with pytest.raises(ValueError, match="x must have shape"):
        reference_energies(model, st.x[:-1], st.theta, st.d1_ref)


def test_unwrap_hint_picks_only_the_whole_turn() -> None:
    """``m_ref_hint`` = the tracked m_ref gives the default answer (the geometric reference
    twist is within (-pi, pi) of the link offset here); a hint one turn off moves the
    closing joint's twist by exactly 2 pi (whole turn from the hint, fraction from frames)."""
    rng = np.random.default_rng(11)
    b = RodBuilder(twist=True)
    b.add_rod(wavy_curve(rng, 6, True), 2e-3, closed=True, link_offset=0)
    model = b.finalize()
    st = State.initial(model)
    theta = rng.uniform(-1, 1, model.edge_count)
    default = reference_energies(model, st.x, theta, st.d1_ref)
    tracked = reference_energies(model, st.x, theta, st.d1_ref, m_ref_hint=st.m_ref)
    assert tracked == default  # same turn chosen, same arithmetic: bitwise equal
    shifted = reference_energies(model, st.x, theta, st.d1_ref,
                                 m_ref_hint=st.m_ref + 2 * np.pi * (np.arange(6) == 0))
    e, _ = ElasticForces(model).evaluate(st.x, theta, st.m_ref + 2 * np.pi * (np.arange(6) == 0),
                                         model.edge_rest_length, False)
    assert shifted["twist"] == pytest.approx(e.twist, rel=REL)
    assert shifted["twist"] > 2 * default["twist"]
