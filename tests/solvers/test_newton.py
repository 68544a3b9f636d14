"""The Newton loop's contract: it reports failure instead of returning NaN; its shift's
ladder after an inertia refusal."""

import math

import numpy as np
import pytest

from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material, second_moment
from tightknot.rods.state import State
from tightknot.solvers import pardiso
from tightknot.solvers.continuation import ContinuationOptions, continuation
from tightknot.solvers.linear import factorize
from tightknot.solvers.newton import NewtonOptions, _raised, newton
from tightknot.solvers.pattern import SparsePattern
from tightknot.solvers.system import RodSystem


def _clamped(points: np.ndarray, load_parameter: float, direction: list[float]) -> RodSystem:
    """A rod of 1 m along ``points``, clamped at its start, its end loaded by
    ``load_parameter`` EI/L^2 along ``direction``."""
    b = RodBuilder()
    b.add_rod(points, diameter=0.01, material=Material(1e6, 0.5, 1000.0))
    m = b.finalize()
    f = load_parameter * 1e6 * second_moment(0.01) * np.asarray(direction, dtype=float)
    return RodSystem(m, State.initial(m),
                     BoundaryConditions(m).clamp(0, "start").force(0, -1, f))


def _cantilever(n: int = 30, load_parameter: float = 5.0) -> RodSystem:
    x = np.linspace(0.0, 1.0, n)
    return _clamped(np.c_[x, 0 * x, 0 * x], load_parameter, [0.0, -1.0, 0.0])


def test_non_convergence_is_reported_not_nan() -> None:
    system = _cantilever()
    system.set_load(1.0)
    # Two iterations cannot reach a large-deflection equilibrium from the straight rod.
    res = newton(system, system.free_vector(), NewtonOptions(max_iterations=2)).run()
    assert not res.converged
    assert res.reason == "max_iterations"
    assert math.isfinite(res.residual) and res.residual > 1e-8
    assert np.isfinite(system.state.x).all()


def test_a_relative_tolerance_stops_at_its_fraction_of_the_start() -> None:
    # relative_tol: the first iterate below a tenth of the start's residual ends the solve
    # as converged (the full solve goes on below it), and its value is checked.
    full = _cantilever()
    full.set_load(1.0)
    whole = newton(full, full.free_vector(), NewtonOptions(max_iterations=100)).run()
    system = _cantilever()
    system.set_load(1.0)
    part = newton(system, system.free_vector(),
                  NewtonOptions(max_iterations=100, relative_tol=0.1)).run()
    assert whole.converged and part.converged
    h = part.history
    assert h[-1] <= 0.1 * h[0] and all(r > 0.1 * h[0] for r in h[:-1])
    assert part.iterations < whole.iterations and whole.history[:len(h)] == h
    for bad in (-0.1, 1.0, float("nan")):
        with pytest.raises(ValueError, match="relative_tol"):
            NewtonOptions(relative_tol=bad)


def test_converges_quadratically_near_solution() -> None:
    system = _cantilever(load_parameter=1.0)
    res = continuation(system, ContinuationOptions(steps=4)).run()
    assert res.converged
    hist = res.steps[-1].newton.history
    # Quadratic convergence: once the residual is below 1e-2, the next is below its square
    # times a modest constant (100 covers the stencil's stiffness ratio), until round-off.
    pairs = [(a, b) for a, b in zip(hist, hist[1:], strict=False) if 1e-6 < a < 1e-2]
    assert pairs, f"no iterate in the quadratic range: {hist}"
    for a, b in pairs:
        assert b < 100 * a * a, hist


def test_failed_continuation_restores_last_equilibrium() -> None:
    system = _cantilever(load_parameter=3.0)
    opts = ContinuationOptions(steps=1, min_step=0.5, newton=NewtonOptions(max_iterations=1))
    res = continuation(system, opts).run()
    assert not res.converged
    assert "min_step" in res.failure and "t=" in res.failure
    assert np.isfinite(system.state.x).all()


def test_direct_solve_is_backward_stable_on_mixed_stiffness() -> None:
    # Positions and twist angles differ in stiffness by decades (EA/l against GJ/l); the
    # equilibrated, threshold-pivoted LU must stay backward stable: normwise backward error
    # |H d + g| / (|H| |d| + |g|) measured 1.4e-16..1.5e-16 at 400 and 4000 vertices; 1e-14
    # leaves a wide margin yet fails a solver that lost digits (unpivoted: 5e-5 relative).
    import scipy.sparse.linalg as spla

    system = _cantilever(n=400)
    system.set_load(1.0)
    _, g, h = system.evaluate(system.free_vector())
    d = factorize(h).solve(-g)
    backward = np.abs(h @ d + g).max() / (
        spla.norm(h, np.inf) * np.abs(d).max() + np.abs(g).max())
    assert backward <= 1e-14


def test_pattern_drops_fixed_dofs() -> None:
    system = _cantilever(n=10)
    pat: SparsePattern = system.pattern
    fixed = system.bcs.fixed_mask()
    assert pat.n == int((~fixed).sum())
    # Every stored entry is on free dofs, and the diagonal is present for each free dof.
    assert (pat.diag_slot >= 0).all()


