"""The contact radius thinned by each rod's mean stretch, with its exact chain rule.

Under tension a section thins, r = r0 lambda^-nu (incompressible: nu = 1/2). Taken with each
edge's own stretch, the contact energy lowers when the few edges under a crossing stretch,
so the contact pulls them apart: at the FEM cross-check's indent the rod carries 3.4 to 54
times the FEM's axial force at the crossing (docs/fem_crosscheck.md), and in a knot pulled
hard the crossing edges stretch far beyond the tails (2.9 against 1.34 in the 185 mm
trefoil at 18.5 N), thin, and let the knot's core collapse (docs/design_notes.md, contact).
Without friction the tension is nearly uniform along a rod (physics.md sec. 6: contact
forces are normal to it), and the study itself defines the reduced diameter from the rod's
mean stretch, D = D0 [1 - nu (L - L0)/L0] (physics.md sec. 2). Here every section of a rod
thins with that mean stretch s = L/L0 (L the rod's length, L0 its rest length):

    rho_e = r0_e s^-nu_e,   s = sum_e l_e / sum_e l0_e.

The pair kernel evaluates each pair at the given radii (its given-radius variants: no
derivative through the edge lengths) and returns, per pair p of edges (a, b), with
R = rho_a + rho_b, E_R = dE_p/dR, E_RR and gR_p = d(grad_x E_p)/dR. With f' = -nu rho/s,
f'' = nu (nu + 1) rho/s^2, dR_p/ds_r = f'_a [a in r] + f'_b [b in r] and grad s_r =
(1/L0_r) sum_e grad l_e, the chain rule gives the exact gradient and Hessian

    g = g_x + sum_r G_r grad s_r,                       G_r = sum_p E_R,p dR_p/ds_r,
    H = H_xx + sum_r G_r Hess s_r + U C U^T,
    U = [grad s_1 .. grad s_k, w_1 .. w_k],             w_r = sum_p gR_p dR_p/ds_r,
    C = [[S, I], [I, 0]],  S_rq = sum_p E_RR,p dR_p/ds_r dR_p/ds_q + delta_rq sum_p E_R,p
                                  (f''_a [a in r] + f''_b [b in r]).

Hess s_r = (1/L0_r) sum_e [[P, -P], [-P, P]]/l_e (P = I - t t^T) lies in the edges'
stretch blocks; the rest is dense over the rod but of rank 2 per rod in contact, which the
Newton solve takes by the Woodbury identity (:class:`tightknot.solvers.linear.LowRankHessian`).
"""

from __future__ import annotations

import numpy as np

from tightknot.rods.model import Model


