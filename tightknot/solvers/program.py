"""Solver programs: algorithms written as coroutines of questions about a potential.

Every algorithm (the Newton loop, load continuation, proximal steps) and every load path
built on them (tying a knot, pulling it to a knot length) is a *program*: a generator that
yields its questions about a :class:`~tightknot.solvers.system.RodSystem` (an
:class:`Evaluate` of the energy, gradient and Hessian at a point, a :class:`StepBound` of
how far a step may go) and is sent the answers. Who answers decides how a program runs:
:meth:`Program.run` answers each question at once from the system it names (one rod), and
:func:`tightknot.solvers.lockstep.run_lockstep` collects the questions of many rods and
answers them together (one set of launches for a batch). The algorithm is written once.

Programs compose with ``yield from``: a load path runs a continuation by ``yield from
continuation(system, ...)``, which delegates every question to the caller's driver.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Generator
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Generic, TypeVar

import numpy as np

if TYPE_CHECKING:
    from tightknot.solvers.system import RodSystem

T = TypeVar("T")


@dataclass(frozen=True, eq=False)
class Evaluate:
    """Question: the total potential [J] of ``system`` at free dofs ``u``, with its
    free-dof gradient (``want_grad``) and Hessian (``want_hess``); the answer is the
    tuple of :meth:`tightknot.solvers.system.RodSystem.evaluate`."""

    system: RodSystem
    u: np.ndarray
    want_grad: bool = True
    want_hess: bool = True

    def answer(self) -> tuple:
        """The answer computed now, by the system alone."""
        return self.system.evaluate(self.u, self.want_grad, self.want_hess)


@dataclass(frozen=True, eq=False)
class StepBound:
    """Question: the largest fraction in (0, 1] of the step ``du`` from ``u`` that the
    system's terms allow (no passing through); the answer is a float."""

    system: RodSystem
    u: np.ndarray
    du: np.ndarray

    def answer(self) -> float:
        """The answer computed now, by the system alone."""
        return self.system.max_step(self.u, self.du)


Request = Evaluate | StepBound
#: The generator inside a program: yields requests, is sent their answers, returns T.
Coroutine = Generator[Request, Any, T]


class Program(Generic[T]):
    """A solver run not started yet. ``run()`` answers every question at once and
    returns the result; ``yield from program`` inside another program passes its
    questions on; a batch driver takes the coroutine (``iter(program)``)."""

    def __init__(self, coroutine: Coroutine[T], name: str) -> None:
        self._coroutine = coroutine
        self._name = name

    def __iter__(self) -> Coroutine[T]:
        return self._coroutine

    def run(self) -> T:
        """Run to the end, each question answered by the system that it names."""
        gen = self._coroutine
        answer: Any = None
        while True:
            try:
                question = gen.send(answer)
            except StopIteration as done:
                return done.value
            answer = question.answer()

    def __getattr__(self, attr: str) -> Any:
        # A result's attribute asked of the program itself: it was never run.
        raise AttributeError(f"{self._name}(...) returns a Program, which has no {attr!r}: "
                             f"call .run() for its result (e.g. {self._name}(...).run()"
                             f".{attr})")

    def __repr__(self) -> str:
        return f"<Program {self._name}: call .run()>"


def program(fn: Callable[..., Coroutine[T]]) -> Callable[..., Program[T]]:
    """Decorator: a generator function of requests becomes a function returning a
    :class:`Program`."""

    @functools.wraps(fn)
    def make(*args: Any, **kwargs: Any) -> Program[T]:
        return Program(fn(*args, **kwargs), fn.__name__)

    return make


def accept(system: RodSystem, u: np.ndarray) -> Coroutine[None]:
    """Make ``u`` the system's state; its frames come from the evaluation at ``u``, asked
    for first when the last one was elsewhere."""
    if not system.has_trial(u):
        yield Evaluate(system, u, False, False)
    system.accept(u)
