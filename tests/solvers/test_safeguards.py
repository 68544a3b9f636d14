"""Solver safeguards (issue 8): a solve that cannot progress stops with a reason instead of
spending its budget, a failed load path says at which load step, keeps the failing iterate
for inspection and leaves the system at the last equilibrium, and the step adapts."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material, second_moment
from tightknot.rods.state import State
from tightknot.solvers.continuation import ContinuationOptions, continuation
from tightknot.solvers.linear import SparseDirect
from tightknot.solvers.newton import NewtonOptions, newton
from tightknot.solvers.system import RodSystem


class _Blocked:
    """E = |u - 1|^2 / 2 whose every step is blocked to a 1e-14 fraction (as a contact
    layer blocks steps that would pass through): no progress is possible."""

    linear = SparseDirect()
    violation = None

    def residual_floor(self):
        return 0.0

    def __init__(self, n: int = 3) -> None:
        self.target = np.ones(n)
        self.accepted = 0

    def has_trial(self, u):
        return True  # accept needs no evaluation of its own

    def evaluate(self, u, want_grad=True, want_hess=True):
        import scipy.sparse as sp

        r = u - self.target
        return 0.5 * float(r @ r), r.copy(), sp.identity(u.size, format="csc")

    def accept(self, u):
        self.accepted += 1

    def max_step(self, u, du):
        return 1e-14

    def residual_norm(self, g):
        return float(np.abs(g).max())

    def step_norm(self, du):
        return float(np.abs(du).max())

    def energy_roundoff(self):
        return 1e-13 * 1.5


def test_no_progress_stops_as_stalled_within_the_window() -> None:
    prob = _Blocked()
    # step_tol is set out of reach so that only the no-progress test can end the loop early
    # (the blocked steps shrink, which the step-size test would otherwise catch).
    # (blind_iterations off: the blocked steps' predicted decrease is below the round-off,
    # which that test would catch first, see the next test)
    res = newton(prob, np.zeros(3), NewtonOptions(max_iterations=500, step_tol=1e-300,
                                                  stall_iterations=40,
                                                  blind_iterations=0)).run()
    assert not res.converged
    assert res.reason == "stalled"
    # It stops as soon as 40 iterations (the window) made no progress over the start, not at
    # the 500-iteration limit.
    assert res.iterations == 40
    assert math.isfinite(res.residual)


def test_steps_below_the_roundoff_stop_as_stalled() -> None:
    # Blocked steps of 1e-14 predict decreases of ~1e-14, below the energy's round-off
    # (1.5e-13): the energy cannot judge them and the residual does not fall, so after
    # blind_iterations of them the solve stops, long before the window test's 40.
    res = newton(_Blocked(), np.zeros(3), NewtonOptions(
        max_iterations=500, step_tol=1e-300, stall_iterations=40, blind_iterations=10)).run()
    assert res.reason == "stalled" and res.iterations == 10


class _Sliding(_Blocked):
    """E = -u_0 + |u_1.. - 1|^2 / 2: every Newton step lowers the energy by 1 (down a
    slope without end, as a solve that leaps toward another basin) while the residual
    stays 1."""

    def evaluate(self, u, want_grad=True, want_hess=True):
        import scipy.sparse as sp

        r = u - self.target
        r[0] = -1.0
        e = -float(u[0]) + 0.5 * float(r[1:] @ r[1:])
        return e, r, sp.identity(u.size, format="csc")

    def max_step(self, u, du):
        return 1.0


@pytest.mark.parametrize("on_residual", [False, True])
def test_a_falling_energy_counts_as_progress_unless_the_residual_alone_is_judged(
        on_residual: bool) -> None:
    # section_finish's first solve judges its residual alone: its fallback (a homotopy)
    # starts again from the start, so a descent that does not bring the residual down is
    # given up after the window instead of the whole budget.
    res = newton(_Sliding(), np.zeros(3), NewtonOptions(
        max_iterations=120, stall_iterations=40, stall_on_residual=on_residual)).run()
    assert not res.converged
    assert (res.reason, res.iterations) == (("stalled", 40) if on_residual
                                            else ("max_iterations", 120))
    assert res.energy == pytest.approx(-res.iterations, rel=1e-12)


def test_stall_test_can_be_turned_off() -> None:
    res = newton(_Blocked(), np.zeros(3), NewtonOptions(
        max_iterations=60, step_tol=1e-300, stall_iterations=0, blind_iterations=0)).run()
    assert res.reason == "max_iterations" and res.iterations == 60


@pytest.mark.parametrize("kw", [dict(stall_iterations=-1), dict(stall_iterations=2.5),
                                dict(stall_factor=1.0), dict(stall_factor=math.nan),
                                dict(stall_roundoffs=0.0), dict(max_iterations=0),
                                dict(blind_iterations=-1)])
def test_bad_newton_options_name_the_parameter(kw: dict) -> None:
    with pytest.raises(ValueError, match=next(iter(kw))):
        NewtonOptions(**kw)


@pytest.mark.parametrize("kw", [dict(steps=0), dict(min_step=0.0), dict(max_step=math.inf),
                                dict(proximal_dt=-1.0), dict(max_newton_iterations=0)])
def test_bad_continuation_options_name_the_parameter(kw: dict) -> None:
    name = next(iter(kw))
    with pytest.raises(ValueError, match=name):
        ContinuationOptions(**kw)


def _cantilever(n: int = 30, load_parameter: float = 5.0) -> RodSystem:
    x = np.linspace(0.0, 1.0, n)
    b = RodBuilder()
    b.add_rod(np.c_[x, 0 * x, 0 * x], diameter=0.01, material=Material(1e6, 0.5, 1000.0))
    m = b.finalize()
    f = load_parameter * 1e6 * second_moment(0.01)
    return RodSystem(m, State.initial(m),
                     BoundaryConditions(m).clamp(0, "start").force(0, -1, [0, -f, 0]))


def test_failure_names_the_load_step_and_keeps_the_failing_iterate() -> None:
    system = _cantilever(load_parameter=3.0)
    opts = ContinuationOptions(steps=4, min_step=0.2, newton=NewtonOptions(max_iterations=2))
    res = continuation(system, opts).run()
    assert not res.converged
    assert "load step 1 (from t=0 to t=" in res.failure, res.failure
    # The system is back at the last equilibrium (here the start), the failing iterate is
    # kept apart, finite, and elsewhere (two Newton steps moved it).
    assert np.array_equal(system.state.x, system.model.vertex_initial_position)
    assert res.failed_state is not None and np.isfinite(res.failed_state.x).all()
    assert np.abs(res.failed_state.x - system.state.x).max() > 1e-6


def test_callback_refusal_names_the_load_step() -> None:
    system = _cantilever(load_parameter=1.0)
    res = continuation(system, ContinuationOptions(steps=4),
                       callback=lambda s, rec: "refused" if rec.t > 0.4 else None).run()
    assert not res.converged
    assert res.failure.startswith("refused [load step 2 (from t=0.25 to t=0.5)]"), res.failure


def test_newton_budget_stops_the_path() -> None:
    system = _cantilever(load_parameter=5.0)
    res = continuation(system, ContinuationOptions(steps=20, max_newton_iterations=10)).run()
    assert not res.converged
    assert "budget of 10 iterations" in res.failure and "load step" in res.failure
    assert res.newton_iterations >= 10 and res.t < 1.0
    assert np.isfinite(system.state.x).all()


def test_steps_halve_on_failure_and_grow_after_easy_ones() -> None:
    # One step to a large deflection fails with a small Newton budget; the path halves it
    # until steps converge, then grows them again after easy steps.
    system = _cantilever(load_parameter=5.0)
    opts = ContinuationOptions(steps=1, grow_below=8, newton=NewtonOptions(max_iterations=8))
    res = continuation(system, opts).run()
    assert res.converged, res.failure
    dts = np.diff([0.0] + [r.t for r in res.steps])
    assert dts.max() < 1.0  # the first full step was halved
    # ...and some later step is longer than an earlier one (grown).
    assert any(b > a * 1.5 for a, b in zip(dts, dts[1:], strict=False)), dts