class RodMeanRadius:
    """The contact radius of each section from its rod's mean stretch, and its chain rule.

    Args:
        model: the rods.
        poisson: nu of each edge [-] (the thinning exponent).
    """

    def __init__(self, model: Model, poisson: np.ndarray) -> None:
        self.model = model
        self.nu = np.asarray(poisson, dtype=np.float64)
        self.rod_count = len(model.rods)
        ev = model.edge_vertex.astype(np.int64)
        vd = model.vertex_dof.astype(np.int64)
        #: The 6 position dofs of each edge (its two vertices).
        self.edge_dofs = np.concatenate([vd[ev[:, 0]][:, None] + np.arange(3),
                                         vd[ev[:, 1]][:, None] + np.arange(3)], axis=1)

    def rod_stretch(self, x: np.ndarray, rest: np.ndarray) -> np.ndarray:
        """The mean stretch L/L0 of each rod [-] at positions ``x`` [m] and edge rest
        lengths ``rest`` [m]."""
        m = self.model
        ev = m.edge_vertex
        le = np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1)
        length = np.bincount(m.edge_rod, le, self.rod_count)
        return length / np.bincount(m.edge_rod, np.asarray(rest, dtype=np.float64),
                                    self.rod_count)

    def stretch(self, x: np.ndarray, rest: np.ndarray) -> np.ndarray:
        """The stretch that thins each edge's section: its rod's mean [-]."""
        return self.rod_stretch(x, rest)[self.model.edge_rod]

    def radii(self, x: np.ndarray, rest: np.ndarray) -> dict[str, np.ndarray]:
        """Unit tangents t, lengths l [m], radii rho [m], f' [m], f'' [m] of each edge, the
        rods' mean stretches s and rest lengths L0 [m]."""
        m = self.model
        ev = m.edge_vertex
        e = x[ev[:, 1]] - x[ev[:, 0]]
        le = np.linalg.norm(e, axis=1)
        rest = np.asarray(rest, dtype=np.float64)
        big_l0 = np.bincount(m.edge_rod, rest, self.rod_count)
        s = np.bincount(m.edge_rod, le, self.rod_count) / big_l0
        se = s[m.edge_rod]
        rho = m.edge_radius * se ** (-self.nu)
        return {"t": e / le[:, None], "l": le, "rho": rho, "s": s, "L0": big_l0,
                "f1": -self.nu * rho / se, "f2": self.nu * (self.nu + 1.0) * rho / se**2}

    def _pair_rates(self, geo: dict[str, np.ndarray], pairs: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Per pair side: dR/ds of its rod and d2R/ds2 (a, b), as (P,) arrays."""
        return (geo["f1"][pairs[:, 0]], geo["f1"][pairs[:, 1]], geo["f2"][pairs[:, 0]],
                geo["f2"][pairs[:, 1]])

    def gradient(self, geo: dict[str, np.ndarray], pairs: np.ndarray,
                 e_r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The gradient term sum_r G_r grad s_r over vertex positions (V, 3) [N] and G per
        rod [J] (module docstring). ``pairs`` (P, 2) edges, ``e_r`` their E_R [J/m]."""
        fa, fb, _, _ = self._pair_rates(geo, pairs)
        rod = self.model.edge_rod
        big_g = (np.bincount(rod[pairs[:, 0]], e_r * fa, self.rod_count)
                 + np.bincount(rod[pairs[:, 1]], e_r * fb, self.rod_count))
        return self.chain_gradient(geo, big_g), big_g

    def chain_gradient(self, geo: dict[str, np.ndarray], big_g: np.ndarray) -> np.ndarray:
        """sum_r G_r grad s_r over vertex positions (V, 3) [N] for G [J] per rod, grad s_r
        = (1/L0_r) sum_e dl_e/dx (dl/dx = -+ t at an edge's ends)."""
        m = self.model
        f = (big_g / geo["L0"])[m.edge_rod][:, None] * geo["t"]
        g = np.zeros((m.vertex_count, 3))
        np.add.at(g, m.edge_vertex[:, 1], f)
        np.add.at(g, m.edge_vertex[:, 0], -f)
        return g

    def stretch_columns(self, geo: dict[str, np.ndarray], rods: np.ndarray, first: int = 0,
                        end: int | None = None) -> np.ndarray:
        """grad s_r of each rod in ``rods`` as columns over the dofs ``first`` to ``end``
        (default: all the model's), (end - first, k) [1/m]."""
        end = self.model.dof_count if end is None else end
        u = np.zeros((end - first, len(rods)))
        for j, r in enumerate(rods):
            edges = self.model.rods[int(r)].edge_slice
            t = geo["t"][edges] / geo["L0"][r]
            ed = self.edge_dofs[edges] - first
            np.add.at(u[:, j], ed[:, 3:].ravel(), t.ravel())
            np.add.at(u[:, j], ed[:, :3].ravel(), -t.ravel())
        return u

    def stretch_blocks(self, geo: dict[str, np.ndarray], big_g: np.ndarray
                       ) -> np.ndarray:
        """sum_r G_r Hess s_r as one 6 x 6 block per edge over :attr:`edge_dofs`
        (E, 6, 6) [N/m]."""
        t, le = geo["t"], geo["l"]
        c = (big_g / geo["L0"])[self.model.edge_rod] / le
        proj = (np.eye(3)[None] - t[:, :, None] * t[:, None, :]) * c[:, None, None]
        return np.concatenate([np.concatenate([proj, -proj], axis=2),
                               np.concatenate([-proj, proj], axis=2)], axis=1)

    def low_rank(self, geo: dict[str, np.ndarray], pairs: np.ndarray, pair_dofs: np.ndarray,
                 e_r: np.ndarray, e_rr: np.ndarray, g_r: np.ndarray,
                 dofs: tuple[int, int] | None = None) -> tuple[np.ndarray, np.ndarray] | None:
        """The dense part U C U^T of the Hessian (module docstring) as U (dof_count, 2k)
        and C (2k, 2k), k the rods any pair of ``pairs`` touches (None when none does).
        ``pair_dofs`` (P, 12): the dofs of each pair's vertices [a0, a1, b0, b1]; ``e_r``,
        ``e_rr`` (P,) [J/m, J/m^2]; ``g_r`` (P, 12) [N/m]. ``dofs`` (first, end): U's rows
        for those dofs only (the rods touched must lie in them: one rod of a batch)."""
        if pairs.shape[0] == 0:
            return None
        m = self.model
        rod = m.edge_rod
        ra, rb = rod[pairs[:, 0]], rod[pairs[:, 1]]
        rods = np.unique(np.concatenate([ra, rb]))
        k = rods.size
        slot = np.full(self.rod_count, -1, dtype=np.int64)
        slot[rods] = np.arange(k)
        fa, fb, f2a, f2b = self._pair_rates(geo, pairs)
        # dR_p/ds_r of each pair for each rod it touches (P, k)
        rate = np.zeros((pairs.shape[0], k))
        np.add.at(rate, (np.arange(pairs.shape[0]), slot[ra]), fa)
        np.add.at(rate, (np.arange(pairs.shape[0]), slot[rb]), fb)
        s_mat = rate.T @ (e_rr[:, None] * rate)
        curv = (np.bincount(slot[ra], e_r * f2a, k) + np.bincount(slot[rb], e_r * f2b, k))
        s_mat[np.diag_indices(k)] += curv
        first, end = (0, m.dof_count) if dofs is None else dofs
        u = np.zeros((end - first, 2 * k))
        u[:, :k] = self.stretch_columns(geo, rods, first, end)
        for j in range(k):
            np.add.at(u[:, k + j], (pair_dofs - first).ravel(),
                      (g_r * rate[:, j:j + 1]).ravel())
        c = np.zeros((2 * k, 2 * k))
        c[:k, :k] = s_mat
        c[:k, k:] = np.eye(k)
        c[k:, :k] = np.eye(k)
        return u, c
