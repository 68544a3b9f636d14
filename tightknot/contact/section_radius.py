"""The stretch-smoothed contact radius of the sections, with its exact chain rule.

The contact layer thins each section with stretch, r = r0 lambda^-nu (incompressible:
nu = 1/2). With each edge's own stretch (``radius_window = 0``, the default) the contact
energy of a crossing lowers when the edges under it stretch, so the contact pulls them
apart: at the FEM cross-check's indent the rod carries 3.4 to 54 times the FEM's axial force
at the crossing and its force is 11 to 16 % short (docs/fem_crosscheck.md). A section of a
solid does not thin with one edge but with the material around it. Here the stretch that
thins the section is the mean over the edges within +-``window`` D0 along the rod (a box
average: lambda_bar = W lambda, an open rod's window cut at its ends, a closed rod's
wrapping):

    rho_e = r0_e lambda_bar_e^-nu_e,   lambda_bar_e = sum_k W_ek l_k / l_bar_k.

The pair kernel evaluates each pair at the given radii (its given-radius variants: no
derivative through the edge lengths) and returns, per pair p of edges (a, b), with
R = rho_a + rho_b, E_R = dE_p/dR, E_RR and gR_p = d(grad_x E_p)/dR. The chain rule then
gives the exact gradient and Hessian (f' = d rho/d lambda_bar = -nu rho/lambda_bar,
f'' = nu (nu + 1) rho/lambda_bar^2, Lambda = d lambda_bar/dx, s_p = f'_a e_a + f'_b e_b,
G_e = sum of E_R over the pairs holding e):

    g = g_x + Lambda^T (G f'),
    H = H_xx + sum_k c_k Hess(l_k) + B Lambda + Lambda^T B^T + Lambda^T C Lambda,
    c = W^T (G f') / l_bar,  B = sum_p gR_p s_p^T,  C = sum_p E_RR,p s_p s_p^T + diag(G f'').

The Hessian couples every vertex of the window of a with every vertex of the window of b
(about 78 x 78 entries per pair at 1 D0 and 12 edges per D0): Newton keeps its quadratic
convergence, at about twice the time (bench/contact_levels.py, docs/design_notes.md).
"""

from __future__ import annotations

import math

import numpy as np
import scipy.sparse as sp

from tightknot.rods.model import Model


