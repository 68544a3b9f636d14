"""Quasi-static Newton solver for a nearly incompressible solid with barrier contact.

The unknowns are the displacements u [m] of one FElupe field (all bodies in one mesh);
displacement control moves the prescribed dofs with a load parameter t. The total energy

    Pi(u) = Psi_solid(u) + U_barrier(u) - f(t) . u

minus the work of dead loads f(t) (``external``; zero where all loads are prescribed
displacements) is minimised at each load by
an own Newton loop, because the barrier needs what FElupe's ``newtonraphson`` does not
give (with a CCD cap inside it, it stalls at first contact):

- predictor: the tangent step of the prescribed increment (K_ff du_f = -r_f - K_fD du_D),
  cut back by continuous collision detection so that no surface passes through another;
  the load advances by the fraction taken, and cut predictors follow each other;
- corrector: Newton steps at that load, each capped by CCD and then halved until the
  total energy decreases enough (Armijo), the barrier Hessian projected to positive
  semi-definite far from the solution (it is indefinite) and exact near it
  (IPC: Li et al., ACM TOG 39, 2020, Algorithm 1).

Psi_solid is the mean-dilatation (Q1/P0) energy of FElupe's
``SolidBodyNearlyIncompressible``, sum_c [ int psi_iso(F) dV + K V_c / 2 (v_c / V_c - 1)^2 ]
(Bonet, Gil & Wood 2016, sec. 8.6.5); FElupe's residual is its exact gradient whatever
the condensed pressure, and its tangent is the exact Hessian once the condensed pressure
is set to K (v / V - 1), which :meth:`BarrierProblem.assemble` does.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from .barrier import BarrierContact
from .linsolve import SymmetricSolver, default_solver


class BarrierNewtonFailure(RuntimeError):
    """A load increment did not converge (its message says where)."""


ARMIJO: float = 1e-4
"""Sufficient-decrease constant of the line search (Nocedal & Wright 2006, eq. 3.4)."""


@dataclass
class BarrierProblem:
    """Solid ``solid`` on ``field`` with barrier ``contact``, prescribed dofs ``fixed``.

    ``fixed`` is a boolean mask over the dofs (point-major); ``prescribed(t)`` returns the
    displacement [m] of every dof at load t (only the fixed entries are used);
    ``log`` (optional) is called with one line per Newton iteration (progress);
    ``force_scale`` [N or N/m] sets the floor of the convergence test: the residual is
    compared with ``tol`` times the larger of the reaction and ``1e-4 force_scale``, far
    below FElupe's default absolute 1e-3 N, which stops soft-contact iterations before the
    patch has formed. ``external(t)`` (optional) returns the dead load [N] on every dof at
    load t (force control: the load parameter is then a force level, and the applied
    load's norm joins the reaction in the convergence scale); ``linear_solver`` names the
    sparse solver (:mod:`tightknot.fem.linsolve`).
    """

    field: Any
    solid: Any
    contact: BarrierContact
    fixed: np.ndarray
    prescribed: Callable[[float], np.ndarray]
    force_scale: float
    tol: float = 1e-8
    max_iterations: int = 200
    project_above: float = 1e-3
    iterations: list[int] = field(default_factory=list)
    load: float = 0.0
    log: Callable[[str], None] | None = None
    intermediate_tol: float = 1e-4
    external: Callable[[float], np.ndarray] | None = None
    linear_solver: str = field(default_factory=default_solver)
    _linear: SymmetricSolver | None = field(default=None, init=False, repr=False,
                                            compare=False)

    @property
    def u(self) -> np.ndarray:
        """Current displacements [m], flat point-major view into the field."""
        return self.field[0].values.reshape(-1)

    def _set(self, u: np.ndarray) -> None:
        self.field[0].values[:] = u.reshape(self.field[0].values.shape)

    def _cell_volumes(self) -> tuple[np.ndarray, np.ndarray]:
        """Deformed and reference cell volumes v, V [m^3 or m^2]."""
        dv = self.field.region.dV
        det = np.linalg.det(self.field.extract()[0].T).T  # (q, c)
        return (det * dv).sum(axis=0), dv.sum(axis=0)

    def solid_energy(self) -> float:
        """Psi_solid [J or J/m] of the current displacements (module docstring)."""
        solid = self.solid
        f = self.field.extract()[0]
        w = solid.umat.function([f, solid.results.statevars])[0]
        v, vol = self._cell_volumes()
        iso = float((w * self.field.region.dV).sum())
        return iso + float(0.5 * solid.bulk * (vol * (v / vol - 1.0) ** 2).sum())

    def energy(self) -> float:
        """Total energy Pi [J or J/m]; inf where surfaces cross or elements invert."""
        # an over-long trial step can invert an element at a quadrature point while its
        # cell volume stays positive: check J there, before FElupe's J^(-2/3)
        if not np.all(np.linalg.det(self.field.extract()[0].T) > 0.0):
            return float("inf")
        barrier = self.contact.energy()
        if not np.isfinite(barrier):
            return float("inf")
        return self.solid_energy() + barrier - float(self._external(self.load) @ self.u)

    def _external(self, load: float) -> np.ndarray:
        """Dead load [N] on every dof at ``load`` (zeros without ``external``)."""
        if self.external is None:
            return np.zeros(self.fixed.size)
        return np.asarray(self.external(load), dtype=float)

    def assemble(self, project: bool) -> tuple[np.ndarray, sp.csr_matrix]:
        """Residual dPi/du [N] and tangent [N/m] at the current displacements."""
        r, k = self._assemble_solid()
        r = r + self.contact.gradient() - self._external(self.load)
        return r, (k + self.contact.hessian(project=project)).tocsr()

    def _set_state(self) -> None:
        """Set the solid's condensed fields to the current displacements."""
        solid = self.solid
        state = solid.results.state
        v, vol = self._cell_volumes()
        state.u[:] = self.field[0].values
        state.J[:] = v / vol
        state.p[:] = solid.bulk * (v / vol - 1.0)  # exact Hessian (module docstring)

    def _assemble_solid(self) -> tuple[np.ndarray, sp.csr_matrix]:
        self._set_state()
        r = np.asarray(self.solid.assemble.vector(self.field).todense()).ravel()
        return r, self.solid.assemble.matrix(self.field).tocsr()

    def residual(self) -> np.ndarray:
        """dPi/du [N or N/m] at the current displacements and load, over all dofs: at
        the prescribed dofs, the forces that the supports exert on the bodies."""
        self._set_state()
        r = np.asarray(self.solid.assemble.vector(self.field).todense()).ravel()
        return r + self.contact.gradient() - self._external(self.load)

    def _solve(self, k: sp.csr_matrix, rhs: np.ndarray) -> np.ndarray:
        free = ~self.fixed
        k_ff = k[free][:, free].tocsc()
        du = np.zeros(self.fixed.size)
        if self._linear is None or self._linear.requested != self.linear_solver:
            # one per problem: PARDISO's analysis is kept while the tangent's pattern stays
            self._linear = SymmetricSolver(self.linear_solver)
        du[free] = self._linear(k_ff, rhs)
        if not np.all(np.isfinite(du)):
            raise BarrierNewtonFailure("non-finite Newton step (singular tangent)")
        return du

    def _direction(self, r: np.ndarray, k_solid: sp.csr_matrix, project: bool) -> np.ndarray:
        """Newton direction; if it does not descend, the barrier Hessian is projected and
        then a growing multiple of the tangent's diagonal added (modified Newton,
        Nocedal & Wright 2006, sec. 3.4): the solid's own Hessian can be indefinite
        under the contact."""
        free = ~self.fixed
        k = k_solid + self.contact.hessian(project=project)
        du = self._solve(k, -r[free])
        if float(r @ du) < 0.0:
            return du
        if not project:
            k = k_solid + self.contact.hessian(project=True)
            du = self._solve(k, -r[free])
        diag = sp.diags(np.abs(k.diagonal()))
        shift = 1e-4
        while float(r @ du) >= 0.0:
            if shift > 1e2:
                raise BarrierNewtonFailure(f"no descent direction at load {self.load:.6g}")
            du = self._solve(k + shift * diag, -r[free])
            shift *= 10.0
        return du

    def _scale(self, r: np.ndarray) -> float:
        applied = float(np.linalg.norm(self._external(self.load)))
        return max(applied + float(np.linalg.norm(r[self.fixed])), 1e-4 * self.force_scale)

    def correct(self, tol: float | None = None) -> int:
        """Newton corrector at the current load to the relative residual ``tol`` (default
        ``self.tol``); return the number of iterations."""
        tol = self.tol if tol is None else tol
        free = ~self.fixed
        pi = self.energy()
        last_res = float("inf")
        for it in range(1, self.max_iterations + 1):
            r, k_solid = self._assemble_solid()
            r = r + self.contact.gradient() - self._external(self.load)
            res = float(np.linalg.norm(r[free]))
            scale = self._scale(r)
            if res <= tol * scale:
                return it - 1
            # round-off floor: the residual of the nearly incompressible solid stops
            # falling near 1e-8 of the reaction at the smallest loads; a residual that no
            # longer falls there is converged
            if res <= 1e3 * tol * scale and res >= 0.5 * last_res:
                return it - 1
            last_res = res
            if self.log is not None:
                self.log(f"load {self.load:.6g} iteration {it} residual {res:.3g} of "
                         f"{scale:.3g}")
            du = self._direction(r, k_solid, project=res >= self.project_above * scale)
            u0 = self.u.copy()
            alpha = min(1.0, self.contact.max_step(self.field[0].values, du.reshape(
                self.field[0].values.shape)))
            slope = float(r @ du)
            while True:
                self._set(u0 + alpha * du)
                trial = self.energy()
                # round-off floor: near the solution the decrease is below the energy's
                # last digits, where any step that does not raise Pi is taken
                if trial <= pi + ARMIJO * alpha * slope + 1e-14 * abs(pi):
                    break
                alpha *= 0.5
                if alpha < 1e-10:
                    self._set(u0)
                    raise BarrierNewtonFailure(
                        f"line search failed at load {self.load:.6g} (iteration {it}, "
                        f"residual {res:.3g} of {scale:.3g})")
            pi = trial
        raise BarrierNewtonFailure(f"no convergence in {self.max_iterations} iterations at "
                                   f"load {self.load:.6g}")

    def advance(self, target: float, max_predictors: int = 400) -> int:
        """Move the load from the current value to ``target``; return the number of
        linear solves (predictors and corrector iterations).

        Each predictor is a Newton step of the problem at ``target`` from the current
        state (the residual and the prescribed increment together), cut back by CCD; the
        load advances by the fraction taken, and a corrector follows. The correctors at
        intermediate loads stop at ``intermediate_tol`` (the next predictor starts from
        their state and its residual is in its right-hand side), the last one at ``tol``.
        """
        total = 0
        for _ in range(max_predictors):
            if self.load >= target:
                return total
            r, k = self.assemble(project=True)
            # the predictor solves for the load at the target: its dead load enters here
            r = r + self._external(self.load) - self._external(target)
            u0 = self.u.copy()
            du_d = np.where(self.fixed, self.prescribed(target) - u0, 0.0)
            free = ~self.fixed
            du = self._solve(k, -r[free] - (k @ du_d)[free]) + du_d
            step = min(1.0, self.contact.max_step(self.field[0].values,
                                                  du.reshape(self.field[0].values.shape)))
            if step <= 0.0:
                raise BarrierNewtonFailure(f"no collision-free predictor at load "
                                           f"{self.load:.6g}")
            while True:
                new_load = target if step >= 1.0 else self.load + step * (target - self.load)
                # the fixed dofs take their exact values at the new load
                self._set(np.where(self.fixed, self.prescribed(new_load), u0 + step * du))
                if np.isfinite(self.energy()):
                    break
                step *= 0.5  # an inverted element: shorten the predictor
                if step < 1e-8:
                    raise BarrierNewtonFailure(f"predictor inverts elements at load "
                                               f"{self.load:.6g}")
            self.load = new_load
            total += 1
            total += self.correct(self.tol if self.load >= target else self.intermediate_tol)
        raise BarrierNewtonFailure(f"load {target:.6g} not reached in {max_predictors} "
                                   "predictor steps")

    def run(self, loads: np.ndarray, measure: Callable[[float], dict[str, Any]]
            ) -> list[dict[str, Any]]:
        """Step through the increasing loads; return ``measure(load)`` at each."""
        rows = []
        for target in loads:
            with self.failures_as_newton():
                self.iterations.append(self.advance(float(target)))
            rows.append(measure(float(target)))
        return rows

    @contextmanager
    def failures_as_newton(self) -> Iterator[None]:
        """Report a failure inside the contact library (ipctk's RuntimeError, e.g. a PSD
        projection that fails on crossed surfaces, or its MemoryError from a CCD on a
        runaway step) as :class:`BarrierNewtonFailure`: a failed solve, not a bug."""
        try:
            yield
        except BarrierNewtonFailure:
            raise
        except (RuntimeError, MemoryError) as err:
            raise BarrierNewtonFailure(f"the contact library failed at load "
                                       f"{self.load:.6g}: {err}") from err
