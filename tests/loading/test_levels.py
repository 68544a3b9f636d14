"""The level continuation (tightknot.loading.levels) on a rod with a closed-form answer: a
neo-Hookean rod clamped at one end and pulled by a dead force F at the other, whose
stretch solves F = mu A0 (lam - lam^-2) exactly in the discretisation (the verification
case neo_hookean_uniaxial). 1/lam falls as F grows, as the knot length Lambda_OC does, so
it stands in for Lambda_OC in the search."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tightknot.loading.levels import (
    LevelLoad,
    LevelOptions,
    LevelPath,
    SearchOptions,
    SecantPredictor,
)
from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material, section_area
from tightknot.rods.state import State
from tightknot.solvers.continuation import ContinuationOptions, continuation
from tightknot.solvers.program import Program
from tightknot.solvers.system import RodSystem

MAT = Material(1.0e6, 0.5, 1000.0)
DIAMETER = 0.01
MU_A0 = MAT.neo_hookean_mu * section_area(DIAMETER)  # [N]
#: Pull-style and sweep-style searches (the table in the module docstring).
ONE = LevelOptions(steps="one")
GEOMETRIC = LevelOptions(steps="geometric")


def _rod() -> tuple[RodSystem, LevelLoad]:
    n = 11
    b = RodBuilder(twist=False)
    b.add_rod(np.c_[np.linspace(0.0, 0.1, n), np.zeros(n), np.zeros(n)], DIAMETER, MAT)
    model = b.finalize()
    load = LevelLoad()
    bcs = BoundaryConditions(model).clamp(0, "start").force(
        0, -1, lambda t: load(t) * np.array([1.0, 0.0, 0.0]))
    return RodSystem(model, State.initial(model), bcs), load


def _stretch(system: RodSystem) -> float:
    e = np.linalg.norm(np.diff(system.state.x, axis=0), axis=1)
    return float(e[1:].mean() / system.model.edge_rest_length[1:].mean())


def _tension(system: RodSystem) -> float:
    lam = _stretch(system)
    return MU_A0 * (lam - lam**-2)


def _inverse_stretch(system: RodSystem) -> float:
    return 1.0 / _stretch(system)


def _path(options: LevelOptions, force: float = 2.0, **kw) -> LevelPath:
    """The rod at equilibrium under ``force`` [N]."""
    system, load = _rod()
    path = LevelPath(system, load, options, level=force, **kw)
    assert _run(path.solve(force)) == ""
    return path


def _run(coroutine):
    return Program(coroutine, "test").run()


def test_a_held_load_is_its_value_at_every_t_and_a_ramp_starts_at_the_last() -> None:
    load = LevelLoad(0.1)
    assert load(0.0) == load(0.37) == load(1.0) == 0.1  # exactly: a static solve's level
    load.ramp_to(0.3)
    assert load(0.0) == 0.1 and load(1.0) == pytest.approx(0.3, rel=1e-15)
    load.hold(0.2)
    assert load(0.5) == 0.2


@pytest.mark.parametrize("options", [ONE, GEOMETRIC], ids=["one", "geometric"])
def test_a_move_ends_at_the_equilibrium_of_its_level(options: LevelOptions) -> None:
    path = _path(options)
    for force in (8.0, 3.0):  # up, then down (by 1.15 per solve with geometric steps)
        assert _run(path.move_to(force)) == ""
        assert path.level == force and path.load(1.0) == force
        assert _tension(path.system) == pytest.approx(force, rel=1e-8)
    if options.steps == "geometric":
        # from 8 N down to 3 N at most by 1.15 per solve
        assert path.solves >= 1 + 1 + math.ceil(math.log(8.0 / 3.0) / math.log(1.15))


def test_linear_steps_are_one_continuation_from_the_last_level() -> None:
    # The first two levels have no predictor: each is exactly a one-step continuation of
    # a load ramped from the last level.
    path = LevelPath(*_rod(), LevelOptions(steps="linear", proximal_dt=None,
                                           predictor=SecantPredictor()))
    ref, load = _rod()
    for force in (2.0, 5.0):
        assert _run(path.move_to(force)) == ""
        load.ramp_to(force)
        assert continuation(ref, ContinuationOptions(steps=1)).run().converged
        assert np.array_equal(path.system.state.x, ref.state.x)
    # From the third level on, the extrapolated start: the same equilibrium.
    assert _run(path.move_to(8.0)) == ""
    assert path.level == 8.0
    assert _tension(path.system) == pytest.approx(8.0, rel=1e-8)


@pytest.mark.parametrize("options, search", [
    (ONE, SearchOptions(tolerance=1e-4, retries=3, refine="bisection")),
    (GEOMETRIC, SearchOptions(tolerance=1e-4, secant=True, refine="regula_falsi")),
], ids=["tie_to_lambda", "sweep"])
@pytest.mark.parametrize("target", [0.8, 0.99])  # above and below the start's 1/lam
def test_the_search_brackets_the_target_and_narrows_the_bracket(
        options: LevelOptions, search: SearchOptions, target: float) -> None:
    path = _path(options, force=2.0)
    assert _run(path.seek(target, _inverse_stretch, search)) == ""
    assert abs(_inverse_stretch(path.system) - target) <= search.tolerance
    # The state is the equilibrium of the level reached, which lies between the closed-form
    # forces of the tolerance's ends (F(m) = mu A0 (1/m - m^2) for m = 1/lam).
    assert _tension(path.system) == pytest.approx(path.level, rel=1e-8)
    m_lo, m_hi = target - search.tolerance, target + search.tolerance
    assert MU_A0 * (1 / m_hi - m_hi**2) <= path.level <= MU_A0 * (1 / m_lo - m_lo**2)


def test_a_refused_step_is_retried_with_the_root_of_its_ratio() -> None:
    # A check that refuses any step by more than 10 % (as a knot slips off a tail when
    # loosened too fast): 1.15 is refused, sqrt(1.15) = 1.072 is taken.
    def check(system, rec, force):
        return "too far" if force > 1.1 * path.level else None

    path = _path(ONE)
    path.check = check
    assert _run(path.seek(0.8, _inverse_stretch, SearchOptions(retries=3))) == ""
    path = _path(ONE)
    path.check = check
    before = path.system.state.x.copy()
    why = _run(path.seek(0.8, _inverse_stretch, SearchOptions(retries=0)))
    assert why.startswith("toward Lambda_OC = 0.8: too far (reached ")
    # Left at the last accepted equilibrium, under its load.
    assert path.level == 2.0 and path.load(1.0) == 2.0
    assert np.array_equal(path.system.state.x, before)


def test_a_geometric_move_splits_a_refused_step_until_its_budget_is_spent() -> None:
    def check(system, rec, force):
        return "refused" if force > 3.0 else None

    path = _path(GEOMETRIC, check=check)
    why = _run(path.move_to(10.0))
    assert why == "refused (after 3 tries with smaller force steps)"
    # Sub-steps got as far as the check allows, each an equilibrium of its level.
    assert 2.0 < path.level <= 3.0 and path.load(1.0) == path.level
    assert _tension(path.system) == pytest.approx(path.level, rel=1e-8)


def test_the_predictor_extrapolates_the_last_two_equilibria_when_allowed() -> None:
    calls: list[float] = []

    def guard(x, guess):
        calls.append(float(guess[-1, 0] - x[-1, 0]))  # the tip's predicted motion [m]
        return True

    moved = []
    path = _path(LevelOptions(steps="one", predictor=SecantPredictor(
        falling=False, guard=guard)), recentre=lambda s: moved.append(1))
    _run(path.move_to(3.0))
    # The start and the first equilibrium share a level: no slope yet.
    assert calls == []
    _run(path.move_to(4.0))
    assert len(calls) == 1 and calls[0] > 0  # pulled harder: the tip predicted to move out
    _run(path.move_to(3.5))
    assert len(calls) == 1  # falling: no guess (falling=False)
    assert len(moved) == 4  # the recentre hook before every solve


def test_options_name_the_parameter_and_its_range() -> None:
    with pytest.raises(ValueError, match="steps must be one of"):
        LevelOptions(steps="log")
    with pytest.raises(ValueError, match="down_ratio"):
        LevelOptions(down_ratio=1.0)
    with pytest.raises(ValueError, match="refine must be one of"):
        SearchOptions(refine="newton")
    with pytest.raises(ValueError, match="step_ratio"):
        SearchOptions(step_ratio=0.9)
    with pytest.raises(ValueError, match="needs the level"):
        LevelPath(*_rod(), ONE)


def test_a_solve_that_passed_through_is_refused_without_proximal_steps(monkeypatch) -> None:
    # Two parallel rods, the second pulled at its middle through the first with no contact
    # energy (only a promise to keep them apart): Newton stops with "passed_through". The
    # proximal steps would start from that crossed iterate, so the level path refuses the
    # solve instead (the one static solve, solvers.continuation.static_solve), names the
    # reason, and keeps its last equilibrium.
    import tightknot.loading.levels as levels
    from tests.rods.test_proximity import _Apart  # no energy, a promise to keep apart
    from tightknot.solvers import continuation as cont

    b = RodBuilder(twist=False)
    s = np.linspace(0.0, 5 * DIAMETER, 11)
    b.add_rod(np.c_[s, np.zeros(11), np.zeros(11)], DIAMETER, MAT)
    b.add_rod(np.c_[s, np.full(11, 0.2 * DIAMETER), np.zeros(11)], DIAMETER, MAT)
    model = b.finalize()
    load = LevelLoad()
    bcs = BoundaryConditions(model)
    for rod in (0, 1):
        bcs.pin(rod, 0).pin(rod, -1)
        for v in range(11):
            bcs.fix_components(rod, v, (0, 2))
    bcs.force(1, 5, lambda t: load(t) * np.array([0.0, -1.0, 0.0]))
    system = RodSystem(model, State.initial(model), bcs)
    system.add_term(_Apart())  # its step bound is 0.02 of its D = DIAMETER
    path = LevelPath(system, load, LevelOptions(steps="one", proximal_dt=1e-3),
                     level=0.0)
    start = system.state.x.copy()

    def no_proximal(*args, **kwargs):
        raise AssertionError("proximal steps after the rod passed through itself")

    monkeypatch.setattr(cont, "proximal", no_proximal)
    monkeypatch.setattr(levels, "proximal", no_proximal, raising=False)  # a copy's import
    why = _run(path.solve(0.5))
    assert "passed_through" in why
    assert path.level == 0.0 and np.array_equal(system.state.x, start)


def _inverse_stretch_at(force: float) -> float:
    """The closed form's 1/lam under ``force`` [N]: lam^3 - (F / mu A0) lam^2 - 1 = 0."""
    roots = np.roots([1.0, -force / MU_A0, 0.0, -1.0])
    lam = max(r.real for r in roots if abs(r.imag) < 1e-12)
    return 1.0 / lam


