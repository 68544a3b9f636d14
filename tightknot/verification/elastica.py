"""Independent reference for the large-deflection cantilever: the planar Kirchhoff elastica.

An inextensible rod clamped horizontally at s = 0 carries a dead load F along -y at its tip.
With theta(s) the tangent angle from +x, the moment balance EI theta' = -F (x(L) - x(s))
differentiates to ``theta'' = (F/EI) cos(theta)`` with ``theta(0) = 0`` (clamp) and
``theta'(L) = 0`` (free end), and ``x' = cos(theta)``, ``y' = sin(theta)``
(Timoshenko & Gere, "Theory of Elastic Stability", 1961, sec. 2.7). Solved by collocation
with ``scipy.integrate.solve_bvp``, independently of the rod code.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_bvp


def cantilever_tip(load_parameter: float, length: float = 1.0) -> tuple[float, float]:
    """Tip position (x, y) [m] of the elastica for ``load_parameter`` = F L^2 / EI [-]."""
    k = float(load_parameter) / length**2  # F/EI [1/m^2]

    def rhs(s: np.ndarray, y: np.ndarray) -> np.ndarray:
        th, dth, _x, _y = y
        return np.vstack([dth, k * np.cos(th), np.cos(th), np.sin(th)])

    def bc(ya: np.ndarray, yb: np.ndarray) -> np.ndarray:
        return np.array([ya[0], yb[1], ya[2], ya[3]])

    s = np.linspace(0.0, length, 401)
    # Start from the small-deflection shape, continued in load for robustness.
    guess = np.zeros((4, s.size))
    guess[2] = s
    sol = None
    for frac in np.linspace(0.1, 1.0, 10):
        kk = k * frac

        def rhs_k(ss: np.ndarray, y: np.ndarray, kk: float = kk) -> np.ndarray:
            th, dth, _x, _y = y
            return np.vstack([dth, kk * np.cos(th), np.cos(th), np.sin(th)])

        sol = solve_bvp(rhs_k, bc, s, guess, tol=1e-10, max_nodes=100000)
        if not sol.success:
            raise RuntimeError(f"elastica reference did not converge: {sol.message}")
        guess = sol.sol(s)
    assert sol is not None
    end = sol.sol(length)
    return float(end[2]), float(end[3])
