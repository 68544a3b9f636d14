"""The sectioned contact's partition of unity over a partner rod's edges (bisector planes,
:func:`tightknot.contact.sectioned_reference.partition`): its exact derivatives, its sum of
one over any bent polyline, the open ends' fades, the old hat along a straight partner, and
the oracle's derivatives over all local dofs on a bent partner."""

import math

import numpy as np
import pytest

from tests.contact.test_sectioned import (
    SETTINGS,
    K,
    _pack,
    _unit,
    central_differences,
)
from tightknot.contact.sectioned_reference import (
    EdgeSection,
    pair_terms,
    partition,
    partition_weight,
    quintic_step,
)


def _rotate(v: np.ndarray, axis: np.ndarray, angle: float) -> np.ndarray:
    """v turned by ``angle`` [rad] about the unit ``axis`` (Rodrigues)."""
    return (v * math.cos(angle) + np.cross(axis, v) * math.sin(angle)
            + axis * float(axis @ v) * (1.0 - math.cos(angle)))


def _polyline(n_edges: int, seed: int, closed: bool = False) -> np.ndarray:
    """Vertices (n, 3) of a 3D polyline with unequal edges: open, turning angles in
    [0.2, 0.7] rad, edge lengths in [0.85, 1.15] and its binormal turned at random
    (torsion); closed, a regular polygon (turning 2 pi / n_edges) with its vertices' angles
    jittered by 15 % of their spacing and lifted out of its plane by 0.05 edges (rms), its
    first vertex not repeated."""
    rng = np.random.default_rng(seed)
    if closed:
        phi = 2.0 * math.pi * (np.arange(n_edges) + rng.uniform(-0.075, 0.075, n_edges)) / n_edges
        radius = 1.0 / (2.0 * math.sin(math.pi / n_edges))
        return np.c_[radius * np.cos(phi), radius * np.sin(phi), 0.05 * rng.normal(size=n_edges)]
    t = np.array([1.0, 0.0, 0.0])
    binormal = np.array([0.0, 0.0, 1.0])
    pts = [np.zeros(3)]
    for _ in range(n_edges):
        pts.append(pts[-1] + rng.uniform(0.85, 1.15) * t)
        binormal = _unit(_rotate(binormal, t, rng.uniform(-0.8, 0.8)))
        t = _unit(_rotate(t, binormal, rng.uniform(0.2, 0.7)))
    return np.array(pts)


def _edge_partition(p: np.ndarray, x: np.ndarray, b: int, closed: bool
                    ) -> tuple[float, np.ndarray, np.ndarray]:
    """partition() of edge b of the polyline ``x`` at ``p``, with the rod's neighbours (ghosts
    and fades at an open rod's ends)."""
    n = len(x)
    if closed:
        return partition(p, x[(b - 1) % n], x[b], x[(b + 1) % n], x[(b + 2) % n], False, False)
    return partition(p, x[b - 1] if b > 0 else None, x[b], x[b + 1],
                     x[b + 2] if b + 2 < n else None, b == 0, b + 2 == n)


def _partition_sum(p: np.ndarray, x: np.ndarray, closed: bool) -> float:
    edges = len(x) if closed else len(x) - 1
    return sum(_edge_partition(p, x, b, closed)[0] for b in range(edges))


def _radius_of_curvature(x: np.ndarray, i: int) -> tuple[float, np.ndarray]:
    """At interior vertex i: the radius [m] of the circle through x_{i-1}, x_i, x_{i+1} and
    the unit normal towards its centre (the concave side)."""
    chord = x[i + 1] - x[i - 1]
    turn = math.acos(float(_unit(x[i] - x[i - 1]) @ _unit(x[i + 1] - x[i])))
    inward = _unit((x[i - 1] + x[i + 1]) / 2.0 - x[i])
    return float(np.linalg.norm(chord)) / (2.0 * math.sin(turn)), inward


# -- partition: exact derivatives --------------------------------------------------------

