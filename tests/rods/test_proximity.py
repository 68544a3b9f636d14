"""The independent proximity check: every non-adjacent pair, its floor, and the solver
stopping (with the pair named) when an accepted state fails it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material
from tightknot.rods.proximity import ProximityCheck, _segment_distance
from tightknot.rods.state import State
from tightknot.rods.term import EnergyTerm
from tightknot.solvers.newton import NewtonOptions, newton
from tightknot.solvers.system import RodSystem

D = 0.01
MAT = Material(1e6, 0.5, 1000.0)


def _brute(x, ev, rest, closed, hard=0.045, local=0.225):
    """The same floor, every pair of edges sharing no vertex, one by one."""
    arc1 = np.cumsum(rest)
    arc0 = arc1 - rest
    length = arc1[-1]
    best = (math.inf, -1, -1)
    for a in range(len(ev)):
        for b in range(a + 1, len(ev)):
            if set(ev[a]) & set(ev[b]):
                continue
            sep = arc0[b] - arc1[a]
            if closed:
                sep = min(sep, length - (arc1[b] - arc0[a]))
            floor = min(hard * D, local * D * math.sin(min(sep / D, math.pi / 2)))
            d = _segment_distance(x[ev[a, 0]], x[ev[a, 1]], x[ev[b, 0]], x[ev[b, 1]])
            if d / floor < best[0]:
                best = (d / floor, a, b)
    return best


def _model(points, closed=False):
    b = RodBuilder(twist=False)
    b.add_rod(points, D, MAT, closed=closed)
    return b.finalize()


def _coil(n=90, turns=4.0, radius=0.6 * D, pitch=1.05 * D):
    s = np.linspace(0.0, 2 * np.pi * turns, n)
    return np.c_[radius * np.cos(s), radius * np.sin(s), pitch * s / (2 * np.pi)]


def test_the_closest_pair_is_that_of_every_pair_one_by_one() -> None:
    # A tight coil: many pairs of neighbouring turns near each other, at all separations.
    rng = np.random.default_rng(3)
    x = _coil() + rng.normal(scale=0.02 * D, size=(90, 3))
    m = _model(x)
    got = ProximityCheck(m).check(x, m.edge_rest_length)
    ratio, a, b = _brute(x, m.edge_vertex, m.edge_rest_length, False)
    assert got.ratio == pytest.approx(ratio, rel=1e-12)
    assert got.edges == (a, b)


def _polyline(corners, per_leg=8):
    pts = [np.linspace(a, b, per_leg, endpoint=False) for a, b in zip(corners[:-1],
                                                                      corners[1:], strict=True)]
    return np.vstack(pts + [corners[-1:]])


def test_a_crossing_is_found_and_named() -> None:
    # A loop whose last leg runs through its first (distance 0), as a rod passing through
    # itself does, and its closed twin: every pair found whatever the separation.
    corners = np.array([[0, 0, 0], [4, 0, 0], [4, 2, 0], [2, 2, 0], [2, -2, 0]]) * D
    x = _polyline(corners)
    m = _model(x)
    p = ProximityCheck(m).check(x, m.edge_rest_length)
    assert p.violated and p.distance < 0.05 * D
    a, b = p.edges
    assert abs(a - b) > 1 and str(a) in p.describe(D) and str(b) in p.describe(D)


def test_a_legal_tight_bend_passes() -> None:
    # A ring of diameter D (the tightest bend a tube of diameter D allows) at 40 vertices:
    # its near pairs sit at the chord of the tightest bend, 1/0.225 times the floor.
    s = np.linspace(0.0, 2 * np.pi, 40, endpoint=False)
    x = np.c_[0.5 * D * np.cos(s), 0.5 * D * np.sin(s), np.zeros(40)]
    m = _model(x, closed=True)
    p = ProximityCheck(m).check(x, m.edge_rest_length)
    assert not p.violated and p.ratio > 2.0


class _Apart(EnergyTerm):
    """No energy, but a promise to keep rods apart: the system then checks its states."""

    name = "apart"
    keeps_apart = True

    def max_step(self, x, dx, rest):
        # A step bound that does not see the pair: steps of at most 0.02 D.
        return min(1.0, 0.02 * D / max(float(np.abs(dx).max()), 1e-300))

    def evaluate(self, x, rest, want_grad, want_hess):
        n = x.shape[0]
        return 0.0, (np.zeros((n, 3)) if want_grad else None), (
            (np.zeros(0, int), np.zeros(0, int), np.zeros(0)) if want_hess else None)


def test_a_solve_stops_when_an_accepted_state_fails_the_check() -> None:
    # Two parallel rods, pinned at their ends, the second pulled at its middle toward and
    # past the first, with no contact energy to stop it (only a bound on the step size):
    # the first accepted state closer than the floor ends the solve, the pair named.
    b = RodBuilder(twist=False)
    b.add_rod(np.c_[np.linspace(0, 5 * D, 11), np.zeros(11), np.zeros(11)], D, MAT)
    b.add_rod(np.c_[np.linspace(0, 5 * D, 11), np.full(11, 0.2 * D), np.zeros(11)], D, MAT)
    m = b.finalize()
    from tightknot.rods.boundary import BoundaryConditions

    bcs = BoundaryConditions(m)
    for rod in (0, 1):
        bcs.pin(rod, 0).pin(rod, -1)
        for v in range(11):
            bcs.fix_components(rod, v, (0, 2))
    bcs.force(1, 5, (0.0, -0.5, 0.0))
    system = RodSystem(m, State.initial(m), bcs)
    system.add_term(_Apart())
    system.set_load(1.0)
    res = newton(system, system.free_vector(), NewtonOptions(max_iterations=200)).run()
    assert res.reason == "passed_through" and not res.converged
    assert "passes through itself" in system.violation and "edges" in system.violation


def test_mirror_images_are_not_checked_but_every_other_pair_is() -> None:
    # Three straight rods through one point: rods 0 and 1 declared one body's mirror
    # images (a FEM stack's), rod 2 a real rod crossing both.
    line = np.linspace(-2.0, 2.0, 9)[:, None] * D
    zero = np.zeros_like(line)
    b = RodBuilder(twist=False)
    b.add_rod(np.c_[line, zero, zero], D, MAT)
    b.add_rod(np.c_[zero, line, zero], D, MAT)
    b.add_rod(np.c_[zero + 0.5 * D, zero + 0.5 * D, line], D, MAT)
    m = b.finalize(mirror_rod_pairs=((1, 0),))
    assert m.mirror_rod_pairs == ((0, 1),)
    x = m.vertex_initial_position
    p = ProximityCheck(m).check(x, m.edge_rest_length)
    # rods 0 and 1 meet (distance 0) and are passed over; rod 2 runs 0.5 D off both
    assert p.ratio == pytest.approx(0.5 / 0.045, rel=1e-9)
    x2 = x.copy()
    x2[m.rods[2].vertex_start:] -= [0.0, 0.5 * D, 0.0]  # now through rod 0's axis
    p2 = ProximityCheck(m).check(x2, m.edge_rest_length)
    assert p2.violated and p2.distance == 0.0
    assert {int(m.edge_rod[e]) for e in p2.edges} in ({0, 2}, {1, 2})
    # without the declaration the mirror images' meeting is a violation
    b2 = RodBuilder(twist=False)
    for r in m.rods:
        b2.add_rod(x[r.vertex_start:r.vertex_start + r.vertex_count], D, MAT)
    assert ProximityCheck(b2.finalize()).check(x, m.edge_rest_length).violated


@pytest.mark.parametrize("pairs", [((0, 0),), ((0, 3),), ((-1, 1),)])
def test_mirror_rod_pairs_must_name_two_rods(pairs) -> None:
    b = RodBuilder(twist=False)
    for k in range(3):
        b.add_rod(np.c_[np.linspace(0, 1, 5), np.full(5, k), np.zeros(5)] * D, D, MAT)
    with pytest.raises(ValueError, match="mirror_rod_pairs"):
        b.finalize(mirror_rod_pairs=pairs)
