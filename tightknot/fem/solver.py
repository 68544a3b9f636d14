"""Quasi-static Newton solver for a nearly incompressible solid with rigid penalty contact.

Displacement control: every load parameter moves the rigid surfaces (all Dirichlet
conditions are homogeneous symmetry or end conditions), Newton's method solves for the
displacements, and a failed increment is cut back (halved) from the last checkpoint.
The sparse symmetric system is solved by :class:`tightknot.fem.linsolve.SymmetricSolver`
(MKL PARDISO where installed, else SuperLU with diagonal pivoting off and the symmetric
mode on).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import scipy.sparse as sp

from .contact import PenaltyContact
from .linsolve import SymmetricSolver


class NewtonFailure(RuntimeError):
    """An increment did not converge even after the allowed cutbacks."""


@dataclass
class Problem:
    """A solid body, its rigid contacts and its fixed (zero) degrees of freedom.

    ``field`` is the FElupe ``FieldContainer`` (displacement first), ``solid`` the FElupe
    solid body, ``fixed`` a boolean mask over the dofs (point-major: point * dim + axis),
    ``force_scale`` [N or N/m] a force used for the relative convergence test,
    ``external`` [N] an optional dead (fixed-direction) load vector over the dofs, set by a
    force-controlled scene's ``apply`` (the residual is internal + contact - external),
    ``max_backtracks`` how many times a Newton correction that inverts elements is halved
    before the increment fails (0: fail at once, the behaviour the calibrated scenes had).
    """

    field: Any
    solid: Any
    contacts: list[PenaltyContact]
    fixed: np.ndarray
    force_scale: float
    iterations: list[int] = field(default_factory=list)
    external: np.ndarray | None = None
    max_backtracks: int = 0
    _linear: SymmetricSolver | None = field(default=None, init=False, repr=False,
                                            compare=False)

    @property
    def mesh(self) -> Any:
        """The FElupe mesh of the solid."""
        return self.field.region.mesh

    @property
    def dim(self) -> int:
        """Number of displacement components per point."""
        return int(self.field[0].values.shape[1])

    def positions(self) -> np.ndarray:
        """Current point coordinates [m], shape (npoints, dim)."""
        return self.mesh.points + self.field[0].values

    def assemble(self) -> tuple[np.ndarray, sp.csr_matrix]:
        """Residual vector [N] and tangent matrix [N/m] of solid plus contacts."""
        solid = self.solid
        r = np.asarray(solid.assemble.vector(self.field).todense()).ravel()
        if self.external is not None:
            r = r - self.external  # dead load: no stiffness contribution
        k = solid.assemble.matrix().tocoo()
        rows, cols, data = [k.row], [k.col], [k.data]
        x = self.positions()
        dim = self.dim
        for c in self.contacts:
            force, blocks, _, _ = c.evaluate(x[c.points])
            dof = c.points[:, None] * dim + np.arange(dim)[None, :]  # (m, dim)
            np.add.at(r, dof.ravel(), force.ravel())
            rows.append(np.repeat(dof, dim, axis=1).ravel())
            cols.append(np.tile(dof, (1, dim)).ravel())
            data.append(blocks.ravel())
        n = r.size
        matrix = sp.coo_matrix(
            (np.concatenate(data), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
        ).tocsr()
        return r, matrix

    def newton(self, tol: float = 1e-8, maxiter: int = 30) -> int:
        """Solve the current increment in place; return the number of iterations.

        Converged when the free residual norm is below ``tol`` times the larger of the
        reaction norm and 1e-3 ``force_scale`` and the last correction is below 1e-9 of
        the mesh size (both: a small residual alone can hide a stalled, tiny-penalty step).
        """
        free = ~self.fixed
        size = np.ptp(self.mesh.points, axis=0).max()
        checkpoint: dict | None = None
        du = np.zeros(self.fixed.size)
        backtracks = 0
        for it in range(1, maxiter + 1):
            # with backtracking, an inverted trial element (J <= 0 in FElupe's J^(-2/3)) is
            # an expected event handled below, not a warning for the user
            with np.errstate(invalid="ignore" if self.max_backtracks else "warn"):
                r, k = self.assemble()
            r_free = r[free]
            if not np.all(np.isfinite(r_free)):
                # An over-long correction inverted elements (J <= 0): go back to the last
                # iterate (FElupe's condensed p, J-bar fields included) and take half of it.
                # Force-controlled scenes meet this when a tail swings; displacement-
                # controlled ones converge without it.
                if checkpoint is None or backtracks >= self.max_backtracks:
                    raise NewtonFailure(f"non-finite residual (iteration {it}, "
                                        f"{backtracks} backtracks)")
                self.solid.restore(checkpoint)
                du *= 0.5
                self.field[0].values[:] += du.reshape(-1, self.dim)
                backtracks += 1
                continue
            applied = 0.0 if self.external is None else float(np.linalg.norm(self.external))
            reaction = applied + np.linalg.norm(r[self.fixed]) + sum(
                np.linalg.norm(c.evaluate(self.positions()[c.points])[0]) for c in self.contacts
            )
            scale = max(reaction, 1e-3 * self.force_scale)
            k_free = k[free][:, free].tocsc()
            du = np.zeros_like(r)
            if self._linear is None:  # one per problem: its analysis is kept between solves
                self._linear = SymmetricSolver()
            du[free] = -self._linear(k_free, r_free)
            if not np.all(np.isfinite(du)):
                raise NewtonFailure("non-finite correction")
            if self.max_backtracks > 0:
                checkpoint = self.solid.checkpoint()
            self.field[0].values[:] += du.reshape(-1, self.dim)
            if np.linalg.norm(r_free) <= tol * scale and np.abs(du).max() <= 1e-9 * size:
                return it
        raise NewtonFailure(f"no convergence in {maxiter} iterations")

    def run(self, loads: np.ndarray, apply: Callable[[float], None],
            measure: Callable[[float], dict[str, Any]], max_cutbacks: int = 6) -> list[dict]:
        """Step through the load parameters ``loads`` (increasing), return measurements.

        ``apply(load)`` moves the rigid surfaces; ``measure(load)`` returns a dict of
        outputs of the converged state. A failed increment is halved up to
        ``max_cutbacks`` times (restarting from the last converged checkpoint).
        """
        results = []
        current = 0.0
        for target in loads:
            cutbacks = 0
            while current < target:
                trial = target if cutbacks == 0 else current + (target - current) / 2**cutbacks
                checkpoint = self.solid.checkpoint()
                apply(trial)
                try:
                    self.iterations.append(self.newton())
                    current = trial
                    if current < target:
                        cutbacks = max(cutbacks - 1, 0)
                except (NewtonFailure, RuntimeError, FloatingPointError) as err:
                    self.solid.restore(checkpoint)
                    cutbacks += 1
                    if cutbacks > max_cutbacks:
                        raise NewtonFailure(
                            f"increment to load {target:.4g} failed: {err}"
                        ) from err
            results.append(measure(target))
        return results