class SmoothedRadius:
    """The window average and the chain rule of the smoothed contact radius.

    Args:
        model: the rods.
        window: half-width of the window [D0 of each rod]; at least one edge each side.
        poisson: nu of each edge [-] (the thinning exponent).
    """

    def __init__(self, model: Model, window: float, poisson: np.ndarray) -> None:
        if not (math.isfinite(window) and 0.0 < window <= 10.0):
            raise ValueError(f"radius_window must be in [0, 10] (D0), got {window!r}")
        self.model = model
        self.window = float(window)
        self.nu = np.asarray(poisson, dtype=np.float64)
        rows: list[np.ndarray] = []
        cols: list[np.ndarray] = []
        vals: list[np.ndarray] = []
        self.window_edges = []
        for rod in model.rods:
            sl = rod.edge_slice
            n = rod.edge_count
            d0 = 2.0 * float(np.median(model.edge_radius[sl]))
            k = max(1, int(round(self.window * d0 / float(np.median(model.edge_rest_length[sl])))))
            k = min(k, (n - 1) // 2) if rod.closed else k
            self.window_edges.append(k)
            i = np.repeat(np.arange(n), 2 * k + 1)
            j = i + np.tile(np.arange(-k, k + 1), n)
            if rod.closed:
                j %= n
            else:
                keep = (j >= 0) & (j < n)
                i, j = i[keep], j[keep]
            count = np.bincount(i, minlength=n).astype(np.float64)
            rows.append(rod.edge_start + i)
            cols.append(rod.edge_start + j)
            vals.append(1.0 / count[i])
        ne = model.edge_count
        self.W = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows),
                                                       np.concatenate(cols))), shape=(ne, ne))
        self.WT = self.W.T.tocsr()
        ev = model.edge_vertex.astype(np.int64)
        vd = model.vertex_dof.astype(np.int64)
        #: The 6 position dofs of each edge (its two vertices).
        self.edge_dofs = np.concatenate([vd[ev[:, 0]][:, None] + np.arange(3),
                                         vd[ev[:, 1]][:, None] + np.arange(3)], axis=1)

    def stretch(self, x: np.ndarray, rest: np.ndarray) -> np.ndarray:
        """The smoothed stretch lambda_bar of each edge [-]."""
        ev = self.model.edge_vertex
        le = np.linalg.norm(x[ev[:, 1]] - x[ev[:, 0]], axis=1)
        return self.W @ (le / rest)

    def radii(self, x: np.ndarray, rest: np.ndarray) -> dict[str, np.ndarray]:
        """Unit tangents t, lengths l [m], smoothed radii rho [m] and f', f'' of each edge."""
        ev = self.model.edge_vertex
        e = x[ev[:, 1]] - x[ev[:, 0]]
        le = np.linalg.norm(e, axis=1)
        lam = self.W @ (le / rest)
        rho = self.model.edge_radius * lam ** (-self.nu)
        return {"t": e / le[:, None], "l": le, "rho": rho, "rest": np.asarray(rest),
                "f1": -self.nu * rho / lam, "f2": self.nu * (self.nu + 1.0) * rho / lam**2}

    def gradient(self, geo: dict[str, np.ndarray], pairs: np.ndarray,
                 e_r: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The gradient term Lambda^T (G f') over vertex positions (V, 3) [N], with G and
        c (per edge) for :meth:`hessian`. ``pairs`` (P, 2) edges, ``e_r`` their E_R [J/m]."""
        m = self.model
        big_g = np.zeros(m.edge_count)
        np.add.at(big_g, pairs[:, 0], e_r)
        np.add.at(big_g, pairs[:, 1], e_r)
        c = (self.WT @ (big_g * geo["f1"])) / geo["rest"]
        f = c[:, None] * geo["t"]
        g = np.zeros((m.vertex_count, 3))
        np.add.at(g, m.edge_vertex[:, 1], f)
        np.add.at(g, m.edge_vertex[:, 0], -f)
        return g, big_g, c

    def hessian(self, geo: dict[str, np.ndarray], pairs: np.ndarray, pair_dofs: np.ndarray,
                e_rr: np.ndarray, g_r: np.ndarray, big_g: np.ndarray,
                c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The Hessian terms beyond the kernel's H_xx, as COO triplets over global dofs.

        ``pair_dofs`` (P, 12): the dofs of each pair's vertices [a0, a1, b0, b1];
        ``e_rr`` (P,) [J/m^2]; ``g_r`` (P, 12) [N/m]; ``big_g``, ``c`` from :meth:`gradient`.
        """
        m = self.model
        nd, ne, npairs = m.dof_count, m.edge_count, pairs.shape[0]
        t, le, f1, f2 = geo["t"], geo["l"], geo["f1"], geo["f2"]
        ed = self.edge_dofs
        # sum_k c_k Hess(l_k), Hess(l) = [[P, -P], [-P, P]] / l, P = I - t t^T
        proj = (np.eye(3)[None] - t[:, :, None] * t[:, None, :]) * (c / le)[:, None, None]
        blk = np.concatenate([np.concatenate([proj, -proj], axis=2),
                              np.concatenate([-proj, proj], axis=2)], axis=1)
        local = sp.coo_matrix((blk.ravel(), (np.repeat(ed, 6, axis=1).ravel(),
                                             np.tile(ed, (1, 6)).ravel())), shape=(nd, nd))
        # Lambda = W L, rows of L: d lambda_k/dx = (-t_k, t_k)/l_bar_k on the edge's dofs
        lvals = (np.concatenate([-t, t], axis=1) / geo["rest"][:, None]).ravel()
        lmat = sp.csr_matrix((lvals, (np.repeat(np.arange(ne), 6), ed.ravel())),
                             shape=(ne, nd))
        lam = (self.W @ lmat).tocsr()
        fa, fb = f1[pairs[:, 0]], f1[pairs[:, 1]]
        b = sp.csr_matrix((np.concatenate([g_r * fa[:, None], g_r * fb[:, None]],
                                          axis=1).ravel(),
                           (np.concatenate([pair_dofs, pair_dofs], axis=1).ravel(),
                            np.concatenate([np.repeat(pairs[:, :1], 12, axis=1),
                                            np.repeat(pairs[:, 1:], 12, axis=1)],
                                           axis=1).ravel())), shape=(nd, ne))
        s = sp.csr_matrix((np.concatenate([fa, fb]),
                           (np.tile(np.arange(npairs), 2),
                            np.concatenate([pairs[:, 0], pairs[:, 1]]))), shape=(npairs, ne))
        cmat = (s.T @ sp.diags(e_rr) @ s + sp.diags(big_g * f2)).tocsr()
        bl = b @ lam
        h = (local + bl + bl.T + lam.T @ (cmat @ lam)).tocoo()
        return h.row.astype(np.int64), h.col.astype(np.int64), h.data