def _bent_edge() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """x_prev, x0, x1, x_next of a partner edge of length 1 bent by 0.5 and 0.4 rad at its
    vertices, out of one plane."""
    x0, x1 = np.zeros(3), np.array([1.0, 0.0, 0.0])
    x_prev = x0 - 0.9 * np.array([math.cos(0.5), -math.sin(0.5), 0.0])
    x_next = x1 + 1.2 * _unit(np.array([math.cos(0.4), math.sin(0.4) * 0.6,
                                        math.sin(0.4) * 0.8]))
    return x_prev, x0, x1, x_next


@pytest.mark.parametrize("ends", ["neighbours", "ghosts", "open"])
def test_partition_derivatives_match_finite_differences(ends: str) -> None:
    x_prev, x0, x1, x_next = _bent_edge()
    ghost = ends != "neighbours"
    first_open = last_open = ends == "open"
    # near either vertex, inside the edge and past it, on the concave (+y at x0) and
    # convex side and off the bend's plane
    points = [np.array([v, side * 0.35, 0.15 * side * side - 0.1])
              for v in (-0.35, -0.2, 0.1, 0.3, 0.7, 0.9, 1.15, 1.3) for side in (1.0, -1.0, 0.0)]
    eps = 1e-6  # edge length 1
    checked = 0
    for p in points:
        z0 = np.concatenate([p, x_prev, x0, x1, x_next])

        def at(z: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
            return partition(z[0:3], None if ghost else z[3:6], z[6:9], z[9:12],
                             None if ghost else z[12:15], first_open, last_open)

        om, g, h = at(z0)
        g_fd = np.zeros(15)
        h_fd = np.zeros((15, 15))
        for i in range(15):
            dz = np.zeros(15)
            dz[i] = eps
            hi, lo = at(z0 + dz), at(z0 - dz)
            g_fd[i] = (hi[0] - lo[0]) / (2.0 * eps)
            h_fd[:, i] = (hi[1] - lo[1]) / (2.0 * eps)
        if not 0.0 < om < 1.0:
            continue
        checked += 1
        # central differences of a C2 function with derivatives up to ~30 (the open fades'
        # doubled slopes): truncation ~eps^2, round-off ~1e-16 / eps (measured <= 2.2e-9)
        assert np.max(np.abs(g - g_fd)) < 1e-8
        assert np.max(np.abs(h - h_fd)) < 1e-8
        assert np.allclose(h, h.T, rtol=0.0, atol=1e-13)  # symmetric but for round-off
        if ghost:  # a ghost is no dof: its dependence is on x0, x1
            assert np.all(g[3:6] == 0.0) and np.all(g[12:15] == 0.0)
            assert np.all(h[3:6] == 0.0) and np.all(h[:, 12:15] == 0.0)
        else:
            assert np.linalg.norm(g[3:6]) > 1e-3 or np.linalg.norm(g[12:15]) > 1e-3
    assert checked >= 12


# -- partition: a sum of one -------------------------------------------------------------

@pytest.mark.parametrize("closed", [False, True])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_partition_sums_to_one_around_a_bent_polyline(closed: bool, seed: int) -> None:
    x = _polyline(14 if closed else 8, seed=seed, closed=closed)
    n = len(x)
    vertices = range(n) if closed else range(1, n - 1)
    radii = [_radius_of_curvature(np.roll(x, 1 - i, axis=0)[:3], 1) for i in vertices]
    turns = [math.acos(float(_unit(x[i] - x[i - 1]) @ _unit(x[(i + 1) % n] - x[i])))
             for i in vertices]
    assert 0.19 < min(turns) and max(turns) < 0.71
    lengths = np.linalg.norm(np.roll(x, -1, axis=0) - x, axis=1)[:n if closed else n - 1]
    assert lengths.max() / lengths.min() > 1.1
    # a point far from the axis is weighed over about 1 / (1 - rho kappa) edges, so the
    # curvature that bounds rho is the largest over the polyline
    kappa = 1.0 / min(r for r, _ in radii)
    rng = np.random.default_rng(seed + 10)
    worst = 0.0
    seen_two = 0
    for i in range(n) if closed else range(2, n - 2):  # the ends fade: next test
        xi = np.roll(x, 1 - i, axis=0)[:3]
        inward = _radius_of_curvature(xi, 1)[1]
        tangent = _unit(xi[2] - xi[0])
        # The edges within three of the vertex: their sum telescopes to
        # S(s_{i-3} + 1/2) - S(s_{i+4} + 1/2), both steps saturated at these distances.
        # (A sum over all a rod's edges also holds weights of its parts that curl back
        # towards the point from beyond their own centre of curvature, farther than a
        # radius of curvature: no contact is there.)
        window = ([(i + d) % n for d in range(-3, 3)] if closed
                  else [b for b in range(i - 3, i + 3) if 0 <= b < n - 1])
        for rho_kappa in (0.1, 0.4, 0.7):
            for psi in np.linspace(0.0, 2.0 * math.pi, 12, endpoint=False):
                # around the axis near vertex i: concave (psi = 0) to convex (psi = pi)
                side = math.cos(psi) * inward + math.sin(psi) * np.cross(tangent, inward)
                along = rng.uniform(-0.25, 0.25) * float(np.linalg.norm(xi[2] - xi[0]))
                p = xi[1] + along * tangent + rho_kappa / kappa * side
                weights = [_edge_partition(p, x, b, closed)[0] for b in window]
                worst = max(worst, abs(sum(weights) - 1.0))
                seen_two += sum(0.01 < w < 0.99 for w in weights) >= 2
    # the telescoping sum is one but for round-off of O(1) terms (measured 1.1e-16)
    assert worst < 1e-12
    assert seen_two > 20  # points shared between consecutive edges, not all inside one


def test_an_open_rods_partition_fades_past_its_ends() -> None:
    x = _polyline(6, seed=4)
    e0 = x[1] - x[0]
    e_last = x[-1] - x[-2]
    normal0 = _unit(np.cross(e0, [0.3, 0.5, 0.8]))
    normal1 = _unit(np.cross(e_last, [0.3, 0.5, 0.8]))
    # the sums telescope to the end's step but for round-off of O(1) terms (measured
    # 1.3e-15), hence abs=1e-12
    for v in np.linspace(-0.7, 0.45, 24):
        # v on the first edge's line: S(2 v + 1), below one only past the end
        p = x[0] + v * e0 + 0.3 * normal0
        total = _partition_sum(p, x, closed=False)
        fade = float(quintic_step(np.array(2.0 * v + 1.0))[0])
        assert total == pytest.approx(fade, abs=1e-12)
        assert (total < 1.0) if v < 0.0 else (total == pytest.approx(1.0, abs=1e-12))
        assert total > 0.0 or v <= -0.5
        # and mirrored at the last vertex: 1 - S(2 v - 2) on the last edge's line
        p = x[-2] + (1.0 - v) * e_last + 0.3 * normal1
        total = _partition_sum(p, x, closed=False)
        fade = 1.0 - float(quintic_step(np.array(2.0 * (1.0 - v) - 2.0))[0])
        assert total == pytest.approx(fade, abs=1e-12)


@pytest.mark.parametrize("given", [True, False])
@pytest.mark.parametrize("first_open,last_open", [(False, False), (True, False),
                                                  (False, True), (True, True)])
def test_on_a_straight_partner_of_equal_edges_the_partition_is_the_old_hat(
        given: bool, first_open: bool, last_open: bool) -> None:
    rng = np.random.default_rng(7)
    e = rng.normal(size=3)
    x0 = rng.normal(size=3)
    x1 = x0 + e
    normal = _unit(np.cross(e, rng.normal(size=3)))
    for v in np.linspace(-1.0, 2.0, 61):
        p = x0 + v * e + rng.uniform(0.1, 2.0) * _rotate(normal, _unit(e), rng.uniform(0, 6))
        om = partition(p, x0 - e if given else None, x0, x1, x1 + e if given else None,
                       first_open, last_open)[0]
        old = float(partition_weight(np.array(v), first_open, last_open)[0])
        # s_0 = v and s_1 = v - 1 but for round-off of O(|e|^2) dot products
        assert om == pytest.approx(old, abs=1e-13)


# -- the oracle over all local dofs on a bent partner ------------------------------------

def _bent_pair(seed: int = 1) -> tuple[EdgeSection, EdgeSection]:
    """Two short crossing edges of unit-diameter rods overlapping by about 0.05 D (as
    test_sectioned's pair, pressed closer so that samples in contact reach both vertices of
    each), each with its rod's neighbouring vertices bent off its line by 0.08 to 0.13 rad:
    b's towards a (its concave side, rho kappa about 0.6) and sideways, a's away from b and
    sideways (D = 1)."""
    rng = np.random.default_rng(seed)

    def edge(x0: np.ndarray, x1: np.ndarray, arc: tuple[float, float],
             bend_prev: np.ndarray, bend_next: np.ndarray) -> EdgeSection:
        t = _unit(x1 - x0 + 0.02 * rng.normal(size=3))
        e = x1 - x0
        return EdgeSection(x0=x0, x1=x1, t_ref=t, d1_ref=_unit(np.cross(t, rng.normal(size=3))),
                           coeffs0=0.01 * rng.normal(size=K), coeffs1=0.01 * rng.normal(size=K),
                           twist1=0.3 * rng.normal(), rest=0.97 * float(np.linalg.norm(e)),
                           r0=0.5, arc=arc, x_prev=x0 - 0.9 * e + bend_prev,
                           x_next=x1 + 1.1 * e + bend_next)

    a = edge(np.array([-0.05, 0.0, 0.0]), np.array([0.05, 0.01, 0.0]), (0.0, 0.1),
             np.array([0.0, 0.0, -0.009]), np.array([0.0, 0.012, 0.0]))
    b = edge(np.array([0.01, -0.04, 0.955]), np.array([-0.01, 0.06, 0.97]), (3.0, 3.1),
             np.array([0.0, 0.0, -0.012]), np.array([0.009, 0.0, 0.0]))
    return a, b


def test_oracle_derivatives_on_a_bent_partner_match_finite_differences() -> None:
    a, b = _bent_pair()
    q0 = _pack(a, b)
    assert q0.size == 24 + 4 * K
    ref = pair_terms(a, b, SETTINGS)
    assert ref["energy"] > 0.0 and ref["pen_a"].max() > 0.04  # a real contact
    # samples in contact in the partition's ramps, in both passes
    for pen, wt in ((ref["pen_a"], ref["weight_a"]), (ref["pen_b"], ref["weight_b"])):
        assert np.sum((pen > 0.0) & (wt > 0.0) & (wt < 0.99)) >= 3
    g_fd, h_fd = central_differences(a, b)
    g = ref["grad"]
    nb = 12 + 4 * K
    # every neighbour moves the energy through its chord (both passes, both ends)
    for j in range(4):
        assert np.linalg.norm(g_fd[nb + 3 * j:nb + 3 * j + 3]) > 1e-3 * np.max(np.abs(g_fd))
    # exact: central differences of a C2 energy leave truncation eps^2 and round-off
    # 1e-16 E / eps (measured 5.9e-10 of the largest entry)
    assert np.max(np.abs(g - g_fd)) <= 1e-7 * np.max(np.abs(g_fd))
    h = ref["hess"]
    # symmetric by construction, but for the order of sums (measured 2e-16)
    assert np.allclose(h, h.T, rtol=0.0, atol=1e-10 * np.max(np.abs(h)))
    # the positions' block, neighbours included, is exact but for the frames' second
    # derivatives by central differences (measured 4.8e-4); an omitted term of the
    # partition would be O(1) of its rows
    pos = np.r_[0:12, nb:nb + 12]
    err = (np.linalg.norm(h[np.ix_(pos, pos)] - h_fd[np.ix_(pos, pos)])
           / np.linalg.norm(h_fd[np.ix_(pos, pos)]))
    assert err < 2e-3
    # the neighbours' rows hold no frame's second derivative: exact to the differences' own
    # error (measured 3.9e-10)
    nbr = slice(nb, None)
    assert np.linalg.norm(h[nbr] - h_fd[nbr]) / np.linalg.norm(h_fd[nbr]) < 1e-7
    # the sections' rows exact too (measured 1.2e-5, the differences' own error), the whole
    # within the frames' differences (measured 4.0e-4)
    sec = slice(12, nb)
    assert np.linalg.norm(h[sec] - h_fd[sec]) / np.linalg.norm(h_fd[sec]) < 1e-4
    assert np.linalg.norm(h - h_fd) / np.linalg.norm(h_fd) < 1e-3
