"""The section as a field along a straight rod, pressed by rigid bodies: the sectioned level's
physics where the FEM's indent scene can judge it.

The sectioned contact level (issue 18, docs/sectioned_level.md) gives each edge of a rod the
section boundary r(theta) = R + sum_n a_n cos n theta (:mod:`tightknot.contact.section_modes`).
Here the rod is straight along e_z, as in the FEM's ``indent`` and ``squeeze`` scenes, whose
double symmetry (x -> -x, y -> -y) keeps only the even cosine modes and keeps the centerline
on the axis; what is left is the section's field along the rod and the rod's axial stretch,

    E = sum_edges h [ (1/2) E A0 (lambda - 1)^2 + sum_n (1/2) k_n a_n^2 ]
        + sum_neighbours (1/2) g_n (a_n,i+1 - a_n,i)^2 / h
        + 2 sum_edges sum_samples phi(penetration) R0 dtheta h,

- the stretch lambda of each edge from its two vertices (axial dofs Z_i);
- the plane-strain mode stiffness k_n = 2 pi mu (n^2 - 1) / n (mu = E/3, closed form);
- the axial gradient stiffness g_n = k_n l_n^2 with the decay lengths l_n of
  :func:`tightknot.fem.section_modes.rod_mode_decay` (:data:`DECAY_LENGTH_OVER_D0`);
- the mean radius from incompressibility, R = sqrt(R0^2 / lambda - sum a_n^2 / 2) (Parseval):
  a section pressed from outside pushes lambda up, which is the Poisson effect of an
  incompressible rod exactly to first order (a uniform pressure q gives lambda - 1 = q / E);
- both rigid bodies (the factor 2: the second one by symmetry) as a penalty of the
  penetration of sampled boundary points, rounded as in
  :mod:`tightknot.contact.section_squeeze`.

Units: D0 = 1 and E = 1; forces come out in E D0^2. Only the half rod z >= 0 is modelled
(z = 0 a symmetry plane, the far end free); the force on one body is that of the whole rod.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import cho_solve_banded, cholesky_banded

from tightknot.contact.section_modes import mode_stiffness

#: Decay length l_n / D0 of mode n along a 3D rod of the FEM's solid, fine mesh
#: (docs/sectioned_level.md, ``rod_mode_decay``). Modes above 4 were not measured: they take
#: l_4 * 4 / n, the 1/n of a surface wave (its wavelength pi D0 / n), stated in the results.
DECAY_LENGTH_OVER_D0: dict[int, float] = {2: 0.183, 3: 0.110, 4: 0.077}
#: Plate/indenter penalty kappa = PENALTY_FACTOR * E / D0 and the rounding of its onset [D0],
#: as in section_squeeze (a penetration below a fiftieth of the approaches compared).
PENALTY_FACTOR = 1000.0
PENALTY_ONSET = 1e-4
#: Converged when every generalised force is below this [E D0^2].
RESIDUAL_TOL = 1e-11
MAX_ITERATIONS = 100


def decay_length(n: int) -> tuple[float, bool]:
    """Decay length l_n / D0 of mode ``n`` and whether it was measured (else extrapolated)."""
    if n in DECAY_LENGTH_OVER_D0:
        return DECAY_LENGTH_OVER_D0[n], True
    return DECAY_LENGTH_OVER_D0[4] * 4.0 / n, False


@dataclass
class FieldState:
    """The rod at one approach of the bodies.

    Attributes:
        w_over_d0: approach of each body w / D0.
        force_over_e_d0sq: force on one body F / (E D0^2) (the whole rod).
        semi_axis_axial_over_d0: the contact patch's half length along the rod.
        semi_axis_transverse_over_d0: its half width across (in the mid section).
        contact_fraction_mid: the mid section's perimeter in contact on one side.
        peak_pressure_over_e: largest penalty pressure p / E.
        area_ratio_mid: A / A0 of the mid section (1 / lambda).
        amplitudes_mid_over_d0: the mid section's a_n / D0.
        iterations: Newton iterations.
    """

    w_over_d0: float
    force_over_e_d0sq: float
    semi_axis_axial_over_d0: float
    semi_axis_transverse_over_d0: float
    contact_fraction_mid: float
    peak_pressure_over_e: float
    area_ratio_mid: float
    amplitudes_mid_over_d0: list[float]
    iterations: int


class StraightSectionedRod:
    """Half a straight rod of length ``half_length`` D0 in ``edges`` edges, section modes
    n = 2, 4, ..., ``max_mode``, pressed by ``body``: ``"cylinder"`` (the indent scene: a
    rigid cylinder of diameter D0 across the rod, axis along e_x at y = D0 - w) or
    ``"plates"`` (the squeeze: planes y = +-(D0/2 - w) along the whole rod)."""

    def __init__(self, body: str = "cylinder", max_mode: int = 8, half_length: float = 1.5,
                 edges: int = 75, samples: int = 512, gradient: bool = True) -> None:
        if body not in ("cylinder", "plates"):
            raise ValueError(f"body must be 'cylinder' or 'plates', got {body!r}")
        if int(max_mode) != max_mode or max_mode < 2:
            raise ValueError(f"max_mode must be an integer >= 2, got {max_mode}")
        if not half_length > 0.0 or edges < 2 or samples < 64:
            raise ValueError("half_length must be > 0, edges >= 2 and samples >= 64")
        self.body = body
        self.modes = list(range(2, int(max_mode) + 1, 2))
        self.extrapolated = [n for n in self.modes if not decay_length(n)[1]]
        self.r0 = 0.5
        self.a0 = math.pi * self.r0**2
        self.m = int(edges)
        self.h = half_length / edges
        nk = len(self.modes)
        self.k = np.array([mode_stiffness(n, 1.0) for n in self.modes])
        self.g = (self.k * np.array([decay_length(n)[0] ** 2 for n in self.modes])
                  if gradient else np.zeros(nk))
        dtheta = math.pi / samples
        self.theta = -0.5 * math.pi + dtheta * (np.arange(samples) + 0.5)
        self.cos_t = np.cos(self.theta)
        self.basis = np.cos(np.outer(self.theta, self.modes))  # (samples, modes)
        self.weight = self.r0 * dtheta * self.h  # undeformed surface per sample
        self.kappa = PENALTY_FACTOR / (2.0 * self.r0)
        # dofs edge by edge, (Z_i+1, a_i) for edge i (Z_0 = 0 on the symmetry plane), so
        # that the Hessian is banded: half-bandwidth 2 (1 + K) for K modes
        self.block = 1 + nk
        self.ndof = self.m * self.block
        self.bandwidth = 2 * self.block
        # each edge's local variables q = (lambda, z, a_1..a_K) are q = T (Z_i, Z_i+1, a_i)
        self.transform = np.eye(2 + nk)
        self.transform[:2, :2] = [[-1.0 / self.h, 1.0 / self.h], [0.5, 0.5]]
        edge = np.arange(self.m)
        z_dof = np.stack([(edge - 1) * self.block, edge * self.block], axis=1)
        z_dof[0, 0] = -1  # Z_0 is fixed
        a_dof = edge[:, None] * self.block + 1 + np.arange(nk)[None, :]
        self.edge_dofs = np.concatenate([z_dof, a_dof], axis=1)  # (edges, 2 + nk)

    def split(self, u: NDArray) -> tuple[NDArray, NDArray]:
        """Vertex positions Z (with Z_0 = 0) and amplitudes a (edges x modes) of dofs ``u``
        (displacements: Z = rest + u)."""
        blocks = u.reshape(self.m, self.block)
        z = np.concatenate([[0.0], self.h * np.arange(1, self.m + 1) + blocks[:, 0]])
        return z, blocks[:, 1:]

    def _penalty(self, pen: NDArray) -> tuple[NDArray, NDArray, NDArray]:
        k, eps = self.kappa, PENALTY_ONSET
        g = np.maximum(pen, 0.0)
        low = g < eps
        phi = np.where(low, k * g**3 / (6.0 * eps), k * (0.5 * g**2 - 0.5 * eps * g + eps**2 / 6.0))
        dphi = np.where(low, k * g**2 / (2.0 * eps), k * (g - 0.5 * eps))
        d2phi = np.where(low, k * g / eps, k)
        return phi, dphi, d2phi

    def _contact(self, lam: NDArray, zc: NDArray, a: NDArray, w: float) -> dict[str, NDArray]:
        """Penetration of every sample of every edge (edges x samples), its derivatives in
        each edge's local variables q = (lambda, z, a) and the pieces of its second
        derivative (module docstring; y = r cos theta, r = R + sum a_n cos n theta)."""
        nk = a.shape[1]
        s = self.r0**2 / lam - 0.5 * np.sum(a * a, axis=1)
        big_r = np.sqrt(s)
        ds = np.concatenate([(-self.r0**2 / lam**2)[:, None], np.zeros((len(lam), 1)), -a],
                            axis=1)  # dS/dq per edge
        r = big_r[:, None] + a @ self.basis.T  # (edges, samples)
        y = r * self.cos_t[None, :]
        dr = np.repeat((ds / (2.0 * big_r[:, None]))[:, None, :], len(self.theta), axis=1)
        dr[:, :, 2:] += self.basis[None, :, :]
        dy = dr * self.cos_t[None, :, None]
        if self.body == "plates":
            pen = y - (self.r0 - w)
            zero = np.zeros_like(y)
            fy, fz, fyy, fyz, fzz = np.ones_like(y), zero, zero, zero, zero
            dpen_dc = np.ones_like(y)
        else:
            c = 2.0 * self.r0 - w
            zz = np.broadcast_to(zc[:, None], y.shape)
            d = np.sqrt((y - c) ** 2 + zz * zz)
            pen = self.r0 - d
            fy, fz = -(y - c) / d, -zz / d
            fyy, fyz, fzz = -(zz * zz) / d**3, (y - c) * zz / d**3, -((y - c) ** 2) / d**3
            dpen_dc = (c - y) / d  # the body's reaction along y per unit penalty force
        dpen = fy[:, :, None] * dy
        dpen[:, :, 1] += fz
        d2s = np.zeros((len(lam), 2 + nk, 2 + nk))
        d2s[:, 0, 0] = 2.0 * self.r0**2 / lam**3
        d2s[:, 2:, 2:] = -np.eye(nk)
        d2r = (d2s / (2.0 * big_r[:, None, None])
               - ds[:, :, None] * ds[:, None, :] / (4.0 * big_r[:, None, None] ** 3))
        return {"pen": pen, "dpen": dpen, "r": r, "y": y, "dy": dy, "fy": fy, "fyy": fyy,
                "fyz": fyz, "fzz": fzz, "d2r": d2r, "dpen_dc": dpen_dc}

    def energy(self, u: NDArray, w: float) -> tuple[float, NDArray, NDArray]:
        """E(u) [E D0^3 units: energy of the half rod], gradient and Hessian (infinite where
        a trial state has no mean radius or a reversed edge, so a line search refuses it)."""
        z_v, a = self.split(u)
        lam = np.diff(z_v) / self.h
        zc = 0.5 * (z_v[1:] + z_v[:-1])
        if np.any(lam <= 0.0) or np.any(self.r0**2 / lam - 0.5 * np.sum(a**2, axis=1) <= 0.0):
            return math.inf, np.zeros(self.ndof), np.eye(self.ndof)
        nk = len(self.modes)
        # stretch and section energies of each edge (per rest length h)
        e = self.h * float(np.sum(0.5 * self.a0 * (lam - 1.0) ** 2) + 0.5 * np.sum(self.k * a**2))
        ql = np.zeros((self.m, 2 + nk))
        hl = np.zeros((self.m, 2 + nk, 2 + nk))
        ql[:, 0] = self.h * self.a0 * (lam - 1.0)
        hl[:, 0, 0] = self.h * self.a0
        ql[:, 2:] = self.h * self.k * a
        hl[:, 2:, 2:] += self.h * np.diag(self.k)
        ct = self._contact(lam, zc, a, w)
        phi, dphi, d2phi = self._penalty(ct["pen"])
        c = 2.0 * self.weight  # both bodies
        e += c * float(np.sum(phi))
        dpen, dy = ct["dpen"], ct["dy"]
        ql += c * np.einsum("esq,es->eq", dpen, dphi)
        hl += c * np.einsum("esq,es,esp->eqp", dpen, d2phi, dpen)
        # phi' times the penetration's own second derivative
        hl += c * np.einsum("esq,es,esp->eqp", dy, dphi * ct["fyy"], dy)
        cross = c * np.einsum("esq,es->eq", dy, dphi * ct["fyz"])
        hl[:, :, 1] += cross
        hl[:, 1, :] += cross
        hl[:, 1, 1] += c * np.sum(dphi * ct["fzz"], axis=1)
        hl += c * np.sum(dphi * ct["fy"] * self.cos_t[None, :], axis=1)[:, None, None] * ct["d2r"]
        tr = self.transform
        gl = ql @ tr  # per edge, in (Z_i, Z_i+1, a_i)
        hu = np.einsum("qa,eqp,pb->eab", tr, hl, tr)
        dofs = self.edge_dofs
        keep = dofs >= 0
        grad = np.zeros(self.ndof)
        np.add.at(grad, dofs[keep], gl[keep])
        hess = np.zeros((self.ndof, self.ndof))
        pair = keep[:, :, None] & keep[:, None, :]
        rows = np.broadcast_to(dofs[:, :, None], hu.shape)[pair]
        cols = np.broadcast_to(dofs[:, None, :], hu.shape)[pair]
        np.add.at(hess, (rows, cols), hu[pair])
        # axial gradient of each mode between neighbouring edges (mirror edge at z = 0 equal)
        da = np.diff(a, axis=0)
        e += float(np.sum(0.5 * self.g * da**2)) / self.h
        f = self.g * da / self.h  # (edges - 1, modes)
        ga = np.zeros_like(a)
        ga[:-1] -= f
        ga[1:] += f
        idx = self.edge_dofs[:, 2:]
        grad[idx.ravel()] += ga.ravel()
        s = np.broadcast_to(self.g / self.h, (self.m - 1, nk))
        p_i, q_i = idx[:-1].ravel(), idx[1:].ravel()
        np.add.at(hess, (p_i, p_i), s.ravel())
        np.add.at(hess, (q_i, q_i), s.ravel())
        np.add.at(hess, (p_i, q_i), -s.ravel())
        np.add.at(hess, (q_i, p_i), -s.ravel())
        return e, grad, hess

    def solve(self, w: float, start: NDArray | None = None) -> tuple[FieldState, NDArray]:
        """Equilibrium at body approach ``w`` [D0] from ``start`` (dofs of a nearby approach)."""
        if not 0.0 <= w < 0.5:
            raise ValueError(f"w must be in [0, 0.5) D0, got {w}")
        u = np.zeros(self.ndof) if start is None else np.asarray(start, float).copy()
        e, g, hess = self.energy(u, w)
        for it in range(MAX_ITERATIONS):
            if float(np.max(np.abs(g))) <= RESIDUAL_TOL:
                return self._measure(u, w, it), u
            d = self._newton_step(hess, g)
            step = 1.0
            while step > 1e-12:
                e1, g1, h1 = self.energy(u + step * d, w)
                tiny = abs(e1 - e) <= 1e-13 * max(abs(e), 1e-30)
                if e1 <= e + 1e-4 * step * float(g @ d) or (
                        tiny and np.max(np.abs(g1)) < np.max(np.abs(g))):
                    break
                step *= 0.5
            else:
                break
            u, e, g, hess = u + step * d, e1, g1, h1
        raise FloatingPointError(f"sectioned rod at w = {w} D0 did not converge (largest "
                                 f"generalised force {float(np.max(np.abs(g))):.2e})")

    def _newton_step(self, hess: NDArray, g: NDArray) -> NDArray:
        """-H^-1 g by banded Cholesky, H shifted to positive definite where the shrinking mean
        radius makes it indefinite."""
        b = self.bandwidth
        n = self.ndof
        band = np.zeros((b + 1, n))  # upper form: band[b + i - j, j] = H[i, j]
        for k in range(b + 1):
            band[b - k, k:] = np.diagonal(hess, k)
        shift = 0.0
        while True:
            try:
                shifted = band.copy()
                shifted[b] += shift
                chol = cholesky_banded(shifted)
                return -cho_solve_banded((chol, False), g)
            except np.linalg.LinAlgError:
                shift = max(2.0 * shift, 1e-8 * float(np.max(band[b])))

    def _measure(self, u: NDArray, w: float, iterations: int) -> FieldState:
        z_v, a = self.split(u)
        lam = np.diff(z_v) / self.h
        zc = 0.5 * (z_v[1:] + z_v[:-1])
        ct = self._contact(lam, zc, a, w)
        pen = ct["pen"]
        p = self._penalty(pen)[1]
        # the body's reaction along y: the half rod's, twice for the other half
        force = 2.0 * float(np.sum(p * ct["dpen_dc"])) * self.weight
        touching = np.flatnonzero(np.any(pen > 0.0, axis=1))
        axial = float(zc[touching[-1]] + 0.5 * self.h) if touching.size else 0.0
        x = ct["r"][0] * np.sin(self.theta)
        inside = np.flatnonzero((self.theta > 0.0) & (pen[0] > 0.0))
        transverse = float(x[inside[-1]]) if inside.size else 0.0
        xy = np.stack([x, ct["y"][0]], axis=1)
        perim = 2.0 * (float(np.sum(np.linalg.norm(np.diff(xy, axis=0), axis=1)))
                       + abs(xy[0, 1]) + abs(xy[-1, 1]))
        return FieldState(
            w_over_d0=float(w), force_over_e_d0sq=force, semi_axis_axial_over_d0=axial,
            semi_axis_transverse_over_d0=transverse,
            contact_fraction_mid=2.0 * transverse / perim,
            peak_pressure_over_e=float(p.max()), area_ratio_mid=float(1.0 / lam[0]),
            amplitudes_mid_over_d0=[float(v) for v in a[0]], iterations=iterations)

    def path(self, ws: list[float]) -> list[FieldState]:
        """Equilibria along increasing approaches, each solve from the last."""
        out, u = [], None
        for w in ws:
            state, u = self.solve(w, u)
            out.append(state)
        return out
