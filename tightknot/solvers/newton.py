"""One damped Newton loop for every solver (static, continuation, implicit dynamics).

Each iteration solves ``(H + mu D) d = -g`` with D the absolute diagonal of H (a
Levenberg-Marquardt shift, Nocedal & Wright 2006 sec. 3.4) raised whenever the Hessian
proves not positive definite along the step (``d.H d <= 0``), the step is not a descent
direction, or the factorization fails, and adapted like a trust region after each step
(grown when the step had to be cut or overshot, relaxed after good full steps); the step is
cut to the largest fraction the
problem allows (no passing through, from the contact layer) and a backtracking Armijo line
search on the total potential follows (Nocedal & Wright Alg. 3.1).

Convergence: the scaled residual (forces over EI/L^2, moments over EI/L) is below
``residual_tol``. The step size is reported, and two kinds of stagnation end the loop as a
failure instead of spending the iteration budget: tiny steps without a small residual
("stagnated"), and no progress over a window of iterations, i.e. neither the best residual
nor the energy improved by a measurable amount ("stalled": a solver cycling at a point it
cannot pass), or several iterations in a row predicted a decrease below the energy's
round-off without lowering the residual ("stalled" too: the energy can no longer judge the
steps, and the trust ratio, noise then, is not used to raise the shift). A failed solve
returns a result saying so, never NaN.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from tightknot.solvers.program import Coroutine, Evaluate, StepBound, accept, program

if TYPE_CHECKING:
    from tightknot.solvers.system import RodSystem


@dataclass
class NewtonOptions:
    """Settings of the Newton loop.

    Attributes:
        residual_tol: converged when the scaled residual is below this [-].
        relative_tol: converged also when the scaled residual is below this fraction of
            its value at the start (0: off), for a solve that only brings a later one
            near its solution [-].
        step_tol: a step below this (scaled) that did not cut the residual by
            ``stall_factor`` is stagnation.
        max_iterations: iteration limit.
        armijo: sufficient-decrease constant of the line search.
        max_backtracks: line-search halvings before the shift is raised instead.
        shift_initial: first relative shift mu when the Hessian is not positive definite.
        shift_trust: first relative shift when steps overshoot (trust-region damping).
        shift_inertia: the smallest shift tried after the linear solver refused the shifted
            Hessian for a negative eigenvalue (a solver that reads its factorization's
            inertia, :class:`tightknot.solvers.pardiso.PardisoDirect`): the shift's
            ladder (``shift_initial`` times powers of ten) skips the rungs below it,
            factorizations too small a shift to lift the negative eigenvalues of a
            tight knot's sectioned Hessian (docs/sectioned_level.md, "Cost").
        shift_max: beyond this shift the solve gives up.
        stall_iterations: window of the no-progress test (0 turns it off): the solve stops
            as "stalled" when over this many iterations the best residual did not fall
            below ``stall_factor`` times its value before the window and the energy fell
            by less than ``stall_roundoffs`` times its round-off.
        stall_factor: residual improvement that counts as progress [-].
        stall_roundoffs: energy decrease that counts as progress, in units of the
            problem's energy round-off (a thousand: well above noise, yet far below the
            decrease of any iteration that moves the rod measurably).
        stall_on_residual: the no-progress test judges the residual alone, an energy that
            still falls counting as no progress (a solve with a fallback, for which a
            descent that does not bring the residual down leads into another basin, e.g.
            :func:`tightknot.loading.tie.section_finish`'s first solve).
        blind_iterations: the solve stops as "stalled" after this many iterations in a
            row whose predicted decrease was below the energy's round-off (the energy can
            then not judge the step) while the residual did not fall below
            ``stall_factor`` times its value before them (0 turns it off).
    """

    residual_tol: float = 1e-8
    relative_tol: float = 0.0
    step_tol: float = 1e-13
    max_iterations: int = 100
    armijo: float = 1e-4
    max_backtracks: int = 30
    shift_initial: float = 1e-8
    shift_trust: float = 1e-3
    shift_inertia: float = 1e-6
    shift_max: float = 1e8
    stall_iterations: int = 50
    stall_factor: float = 0.5
    stall_roundoffs: float = 1e3
    stall_on_residual: bool = False
    blind_iterations: int = 10

    def __post_init__(self) -> None:
        for name in ("residual_tol", "step_tol", "armijo", "shift_initial", "shift_trust",
                     "shift_inertia", "shift_max", "stall_factor", "stall_roundoffs"):
            v = getattr(self, name)
            if not (isinstance(v, numbers.Real) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name} must be finite and > 0, got {v!r}")
        for name, low in (("max_iterations", 1), ("max_backtracks", 1),
                          ("stall_iterations", 0), ("blind_iterations", 0)):
            v = getattr(self, name)
            if not (isinstance(v, numbers.Integral) and v >= low):
                raise ValueError(f"{name} must be a whole number >= {low}, got {v!r}")
        if not (isinstance(self.relative_tol, numbers.Real) and 0.0 <= self.relative_tol < 1.0):
            raise ValueError(f"relative_tol must be in [0, 1), got {self.relative_tol!r}")
        if self.stall_factor >= 1.0:
            raise ValueError(f"stall_factor must be in (0, 1), got {self.stall_factor!r}")


@dataclass
class NewtonResult:
    """Outcome of a Newton solve.

    Attributes:
        converged: the residual test passed.
        iterations: Newton iterations taken.
        residual: final scaled residual [-].
        step: last scaled step [-].
        energy: final total potential [J].
        reason: why the loop stopped ("converged", "max_iterations", "stagnated",
            "stalled", "line_search_failed", "non_finite", "passed_through": an accepted
            iterate failed the system's independent proximity check, ``p.violation``).
        history: scaled residual after each iteration.
    """

    converged: bool
    iterations: int
    residual: float
    step: float
    energy: float
    reason: str
    history: list[float] = field(default_factory=list)


@program
def newton(p: RodSystem, u0: np.ndarray, options: NewtonOptions | None = None) -> Coroutine:
    """The damped Newton loop (module docstring) minimising the potential of ``p`` from
    free dofs ``u0``, as a program (:mod:`tightknot.solvers.program`): accepted iterates
    become the system's state. ``newton(p, u0).run()`` returns the :class:`NewtonResult`.
    The Newton systems are solved by the system's linear solver (``p.linear``)."""
    opt = options or NewtonOptions()
    # Round-off bounds what a tolerance can ask (RodSystem.residual_floor).
    tol = max(opt.residual_tol, p.residual_floor())
    u = np.array(u0, dtype=np.float64)
    energy, g, hp = yield Evaluate(p, u, True, True)
    if not (math.isfinite(energy) and np.isfinite(g).all()):
        return NewtonResult(False, 0, math.inf, math.inf, energy, "non_finite")
    res = p.residual_norm(g)
    if not math.isfinite(res):  # e.g. a zero force scale (a rod without stiffness)
        return NewtonResult(False, 0, math.inf, math.inf, energy, "non_finite")
    history = [res]
    if opt.relative_tol > 0.0:
        tol = max(tol, opt.relative_tol * res)
    mu = 0.0
    step = math.inf
    if res <= tol:
        yield from accept(p, u)
        return NewtonResult(True, 0, res, 0.0, energy, "converged", history)
    # Progress record of the stall test: best residual and energy after each iteration.
    best = [res]
    energies = [energy]
    blind, blind_ref = 0, res
    for it in range(1, opt.max_iterations + 1):
        accepted = False
        h = p.linear.matrix(hp)
        diag = np.abs(p.linear.diagonal(hp))
        diag = np.maximum(diag, 1e-12 * (diag.max() if diag.size else 1.0))
        while not accepted:
            d = p.linear.shifted_direction(hp, g, mu, diag)
            # H d is kept for the model decrease after the line search.
            hd = None if d is None else h @ d
            if d is None or not _acceptable(d, g, hd, mu, diag):
                mu = _raised(mu, opt, d is None and p.linear.refused_indefinite)
                if mu > opt.shift_max:
                    yield from accept(p, u)
                    return NewtonResult(False, it, res, step, energy, "line_search_failed",
                                        history)
                continue
            alpha = min(1.0, (yield StepBound(p, u, d)))
            slope = float(g @ d)
            roundoff = p.energy_roundoff()
            for _ in range(opt.max_backtracks):
                trial = u + alpha * d
                e_trial, _, _ = yield Evaluate(p, trial, False, False)
                if not math.isfinite(e_trial):
                    alpha *= 0.5
                    continue
                if e_trial <= energy + opt.armijo * alpha * slope:
                    accepted = True
                    break
                # Near the minimum the predicted decrease is below the round-off of the
                # energy, which can then not rank the iterates: accept the step if the
                # energy did not grow beyond that round-off (the quadratic model is exact).
                if -alpha * slope <= roundoff and e_trial <= energy + roundoff:
                    accepted = True
                    break
                alpha *= 0.5
            if not accepted:
                mu = _raised(mu, opt, False)
                if mu > opt.shift_max:
                    yield from accept(p, u)
                    return NewtonResult(False, it, res, step, energy, "line_search_failed",
                                        history)
        du = alpha * d
        predicted = -(alpha * slope + 0.5 * alpha * alpha * float(d @ hd))
        u = u + du
        step = p.step_norm(du)
        yield from accept(p, u)
        if p.violation is not None:
            # The independent check found two pieces of rod closer than its floor.
            return NewtonResult(False, it, res, step, energy, "passed_through", history)
        e_old = energy
        energy, g, hp = yield Evaluate(p, u, True, True)
        if not (math.isfinite(energy) and np.isfinite(g).all()):
            return NewtonResult(False, it, math.inf, step, energy, "non_finite", history)
        res = p.residual_norm(g)
        if not math.isfinite(res):
            return NewtonResult(False, it, math.inf, step, energy, "non_finite", history)
        history.append(res)
        # Adapt the shift like a trust region (Nocedal & Wright Alg. 4.1 with the
        # Levenberg-Marquardt step): a step that had to be cut, or whose actual decrease is
        # a small part of the quadratic model's, means the model is trusted too far: damp
        # more; a full step that the model predicted well lets the shift decay to zero.
        # Below the energy's round-off the actual decrease is noise: the ratio then says
        # nothing about the model, and must not raise the shift (it did, without end).
        # The actual decrease is the line search's (e_trial), evaluated with the frames the
        # model was made with: accepting the step carries the frames on, which can change
        # the energy of a level whose sections turn with them (the reference twist, held
        # within an iteration), and that change says nothing about the model either.
        unjudged = predicted <= roundoff
        ratio = (e_old - e_trial) / predicted if predicted > 0 and not unjudged else 1.0
        if alpha < 0.5 or ratio < 0.25:
            mu = max(4.0 * mu, opt.shift_trust)
        elif alpha == 1.0 and ratio > 0.75:
            mu = 0.0 if mu <= opt.shift_trust else mu / 4.0
        if res <= tol:
            return NewtonResult(True, it, res, step, energy, "converged", history)
        # A tiny step that still cut the residual (a small correction, e.g. under the
        # stiff inertia of a short time step) is progress; one that did not is stagnation.
        if step <= opt.step_tol and res > opt.stall_factor * history[-2]:
            return NewtonResult(False, it, res, step, energy, "stagnated", history)
        # A run of unjudged steps that does not halve the residual (stall_factor) is blind.
        if not unjudged or res <= opt.stall_factor * blind_ref:
            blind, blind_ref = 0, res
        else:
            blind += 1
        best.append(min(best[-1], res))
        energies.append(energy)
        if _stalled(best, energies, opt, p.energy_roundoff()) or (
                opt.blind_iterations and blind >= opt.blind_iterations):
            return NewtonResult(False, it, res, step, energy, "stalled", history)
    return NewtonResult(False, opt.max_iterations, res, step, energy, "max_iterations", history)


def _stalled(best: list[float], energies: list[float], opt: NewtonOptions,
             roundoff: float) -> bool:
    """No progress over the last ``stall_iterations`` iterations (see NewtonOptions)."""
    w = opt.stall_iterations
    if w == 0 or len(best) <= w:
        return False
    if best[-1] < opt.stall_factor * best[-1 - w]:
        return False
    return (opt.stall_on_residual
            or energies[-1 - w] - energies[-1] <= opt.stall_roundoffs * roundoff)


def _raised(mu: float, opt: NewtonOptions, indefinite: bool) -> float:
    """The shift's next rung after ``mu`` failed: ``shift_initial``, then ten times the
    last; after a refusal for a negative eigenvalue (``indefinite``) the first rung at or
    above ``shift_inertia`` (the same values the ladder passes through, without the
    factorizations below)."""
    mu = opt.shift_initial if mu == 0.0 else mu * 10.0
    while indefinite and mu < opt.shift_inertia:
        mu *= 10.0
    return mu


def _acceptable(d: np.ndarray, g: np.ndarray, hd: np.ndarray, mu: float,
                diag: np.ndarray) -> bool:
    # A descent direction along which the shifted model (the one the step minimises) has
    # positive curvature; otherwise that model is not positive definite there and the shift
    # must grow. The unshifted Hessian may stay indefinite (a loose knot is floppy): with
    # the shift the step is a damped descent step, and the line search judges it.
    slope = float(g @ d)
    curv = float(d @ hd) + mu * float(np.sum(diag * d * d))
    return slope < 0.0 and curv > 0.0
