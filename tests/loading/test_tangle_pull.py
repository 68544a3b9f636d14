"""Pulling two-rod tangles: equilibrium of the four ends, the load paths' targets, and the
failures that must say why."""

from __future__ import annotations

import numpy as np
import pytest

from tightknot.knots.tangle_scenes import tangle_scene
from tightknot.loading.tangle_pull import pull_tangle, pulling_force

# A coarse clasp (the clasp's rods are ~23 D0 long: 60 vertices give edges of 0.4 D0,
# within the contact's 0.5 D0) pulled to 0.5 N (0.11 EI/D0^2): a second or two.
NODES = 60
FORCE = 0.5


@pytest.fixture(scope="module")
def clasp_pulled():
    scene = tangle_scene("clasp", nodes=NODES)
    return scene, pull_tangle(scene, force=FORCE)


def test_clasp_reaches_the_force_and_keeps_its_type(clasp_pulled):
    scene, res = clasp_pulled
    assert res.converged, res.failure
    start = scene.start_type.label()
    assert res.tangle_types and all(t == start for t in res.tangle_types)
    assert abs(scene.start_type.linking_number) == 1
    # The dead load is the pulling force: B's two ends carry FORCE/2 each along +x.
    assert res.pull_force_N == pytest.approx(FORCE, rel=1e-6)
    # The rods are hooked: the last equilibrium is farther apart than the relaxed start.
    assert res.force_extension[-1][0] > res.force_extension[0][0]


def test_end_reactions_balance(clasp_pulled):
    scene, res = clasp_pulled
    total = sum(r.force_N for r in res.reactions)
    # The four end forces are the only external forces: they sum to zero at equilibrium,
    # to the Newton tolerance (1e-6 of the force scale EI/L^2 ~ 1e-3 N) and far below F.
    assert np.linalg.norm(total) < 1e-4 * FORCE
    fa = sum(r.force_N[0] for r in res.reactions if r.rod == "A")
    fb = sum(r.force_N[0] for r in res.reactions if r.rod == "B")
    assert fb == pytest.approx(FORCE, rel=1e-6)
    assert fa == pytest.approx(-FORCE, rel=1e-4)
    assert pulling_force(res.reactions) == pytest.approx(FORCE, rel=1e-4)


def test_end_distance_pull_reaches_its_distance():
    scene = tangle_scene("clasp", nodes=NODES)
    d0 = scene.end_distance(scene.state.x)
    target = d0 + 3.0 * scene.diameters[0]
    res = pull_tangle(scene, end_distance=target)
    assert res.converged, res.failure
    # The grips are prescribed: the end distance is the target to round-off.
    assert scene.end_distance(res.system.state.x) == pytest.approx(target, abs=1e-12)
    assert all(p == "pull" for _, _, p in res.force_extension[1:])


def test_unreachable_force_says_why():
    scene = tangle_scene("clasp", nodes=NODES)
    d0 = scene.end_distance(scene.state.x)
    res = pull_tangle(scene, force=50.0, max_end_distance=d0 + 0.5 * scene.diameters[0])
    assert not res.converged
    assert "the force 50 N was not reached" in res.failure
    assert res.system is not None and len(res.reactions) == 4


def test_a_tangle_that_comes_apart_stops_the_run_with_its_state():
    scene = tangle_scene("clasp", nodes=NODES)
    calls = [0]

    def flaky(sc, x):
        # The true label until the third step, then another: a change of type.
        calls[0] += 1
        return sc.tangle_type(x).label() if calls[0] < 3 else "lk 0; rods 0_1,0_1"

    res = pull_tangle(scene, force=FORCE, tangle_type=flaky)
    assert not res.converged
    assert "the tangle came apart in phase pull" in res.failure
    assert "rods A and B" in res.failure
    assert res.failed_state is not None


def test_bad_loads_are_refused():
    scene = tangle_scene("clasp", nodes=NODES)
    with pytest.raises(ValueError, match="exactly one"):
        pull_tangle(scene)
    with pytest.raises(ValueError, match="force must be finite"):
        pull_tangle(scene, force=-1.0)
    # The grips only pull apart: a target short of the start is known bad before a solve.
    short = 0.5 * scene.end_distance(scene.state.x)
    with pytest.raises(ValueError, match="end_distance must exceed the start's"):
        pull_tangle(scene, end_distance=short)
    with pytest.raises(ValueError, match="max_end_distance must exceed"):
        pull_tangle(scene, force=1.0, max_end_distance=short)


def test_rods_of_different_stiffness_are_pulled_and_flagged():
    from tightknot.rods.material import Material

    scene = tangle_scene("clasp", nodes=NODES,
                         material_b=Material(youngs_modulus=2.5e6, poisson_ratio=0.5))
    assert scene.info["warnings"]  # outside the contact law's identical-rod calibration
    assert scene.model.rods[1].material.youngs_modulus == 2.5e6
    res = pull_tangle(scene, force=FORCE)
    assert res.converged, res.failure
    # Equal end forces: the rod of twice the modulus stretches less (not half as much:
    # the grips' lateral forces and the bends share the strain; a closed form does not
    # hold here).
    x = res.system.state.x
    s = [scene.model.rod_length(x, r) / scene.model.rest_length(r) - 1.0 for r in (0, 1)]
    assert 0.0 < s[1] < s[0]