def test_a_question_answered_later_gives_the_same_solve() -> None:
    # A program's questions may be answered whenever its driver likes (a batch collects
    # them): answered one by one from outside, the continuation is the same to the bit.
    from tightknot.solvers.program import Evaluate

    direct = _cantilever(load_parameter=1.0)
    ref = continuation(direct, ContinuationOptions(steps=4)).run()
    system = _cantilever(load_parameter=1.0)
    gen = iter(continuation(system, ContinuationOptions(steps=4)))
    asked = 0
    answer = None
    while True:
        try:
            question = gen.send(answer)
        except StopIteration as done:
            res = done.value
            break
        assert question.system is system
        asked += isinstance(question, Evaluate)
        answer = question.answer()
    assert asked > 0
    assert res.converged and res.newton_iterations == ref.newton_iterations
    np.testing.assert_array_equal(system.state.x, direct.state.x)


def test_a_program_says_it_was_not_run() -> None:
    system = _cantilever()
    prog = continuation(system, ContinuationOptions(steps=4))
    with pytest.raises(AttributeError, match=r"call \.run\(\)"):
        _ = prog.converged
    assert prog.run().converged


def test_a_batch_rod_is_not_evaluated_alone() -> None:
    system = _cantilever()
    system.batch = object()  # attached to some batch: only the batch answers it
    with pytest.raises(RuntimeError, match="answered by the batch"):
        system.evaluate(system.free_vector())


def _column(load_parameter: float) -> RodSystem:
    """A clamped column pushed along its axis by ``load_parameter`` EI/L^2 (Euler's
    critical load of a cantilever is pi^2/4 = 2.47 of them), bent slightly to start."""
    x = np.linspace(0.0, 1.0, 30)
    system = _clamped(np.c_[x, 1e-3 * x**2, 0 * x], load_parameter, [-1.0, 0.0, 0.0])
    system.set_load(1.0)
    return system


def test_the_inertia_ladder_skips_rungs_only() -> None:
    # After a refusal for a negative eigenvalue the shift's ladder starts at shift_inertia
    # but passes through the same values as the plain ladder from shift_initial.
    opt = NewtonOptions(shift_initial=1e-8, shift_inertia=1e-6)
    plain = [0.0]
    for _ in range(6):
        plain.append(_raised(plain[-1], opt, False))
    assert plain[1] == 1e-8
    assert _raised(0.0, opt, True) == plain[3]
    assert _raised(plain[1], opt, True) == plain[3]
    assert _raised(plain[4], opt, True) == plain[5]


@pytest.mark.skipif(not pardiso.available(), reason="pypardiso and MKL not installed")
def test_an_inertia_refusal_costs_fewer_factorizations_on_the_same_path() -> None:
    runs = []
    for inertia in (1e-8, 1e-6):  # 1e-8 = shift_initial: the plain ladder
        system = _column(5.0)
        system.linear = pardiso.PardisoDirect()
        opts = NewtonOptions(shift_inertia=inertia, max_iterations=200)
        res = newton(system, system.free_vector(), opts).run()
        runs.append((res, system.linear, system.state.x.copy()))
    (plain, lin_plain, x_plain), (skip, lin_skip, x_skip) = runs
    assert plain.converged and skip.converged
    # the column buckles: its first Hessians have a negative eigenvalue
    assert lin_plain.indefinite > 0
    assert np.ptp(x_plain[:, 1]) > 0.1
    # the same shifts accepted, so the same iterates bit for bit
    assert plain.history == skip.history
    np.testing.assert_array_equal(x_plain, x_skip)
    # two rungs (1e-8, 1e-7) fewer for every climb from zero that passed them
    assert lin_skip.factorizations < lin_plain.factorizations
    assert lin_plain.indefinite - lin_skip.indefinite == \
        lin_plain.factorizations - lin_skip.factorizations


class _Rejudged(RodSystem):
    """A rod system whose energy rises by ``jump`` [J] each time a state is accepted, as
    the sectioned level's does where accepting a step carries its frames (and the reference
    twist its sections turn with) on: the function changes, its derivatives do not."""

    jump = 0.0
    accepted_states = 0

    def evaluate(self, u, want_grad=True, want_hess=True):  # noqa: ANN001, ANN201
        e, *rest = super().evaluate(u, want_grad, want_hess)
        return (e + self.jump * self.accepted_states, *rest)

    def accept(self, u: np.ndarray) -> None:
        super().accept(u)
        self.accepted_states += 1


def test_a_change_of_energy_on_acceptance_does_not_steer_the_trust_shift() -> None:
    # The trust ratio compares the model's decrease with the line search's, both at the
    # frames the model was made with; a change of the energy on acceptance is no evidence
    # against the model. With it judged as one, the shift rose and the solve took damped
    # steps (a sectioned pull step stalled at a residual of 2e-3 for 40 iterations).
    runs = []
    for jump in (0.0, 1e-9):
        base = _cantilever(load_parameter=3.0)
        system = _Rejudged(base.model, base.state, base.bcs)
        system.jump = jump
        system.set_load(1.0)
        res = newton(system, system.free_vector(), NewtonOptions(max_iterations=100)).run()
        runs.append((res, system.state.x.copy()))
    (plain, x_plain), (jumping, x_jumping) = runs
    assert plain.converged and jumping.converged
    assert plain.history == jumping.history
    np.testing.assert_array_equal(x_plain, x_jumping)