def test_a_given_slope_makes_the_first_secant_step() -> None:
    # The slope of 1/lam in log F over the step to the target: the first step lands within
    # the tolerance, where the fixed first step (1.15) overshoots and the bracket is
    # searched. A given slope's step aims half the tolerance past the target (a cheaper
    # model's slope has overestimated the response): log F moves by that over the slope.
    target_force = 2.0 * 1.08
    target = _inverse_stretch_at(target_force)
    slope = (target - _inverse_stretch_at(2.0)) / math.log(1.08)
    tol = 1e-6
    search = SearchOptions(tolerance=tol, secant=True, retries=3, refine="bisection")
    hinted = _path(ONE)
    assert _run(hinted.seek(target, _inverse_stretch, search, slope)) == ""
    assert hinted.solves == 2  # the start and the one secant step
    assert hinted.level == pytest.approx(target_force * math.exp(-0.5 * tol / slope),
                                         rel=1e-9)
    assert hinted.level > target_force  # past the target: Lambda_OC falls with F
    plain = _path(ONE)
    assert _run(plain.seek(target, _inverse_stretch, search)) == ""
    assert plain.solves > 2
    # a rising slope says nothing about a target Lambda_OC that falls with the level
    rising = _path(ONE)
    assert _run(rising.seek(target, _inverse_stretch, search, -slope)) == ""
    assert rising.solves == plain.solves
