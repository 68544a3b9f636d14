"""A deformable section between two rigid plates: the section modes against the FEM's squeeze.

The sectioned contact level (issue 18) gives each edge a section boundary

    r(theta) = R + sum_n a_n cos n theta          (:mod:`tightknot.contact.section_modes`)

with the plane-strain mode energy W_n = (1/2) k_n a_n^2 and the mean radius R fixed by the
area (Parseval). Before that section meets another rod, it has to meet the simplest partner:
this module presses it between two rigid frictionless plates at y = +-(D0/2 - w), the FEM's
``squeeze`` scene (:mod:`tightknot.fem.scenes.squeeze`, plane strain), and finds the modes
that minimise

    E(a) = sum_n (1/2) k_n a_n^2 + 2 int (kappa / 2) max(0, y(theta) - h)^2 R0 dtheta,

y(theta) = r(theta) cos theta the height of the boundary point at angle theta from the
plate normal, h = R0 - w, the integral over the upper half (the factor 2: both plates).
The plates' penalty kappa is a numerical device, not physics: it is stiff enough that the
penetration stays below a hundredth of the smallest approach asked for (``penalty_factor``).
By the double symmetry only even n carry the squeeze. The force on one plate per unit length
is F = int kappa max(0, y - h) R0 dtheta, the pressure p = kappa max(0, y - h), and the
contact half-width b the |x| = r sin theta where y - h changes sign.

This is the section's response with no rod around it (plane strain: no axial spread), which
is what the FEM's plane-strain squeeze measures; how many modes the contact width needs is
the question it answers (docs/sectioned_level.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from tightknot.contact.section_modes import mode_stiffness

#: Plate penalty kappa = PENALTY_FACTOR * E / D0 [Pa/m]: at a peak pressure of E/2 the plates
#: are entered by 5e-4 D0, a fiftieth of the smallest approach the FEM scene takes (0.026 D0).
PENALTY_FACTOR = 1000.0
#: Boundary samples over the upper half of the section (spacing 0.0015 D0 along the boundary,
#: a hundredth of the shortest wavelength of N = 24).
SAMPLES = 2048
#: Penetration [D0] over which the penalty's stiffness rises from 0 to kappa: a fifth of the
#: penetration at a pressure of E/2, so the pressure is that of the plain penalty beyond it.
PENALTY_ONSET = 1e-4
#: Converged when every generalised force dE/da_n is below this [E D0]: 1e-10 of the plate
#: force at the smallest approach solved for (about 0.01 E D0 at w = 0.0125 D0).
RESIDUAL_TOL = 1e-12
#: Newton iterations before a solve is declared failed.
MAX_ITERATIONS = 100


def rounded_penalty(pen: NDArray, kappa: float, onset: float) -> tuple[NDArray, NDArray,
                                                                         NDArray]:
    """Penalty per unit boundary length phi(g) of the penetration g [D0] and its first two
    derivatives: kappa g^2 / 2 with the first ``onset`` of penetration rounded into a cubic
    (kappa g^3 / (6 onset)), so that the Hessian is continuous where a sample enters contact
    and Newton converges there."""
    g = np.maximum(pen, 0.0)
    low = g < onset
    phi = np.where(low, kappa * g**3 / (6.0 * onset),
                   kappa * (0.5 * g**2 - 0.5 * onset * g + onset**2 / 6.0))
    dphi = np.where(low, kappa * g**2 / (2.0 * onset), kappa * (g - 0.5 * onset))
    d2phi = np.where(low, kappa * g / onset, kappa)
    return phi, dphi, d2phi


def shifted_cholesky_step(hess: NDArray, g: NDArray, shift_fraction: float) -> NDArray:
    """-H^-1 g, H shifted by a multiple of the identity (doubling from ``shift_fraction`` of
    its largest diagonal entry) until a Cholesky factorisation exists: the shrinking mean
    radius of a section can make the Hessian indefinite."""
    shift = 0.0
    while True:
        try:
            chol = np.linalg.cholesky(hess + shift * np.eye(len(g)))
            return -np.linalg.solve(chol.T, np.linalg.solve(chol, g))
        except np.linalg.LinAlgError:
            shift = max(2.0 * shift, shift_fraction * float(np.max(np.diag(hess))))


def minimise(energy: Callable[[NDArray], tuple[float, NDArray, NDArray]], u0: NDArray,
             step: Callable[[NDArray, NDArray], NDArray], tol: float, max_iterations: int,
             what: str) -> tuple[NDArray, int]:
    """Newton from ``u0`` on ``energy`` (value, gradient, Hessian) with the direction
    ``step(hess, g)``, backtracking on the energy, or on the residual where the energy
    change is below its round-off; converged when every generalised force is below ``tol``.
    Returns the minimiser and the iterations; raises FloatingPointError naming ``what``."""
    u = np.asarray(u0, dtype=float).copy()
    e, g, hess = energy(u)
    for it in range(max_iterations):
        if float(np.max(np.abs(g))) <= tol:
            return u, it
        d = step(hess, g)
        alpha = 1.0
        while alpha > 1e-12:
            e1, g1, h1 = energy(u + alpha * d)
            tiny = abs(e1 - e) <= 1e-13 * max(abs(e), 1e-30)
            if e1 <= e + 1e-4 * alpha * float(g @ d) or (
                    tiny and np.max(np.abs(g1)) < np.max(np.abs(g))):
                break
            alpha *= 0.5
        else:
            break
        u, e, g, hess = u + alpha * d, e1, g1, h1
    raise FloatingPointError(f"{what} did not converge (largest generalised force "
                             f"{float(np.max(np.abs(g))):.2e} after Newton)")


@dataclass
class SqueezeState:
    """The section at one plate approach.

    Attributes:
        w_over_d0: approach of each plate w / D0.
        modes: mode numbers n (even, 2..N).
        amplitudes_over_d0: a_n / D0 of those modes.
        mean_radius_over_d0: R / D0 (the area kept, Parseval).
        force_per_length_over_e_d0: force on one plate per unit length F / (E D0).
        half_width_over_d0: contact half-width b / D0 (0 without contact).
        contact_fraction_side: 2 b over the deformed perimeter (the FEM scene's key).
        peak_pressure_over_e: largest plate pressure p / E.
        max_penetration_over_d0: deepest penalty penetration / D0 (a check on kappa).
        iterations: Newton iterations of the minimisation.
    """

    w_over_d0: float
    modes: list[int]
    amplitudes_over_d0: list[float]
    mean_radius_over_d0: float
    force_per_length_over_e_d0: float
    half_width_over_d0: float
    contact_fraction_side: float
    peak_pressure_over_e: float
    max_penetration_over_d0: float
    iterations: int


class SectionSqueeze:
    """The modes n = 2, 4, ..., ``max_mode`` of a section of diameter D0 = 1 and E = 1 (the
    results are in D0 and E units) between two plates (module docstring)."""

    def __init__(self, max_mode: int = 8, samples: int = SAMPLES,
                 penalty_factor: float = PENALTY_FACTOR) -> None:
        if int(max_mode) != max_mode or max_mode < 2:
            raise ValueError(f"max_mode must be an integer >= 2, got {max_mode}")
        if samples < 64:
            raise ValueError(f"samples must be >= 64, got {samples}")
        if not penalty_factor > 0.0:
            raise ValueError(f"penalty_factor must be > 0, got {penalty_factor}")
        self.modes = list(range(2, int(max_mode) + 1, 2))
        self.r0 = 0.5
        self.k = np.array([mode_stiffness(n, 1.0) for n in self.modes])
        dtheta = math.pi / samples
        self.theta = -0.5 * math.pi + dtheta * (np.arange(samples) + 0.5)  # midpoints
        self.cos_t = np.cos(self.theta)
        self.basis = np.cos(np.outer(self.theta, self.modes))  # (samples, modes)
        self.weight = self.r0 * dtheta  # arc length of the undeformed boundary per sample
        self.kappa = penalty_factor / (2.0 * self.r0)
        self.onset = PENALTY_ONSET

    def _radius(self, a: NDArray[np.float64]) -> tuple[float, NDArray, NDArray]:
        """R and its gradient and Hessian in a: R = sqrt(R0^2 - sum a^2 / 2)."""
        rest = self.r0**2 - 0.5 * float(a @ a)
        if rest <= 0.0:
            raise FloatingPointError("the modes hold more area than the section")
        r = math.sqrt(rest)
        grad = -a / (2.0 * r)
        hess = -np.eye(len(a)) / (2.0 * r) - np.outer(a, a) / (4.0 * r**3)
        return r, grad, hess

    def _gap(self, a: NDArray, h: float) -> tuple[NDArray, NDArray, NDArray]:
        """Height above the plate y - h per sample, dy/da and R's Hessian."""
        r, dr, d2r = self._radius(a)
        y = (r + self.basis @ a) * self.cos_t
        dy = (self.basis + dr[None, :]) * self.cos_t[:, None]
        return y - h, dy, d2r

    def energy(self, a: NDArray, w: float) -> tuple[float, NDArray, NDArray]:
        """Energy per unit length E(a) [E D0^2 units], its gradient and Hessian (infinite
        where the modes alone hold more area than the section, so a trial step there is
        refused)."""
        if 0.5 * float(a @ a) >= self.r0**2:
            return math.inf, np.zeros_like(a), np.eye(len(a))
        pen, dy, d2r = self._gap(a, self.r0 - w)
        phi, dphi, d2phi = self._penalty(pen)
        c = 2.0 * self.weight  # both plates
        e = 0.5 * float(self.k @ a**2) + c * float(np.sum(phi))
        g = self.k * a + c * (dy.T @ dphi)
        hess = (np.diag(self.k) + c * ((dy * d2phi[:, None]).T @ dy)
                + c * float(dphi @ self.cos_t) * d2r)
        return e, g, hess

    def _penalty(self, pen: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        return rounded_penalty(pen, self.kappa, self.onset)

    def solve(self, w_over_d0: float, start: NDArray | None = None) -> tuple[SqueezeState,
                                                                          NDArray]:
        """The section at plate approach w = ``w_over_d0`` D0 (from ``start``, the amplitudes
        of a nearby approach, or the undeformed circle); returns the state and the
        amplitudes."""
        if not 0.0 <= w_over_d0 < 0.5:
            raise ValueError(f"w_over_d0 must be in [0, 0.5), got {w_over_d0}")
        a0 = np.zeros(len(self.modes)) if start is None else start
        a, it = minimise(lambda a: self.energy(a, w_over_d0), a0,
                         lambda h, g: shifted_cholesky_step(h, g, 1e-6), RESIDUAL_TOL,
                         MAX_ITERATIONS, f"section squeeze at w = {w_over_d0} D0")
        return self._measure(a, w_over_d0, it), a

    def _measure(self, a: NDArray, w: float, iterations: int) -> SqueezeState:
        pen, _, _ = self._gap(a, self.r0 - w)
        p = self._penalty(pen)[1]
        force = float(np.sum(p) * self.weight)
        r, _, _ = self._radius(a)
        rad = r + self.basis @ a
        x = rad * np.sin(self.theta)
        half = 0.0
        right = np.flatnonzero((self.theta > 0.0) & (pen > 0.0))
        if right.size:
            i = int(right[-1])
            half = float(x[i])
            if i + 1 < len(x):
                # the gap is linear between the last sample in contact and the next one
                u = pen[i] / (pen[i] - pen[i + 1])
                half = float(x[i] + u * (x[i + 1] - x[i]))
        # the whole boundary by symmetry: 2 x the upper half's length
        xy = np.stack([x, rad * self.cos_t], axis=1)
        half_length = float(np.sum(np.linalg.norm(np.diff(xy, axis=0), axis=1)))
        perimeter = 2.0 * (half_length + abs(xy[0, 1]) + abs(xy[-1, 1]))  # ends to y = 0
        return SqueezeState(
            w_over_d0=float(w), modes=list(self.modes),
            amplitudes_over_d0=[float(v) for v in a], mean_radius_over_d0=r,
            force_per_length_over_e_d0=force, half_width_over_d0=half,
            contact_fraction_side=2.0 * half / perimeter,
            peak_pressure_over_e=float(p.max()),
            max_penetration_over_d0=float(max(pen.max(), 0.0)), iterations=iterations)

    def path(self, w_over_d0: list[float]) -> list[SqueezeState]:
        """The section along increasing approaches, each solve starting from the last."""
        out, a = [], None
        for w in w_over_d0:
            state, a = self.solve(w, a)
            out.append(state)
        return out
