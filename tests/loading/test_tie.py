"""Tying the study's trefoils: the knot type holds at every load step, and the results
have the physics of section 3 of physics.md where this coarse resolution can show it."""

import numpy as np
import pytest

from tightknot.knots.open_measures import lambda_oc
from tightknot.knots.scenes import closed_trefoil, open_trefoil
from tightknot.loading.tie import end_reaction, tie


def _length(x: np.ndarray, closed: bool) -> float:
    e = (np.roll(x, -1, axis=0) - x) if closed else np.diff(x, axis=0)
    return float(np.linalg.norm(e, axis=1).sum())


def test_closed_trefoil_ties_and_stretches() -> None:
    scene = closed_trefoil(nodes=100)
    res = tie(scene, tighten_steps=40).run()
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


def test_open_trefoil_tightens_and_a_harder_pull_makes_it_shorter() -> None:
    # Tighten to L0 = 185 mm (the end then carries ~3.4 N), then pull to 5 N.
    scene = open_trefoil(nodes=150)
    lams: list[float] = []
    res = tie(scene, pull_force=5.0, tighten_steps=40, pull_steps=10,
              hook=lambda phase, sys_, rec: lams.append(
                  lambda_oc(sys_.state.x, scene.diameter, tol=0.0)) if phase == "pull" else None
              ).run()
    assert res.converged, res.failure
    assert set(res.knot_types) == {"3_1"}
    x = res.system.state.x
    dmin, _, _ = scene.contact.min_distance(x)
    # Squeezed, never passed through (hard limit 0.05 D0): measured 0.715 D0 at 5 N.
    assert 0.5 * scene.diameter < dmin < scene.diameter
    # The knot length falls as the pull grows (frictionless: the loop gives up length to
    # the tails); measured 12.4 -> 11.0 over the pull. Each step's value may move by the
    # contact set's discreteness (one edge, 0.15 D0), hence the 0.2 slack.
    assert all(b <= a + 0.2 for a, b in zip(lams, lams[1:], strict=False))
    assert lams[-1] < lams[0] - 0.5
    # Tight: below the ideal open trefoil's 12.4 (Pieranski et al. 2001) is possible only
    # because the sections flatten (physics.md sec. 3); a loose knot would be far longer.
    assert 9.0 < lams[-1] < 12.4


def test_rigid_tube_keeps_its_diameter_and_the_knot_stays_ideal_length() -> None:
    # Issue 3: a rigid-tube run of the pulled open trefoil keeps the centerline distance
    # above 0.98 D0 (measured 0.9966 at 5 N), and its knot is no shorter than the ideal
    # rigid open trefoil (12.4, Pieranski 2001; measured 12.26 here: the 1 % contact
    # tolerance of the measurement and 150 vertices) while the compliant knot is (10.9).
    from tightknot.contact.law import RadialComplianceLaw
    from tightknot.contact.layer import ContactLayer
    from tightknot.study.run import run_knot

    scene = open_trefoil(nodes=150)
    scene.contact = ContactLayer(scene.model, RadialComplianceLaw.from_json().rigid_tube())
    run = run_knot(scene, pull_force=5.0, tighten_steps=40, pull_steps=10)
    assert run.result.converged, run.result.failure
    assert set(run.result.knot_types) == {"3_1"}
    assert run.summary["min_gap_over_D0"] > 0.98
    assert run.summary["lambda_oc"] is not None and run.summary["lambda_oc"] > 12.0


def test_the_study_open_knots_reach_their_target_lengths() -> None:
    # physics.md sec. 1: L0 = 185 mm pulled to Lambda_OC = 15.0 and L0 = 125 mm to 10.1;
    # the issue asks for the target within 0.2 (the search stops within 0.1). Forces
    # measured: 1.77 N and 6.08 N; the tighter knot needs the larger force.
    from tightknot.knots.open_measures import lambda_oc
    from tightknot.knots.scenes import vertex_radii
    from tightknot.loading.pull import tie_to_lambda

    forces = []
    for length, target, nodes in ((0.185, 15.0, 150), (0.125, 10.1, 100)):
        scene = open_trefoil(rest_length=length, nodes=nodes)
        res = tie_to_lambda(scene, target).run()
        assert res.converged, res.failure
        assert set(res.knot_types) == {"3_1"}
        x = res.system.state.x
        radii = vertex_radii(scene, x, res.system.rest)[1]
        assert abs(lambda_oc(x, scene.diameter, radii) - target) <= 0.2
        forces.append(res.pull_force_N)
    assert forces[1] > forces[0] > 0


