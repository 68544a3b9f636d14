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


def u_start(s: np.ndarray, bend_radius: float, leg_length: float
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The U a clamped-U elastica starts from, at arc lengths ``s`` [m]: a leg of
    ``leg_length`` [m] along +x from the origin, a half circle of radius ``bend_radius``
    [m], a leg back along -x at y = 2 ``bend_radius``. Returns the tangent angle from +x
    [rad] and the coordinates x, y [m]."""
    rho, leg = float(bend_radius), float(leg_length)
    arc = np.clip((s - leg) / rho, 0.0, np.pi)
    on_arc = s < leg + np.pi * rho
    x = np.where(s < leg, s, np.where(on_arc, leg + rho * np.sin(arc),
                                      leg - (s - leg - np.pi * rho)))
    y = np.where(s < leg, 0.0, np.where(on_arc, rho * (1.0 - np.cos(arc)), 2.0 * rho))
    return arc, x, y


def clamped_u_apex_shift(bend_radius: float, leg_length: float) -> float:
    """How far [m] the apex of a U moves along its axis when the U settles in its clamps:
    an inextensible elastica, straight at rest, started on a half circle of radius
    ``bend_radius`` [m] with two straight legs of ``leg_length`` [m], both ends clamped
    (position and direction) where the legs start. Positive: away from the clamps.

    With theta(s) the tangent angle from the first leg's direction and (p, q) = F/EI the
    end force over the bending stiffness [1/m^2], the moment balance gives ``theta'' = p
    sin(theta) - q cos(theta)`` (Antman, "Nonlinear Problems of Elasticity", 2005, ch. 4);
    the clamps give theta(0) = 0, theta(L) = pi, (x, y)(0) = 0 and (x, y)(L) = (0, 2
    rho). Solved by collocation with ``scipy.integrate.solve_bvp``, the end force an
    unknown parameter, independently of the rod code."""
    # in units of the bend radius (the solver's tolerances are absolute)
    scale = float(bend_radius)
    rho = 1.0
    leg = float(leg_length) / scale
    length = np.pi * rho + 2.0 * leg
    s = np.linspace(0.0, length, 801)
    arc, x0, y0 = u_start(s, rho, leg)
    dth0 = np.where((s >= leg) & (s <= leg + np.pi * rho), 1.0 / rho, 0.0)
    guess = np.vstack([arc, dth0, x0, y0])

    def rhs(_s: np.ndarray, y: np.ndarray, p: np.ndarray) -> np.ndarray:
        th, dth, _x, _y = y
        return np.vstack([dth, p[0] * np.sin(th) - p[1] * np.cos(th), np.cos(th),
                          np.sin(th)])

    def bc(ya: np.ndarray, yb: np.ndarray, _p: np.ndarray) -> np.ndarray:
        return np.array([ya[0], yb[0] - np.pi, ya[2], ya[3], yb[2], yb[3] - 2.0 * rho])

    sol = solve_bvp(rhs, bc, s, guess, p=np.zeros(2), tol=1e-10, max_nodes=200000)
    if not sol.success:
        raise RuntimeError(f"clamped-U elastica did not converge: {sol.message}")
    return float(sol.sol(0.5 * length)[2] - (leg + rho)) * scale