@pytest.mark.parametrize("contact", ["compliant", "rigid"])
def test_a_hard_pull_keeps_the_knot_and_its_tube(contact: str) -> None:
    # The contact issue asks for 100x the force that makes the knot tight. Measured here
    # (125 mm, 90 vertices): the tightening ends at F_t = 5.2 N compliant, 12 N rigid; 100 F_t
    # is 7 to 17 times EA/3, a stretch of 5 to 20 where the neo-Hookean rod's section thins
    # below 0.5 D0 and edges grow to a diameter (the rigid run stalled at 137 N, stretch 5.4,
    # gap 0.94 D0: Gauss points too far apart to guard the tube). So the check is made at
    # 3 F_t (stretch 1.34 compliant, 1.8 rigid): the knot keeps its type at every step, the
    # compliant tube (with the local-thickness barrier, which stops the fold that jammed
    # this pull at 2 F_t) keeps its strands at least 0.3 D0 apart (measured min 0.36 D0),
    # the rigid one above 0.98 D0 (measured 0.9898).
    from tightknot.contact.layer import ContactLayer

    def make():
        sc = open_trefoil(0.125, nodes=90, contact=contact)
        sc.contact = ContactLayer(sc.model, sc.contact.law, local_thickness=True)
        return sc

    first = make()
    tight = tie(first, tighten_steps=20).run()
    assert tight.converged, tight.failure
    f_t = end_reaction(tight.system)
    scene = make()
    gaps = []

    def hook(phase, system, rec) -> None:
        if phase == "pull":
            gaps.append(scene.contact.min_distance(system.state.x)[0] / scene.diameter)

    res = tie(scene, pull_force=3.0 * f_t, hook=hook, tighten_steps=20, pull_steps=20).run()
    assert res.converged, res.failure
    assert set(res.knot_types) == {"3_1"}
    assert len(gaps) >= 5
    assert min(gaps) >= (0.3 if contact == "compliant" else 0.98)


def test_a_knot_that_slips_off_a_hinged_end_says_so() -> None:
    # Hinged ends and a pull far below what holds the frictionless 185 mm knot: the tail
    # swings out through the loop, which the failure names as such (not a pass-through).
    res = tie(open_trefoil(nodes=90, grip_length=0.0), pull_force=0.3, tighten_steps=20).run()
    assert not res.converged
    assert "knot type 0_1" in res.failure and "an end left the knot" in res.failure
    # The result carries the force of the last equilibrium, where the pull stopped (it
    # ramps down from the tightening's end force to 0.3 N), not the force aimed at.
    assert 0.0 < res.phases["pull"].t < 1.0
    assert res.pull_force_N > 0.3


def test_a_pass_through_between_iterates_is_named() -> None:
    # A closed trefoil and the same curve with one crossing switched by moving the upper
    # strand's vertices straight down through the lower one: the path between the two
    # meets the lower strand, and the change (to the unknot) is said to be a pass-through.
    from tightknot.knots.scenes import closed_trefoil
    from tightknot.loading.diagnose import topology_change
    from tightknot.loading.tie import knot_type_of

    scene = closed_trefoil(nodes=120)
    x = scene.state.x
    n = len(x)
    best = None
    for i in range(n):
        p0, p1 = x[i, :2], x[(i + 1) % n, :2]
        for j in range(i + 2, n - (1 if i == 0 else 0)):
            q0, q1 = x[j, :2], x[(j + 1) % n, :2]
            m = np.array([p1 - p0, q0 - q1]).T
            if abs(np.linalg.det(m)) < 1e-14:
                continue
            s, t = np.linalg.solve(m, q0 - p0)
            if 0 < s < 1 and 0 < t < 1:
                dz = (x[i, 2] + s * (x[(i + 1) % n, 2] - x[i, 2])) - (
                    x[j, 2] + t * (x[(j + 1) % n, 2] - x[j, 2]))
                if best is None or abs(dz) > abs(best[2]):
                    best = (i, j, dz)
    i, j, dz = best
    upper = [i, (i + 1) % n] if dz > 0 else [j, (j + 1) % n]
    moved = x.copy()
    moved[upper, 2] -= np.sign(dz) * 2.0 * abs(dz)
    assert knot_type_of(scene, moved) == "0_1"
    why = topology_change(scene, [x, moved], scene.model.edge_rest_length, knot_type_of)
    assert "passed through itself" in why and "edges" in why



def test_a_search_without_settling_steps_from_the_held_knot(monkeypatch) -> None:
    # The sections' route searches the force from the tied knot whose end is held
    # (tightknot/loading/pull.py: _seek(settle=False)): its first solve is at the
    # search's first force, not the dead-load equilibrium at the force the end carries; a
    # knot already within the tolerance is still brought to that equilibrium, so that the
    # result is one under a dead load.
    import dataclasses

    from tightknot.loading.levels import LevelPath, SearchOptions
    from tightknot.loading.pull import _seek, knot_length
    from tightknot.loading.tie import system_at
    from tightknot.solvers.program import Program

    scene = open_trefoil(0.125, nodes=90)
    tied = tie(scene, tighten_steps=20).run()
    assert tied.converged, tied.failure
    carried = end_reaction(tied.system)
    lam = knot_length(scene, tied.system)
    forces: list[float] = []
    solve = LevelPath.solve

    def recorded(self, value):
        forces.append(value)
        return (yield from solve(self, value))

    monkeypatch.setattr(LevelPath, "solve", recorded)
    search = SearchOptions(tolerance=0.1, step_ratio=1.15, max_steps=60, retries=3,
                           refine="bisection")
    for target, settled in ((lam - 0.5, False), (lam + 0.05, True)):
        forces.clear()
        start = dataclasses.replace(tied, system=system_at(scene, tied.system))
        res = Program(_seek(scene, start, target, search, 1e-8, None, settle=False),
                      "seek").run()
        assert res.converged, res.failure
        assert abs(knot_length(scene, res.system) - target) <= 0.1
        assert forces and (forces[0] == carried) == settled


def test_the_last_slope_of_a_search() -> None:
    # The final route's search after the sections join steps by the slope of the compliant
    # search's last two equilibria (tightknot/loading/pull.py: _last_slope), in log force.
    import math

    from tightknot.loading.pull import _last_slope

    pts = [(math.log(1.72), 15.23), (math.log(1.85), 14.89), (math.log(1.79), 15.07)]
    assert _last_slope(pts) == pytest.approx((15.07 - 14.89) / math.log(1.79 / 1.85))
    assert _last_slope(pts[:1]) is None  # one equilibrium
    assert _last_slope([pts[0], pts[0]]) is None  # one force
    assert _last_slope([pts[0], (math.log(1.85), 15.5)]) is None  # rising: no secant


def test_a_failed_final_route_on_an_open_knot_names_the_pull_path() -> None:
    """Where the sections fail to join a pulled open knot at its end (the final route: a
    20 N pull, docs/sectioned_level.md), the failure says which path adds them before the
    pull; a closed knot or the pull route has no such hint."""
    from tightknot.knots.scenes import closed_trefoil, open_trefoil
    from tightknot.loading.tie import _route_hint

    opened, closed = open_trefoil(0.185, nodes=90), closed_trefoil(nodes=40)
    assert "--section-path pull" in _route_hint(opened, "final")
    assert _route_hint(opened, "pull") == _route_hint(closed, "final") == ""
