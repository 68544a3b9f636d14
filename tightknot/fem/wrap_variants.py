"""The wrap scene with variants of the rod model's pair kernel (a diagnostic of the FEM
cross-check, not a model of the package).

Why. In the cross-check the rod model's line load at the middle of the wrap is 15 to 31 %
below the FEM's (docs/fem_crosscheck.md). Two candidate causes are tested here without
touching the Warp kernel:

1. *The kernel's footprint.* The pair kernel is a radial function psi(rho) of the distance
   of two centerline points; it acts where rho < R = r_a + r_b, so along each strand of a
   crossing it reaches sqrt(R^2 - d^2) ~ sqrt(2 R delta), twice the Hertz patch semi-axis
   sqrt(r delta) of two crossed cylinders of radius r (Johnson 1985, eq. 4.22 with
   R_e = r). A kernel that scales the separation's component in the plane of the two
   tangents by ``footprint`` = alpha and multiplies psi by alpha^2 keeps the energy of
   EVERY straight crossing exactly (the in-plane integral is a change of variables,
   ``int int alpha^2 psi(sqrt(d^2 + alpha^2 |v|^2)) dA = int int psi(sqrt(d^2 + |v|^2)) dA``)
   and shrinks the footprint by alpha.
2. *The law.* A strand wrapped around another lies along its surface: locally a line
   contact (a round section on a straight generator), whatever the angle of the axes, so
   the line law may apply instead of the point law (``kernel="line"``).

How. The wrap's obstacle is a straight rigid line along e_x and the rod stays in the plane
x = 0, so the tangents are orthogonal and the integral over the obstacle is done exactly:
a Gauss point p of a chord with unit tangent t, at D^2 = |p - q0|^2 + (alpha^2 - 1)
((p - q0).t)^2 from the obstacle axis point q0, carries alpha Lambda(D) per length, with
Lambda the Abel transform of psi: for the point kernel psi_p = K m (R - rho)^(m-1)/(2 pi
rho) (contact_law) ``Lambda(D) = (K m/pi) R^(m-1) L(D/R)``, L tabulated by quadrature; for
the line kernel exactly the line law, ``Lambda(D) = K_l (R - D)^m_l``. Each chord's energy
is differentiated by central differences over its 4 in-plane dofs (step 1e-6 D0: relative
truncation error ~1e-12, round-off ~1e-10 of the force; the Newton solves converge in 3 to
5 iterations). The point variant with alpha = 1 is the shipped model; it reproduces the
Warp kernel's wrap within 0.5 % (tests/fem/test_wrap_variants.py), which validates this
re-implementation. The onset band (1e-4 R) and the hard core are left out: neither acts at
the wrap's overlaps.
"""

from __future__ import annotations

import functools
import math
import time
from typing import Any

import numpy as np

from tightknot.rods.term import EnergyTerm

from .material import ROD_DIAMETER, YOUNGS_MODULUS

KERNELS = ("point", "line")

_GAUSS_XI = np.array([0.5 - 0.5 / math.sqrt(3.0), 0.5 + 0.5 / math.sqrt(3.0)])
_GAUSS_W = np.array([0.5, 0.5])
_FD_STEP = 1e-6  # of D0, see the module docstring


@functools.lru_cache(maxsize=8)
def _point_abel_table(m: float) -> Any:
    """Cubic spline of L(x) = int_0^sqrt(1-x^2) (1 - sqrt(x^2+u^2))^(m-1)/sqrt(x^2+u^2) du,
    x = D/R in [0.3, 1] (the wrap's D/R stays above 0.6), zero beyond 1."""
    from scipy.integrate import quad
    from scipy.interpolate import CubicSpline

    xs = np.concatenate([np.linspace(0.3, 0.9, 200, endpoint=False),
                         np.linspace(0.9, 1.0, 401)])

    def integrand(u: float, x: float) -> float:
        rho = math.sqrt(x * x + u * u)
        return (1.0 - rho) ** (m - 1.0) / rho

    vals = [quad(integrand, 0.0, math.sqrt(max(1.0 - x * x, 0.0)), args=(x,),
                 epsabs=1e-14, epsrel=1e-12)[0] if x < 1.0 else 0.0 for x in xs]
    return CubicSpline(np.append(xs, 1.2), np.append(vals, 0.0))


class ObstacleLineContact(EnergyTerm):
    """Contact energy of a planar rod (plane x = 0, vertices ``0..n``) against a rigid
    straight cylinder along e_x through (0, ``y_axis``, 0), with the kernel variants of the
    module docstring: an energy term of the rod system (:class:`tightknot.rods.term.EnergyTerm`)."""

    name = "contact"

    def __init__(self, model: Any, law: Any, y_axis: float, kernel: str = "point",
                 footprint: float = 1.0, youngs_modulus: float = YOUNGS_MODULUS,
                 diameter: float = ROD_DIAMETER) -> None:
        if kernel not in KERNELS:
            raise ValueError(f"kernel must be one of {KERNELS}, got {kernel!r}")
        if not (math.isfinite(footprint) and 1.0 <= footprint <= 4.0):
            raise ValueError(f"footprint must be in [1, 4], got {footprint!r}")
        self.model = model
        self.n = model.rods[0].edge_count
        self.y_axis = y_axis
        self.kernel = kernel
        self.alpha = footprint
        self.r_obstacle = 0.5 * diameter
        self.lbar = model.edge_rest_length[: self.n].copy()
        self.r0 = model.edge_radius[: self.n].copy()
        self.nu = 0.5
        self.d0 = diameter
        if kernel == "point":
            self.m = law.p_point + 1.0
            self.coef = law.point_energy_coefficient(youngs_modulus, diameter)
            self.table = _point_abel_table(self.m)
        else:
            self.m = law.p_line + 1.0
            self.coef = law.line_energy_coefficient(youngs_modulus, diameter)

    def _abel(self, dist: np.ndarray, big_r: np.ndarray) -> np.ndarray:
        """Energy per length of a chord point at distance ``dist`` from the obstacle axis,
        contact radius ``big_r`` [J/m]."""
        if self.kernel == "line":
            return self.coef * np.maximum(big_r - dist, 0.0) ** self.m
        x = dist / big_r
        vals = np.where(x < 1.0, self.table(np.minimum(x, 1.0)), 0.0)
        return self.coef * self.m / math.pi * big_r ** (self.m - 1.0) * vals

    def chord_energy(self, q: np.ndarray) -> np.ndarray:
        """Energy [J] of each chord, ``q`` (n, 4): (y, z) of its two ends [m]."""
        p0, p1 = q[:, :2], q[:, 2:]
        e = p1 - p0
        la = np.linalg.norm(e, axis=1)
        t = e / la[:, None]
        big_r = self.r0 * (la / self.lbar) ** -self.nu + self.r_obstacle
        out = np.zeros(q.shape[0])
        for xg, w in zip(_GAUSS_XI, _GAUSS_W, strict=True):
            d = p0 + xg * e - np.array([self.y_axis, 0.0])
            dist2 = (d * d).sum(axis=1) + (self.alpha**2 - 1.0) * (d * t).sum(axis=1) ** 2
            out += w * la * self.alpha * self._abel(np.sqrt(dist2), big_r)
        return out

    def evaluate(self, x: np.ndarray, rest: np.ndarray, want_grad: bool = True,
                 want_hess: bool = True
                 ) -> tuple[float, np.ndarray | None, tuple[np.ndarray, ...] | None]:
        """Energy [J], gradient (vertex_count, 3) [N], Hessian COO over global dofs."""
        n = self.n
        yz = x[: n + 1, 1:]
        q = np.concatenate([yz[:-1], yz[1:]], axis=1)
        energy = float(self.chord_energy(q).sum())
        h = _FD_STEP * self.d0
        grad = coo = None
        if want_grad or want_hess:
            gl = np.empty((n, 4))
            for i in range(4):
                dq = np.zeros(4)
                dq[i] = h
                gl[:, i] = (self.chord_energy(q + dq) - self.chord_energy(q - dq)) / (2 * h)
            grad = np.zeros((self.model.vertex_count, 3))
            idx = np.arange(n)
            np.add.at(grad[:, 1], idx, gl[:, 0])
            np.add.at(grad[:, 2], idx, gl[:, 1])
            np.add.at(grad[:, 1], idx + 1, gl[:, 2])
            np.add.at(grad[:, 2], idx + 1, gl[:, 3])
        if want_hess:
            hl = np.empty((n, 4, 4))
            for i in range(4):
                for j in range(i, 4):
                    di = np.zeros(4)
                    dj = np.zeros(4)
                    di[i] = h
                    dj[j] = h
                    v = (self.chord_energy(q + di + dj) - self.chord_energy(q + di - dj)
                         - self.chord_energy(q - di + dj)
                         + self.chord_energy(q - di - dj)) / (4 * h * h)
                    hl[:, i, j] = v
                    hl[:, j, i] = v
            vd = self.model.vertex_dof.astype(np.int64)
            dofs = np.stack([vd[:n] + 1, vd[:n] + 2, vd[1:n + 1] + 1, vd[1:n + 1] + 2], axis=1)
            active = np.abs(hl).sum(axis=(1, 2)) > 0.0
            dofs, hl = dofs[active], hl[active]
            coo = (np.broadcast_to(dofs[:, :, None], hl.shape).ravel(),
                   np.broadcast_to(dofs[:, None, :], hl.shape).ravel(), hl.ravel())
        return energy, grad, coo

    def max_step(self, x: np.ndarray, dx: np.ndarray, rest: np.ndarray) -> float:
        """No step limit: the rod cannot pass through an analytic line it is pressed on
        (the energy grows without bound before the axes meet)."""
        return 1.0


def rod_wrap_variant(tension_levels: list[float], kernel: str = "point",
                     footprint: float = 1.0, wrap_angle_deg: float = 90.0,
                     diameter: float = ROD_DIAMETER, youngs_modulus: float = YOUNGS_MODULUS,
                     length_over_d0: float = 4.5, law: Any = None) -> dict[str, Any]:
    """:func:`tightknot.fem.rod_model.rod_wrap` with the kernel variant ``kernel`` /
    ``footprint`` (module docstring) against an analytic obstacle. Returns per tension
    level [N]: ``force_per_length_mid`` [N/m], ``overlap_over_d0``, ``approach_over_d0``,
    ``kappa_d0_mid``, ``contact_half_length_over_d0`` (rest arc length from the middle to
    the last loaded vertex), and the wall time."""
    from tightknot.contact.law import RadialComplianceLaw
    from tightknot.knots.curvature import bergou_curvature
    from tightknot.loading.levels import LevelLoad
    from tightknot.rods.boundary import BoundaryConditions
    from tightknot.rods.builder import RodBuilder
    from tightknot.rods.material import Material
    from tightknot.rods.state import State
    from tightknot.solvers.system import RodSystem

    from .rod_model import (
        DENSITY,
        EDGES_PER_D0,
        _solve_levels,
        rigid_counterbody_law,
        wrap_constraints,
    )

    start = time.perf_counter()
    pair_law = rigid_counterbody_law(law or RadialComplianceLaw.from_json())
    d0 = diameter
    theta = 0.5 * math.radians(wrap_angle_deg)
    n_rod = int(round(length_over_d0 * EDGES_PER_D0))
    n_rod += n_rod % 2
    half = 0.5 * length_over_d0 * d0
    y_axis = d0 - 0.01 * d0  # as rod_wrap: the rod floats on a small initial overlap
    b = RodBuilder(twist=False)
    b.add_rod(np.linspace([0.0, 0.0, -half], [0.0, 0.0, half], n_rod + 1), d0,
              Material(youngs_modulus, 0.5, DENSITY))
    model = b.finalize()
    load = LevelLoad()
    bcs = BoundaryConditions(model)
    mid = wrap_constraints(bcs, n_rod, theta, load)
    system = RodSystem(model, State.initial(model), bcs)
    term = ObstacleLineContact(model, pair_law, y_axis, kernel, footprint, youngs_modulus, d0)
    system.add_term(term)
    arc = np.concatenate([[0.0], np.cumsum(model.edge_rest_length)])
    arc -= arc[mid]

    def measure(tension: float) -> dict[str, Any]:
        x = system.state.x
        _, g, _ = term.evaluate(x, model.edge_rest_length, True, False)
        e = np.linalg.norm(np.diff(x, axis=0), axis=1)
        voronoi = 0.5 * (e[mid - 1] + e[mid])
        f_mid = float(np.linalg.norm(g[mid])) / voronoi
        stretch = voronoi / (2.0 * half / n_rod)
        dist = math.hypot(y_axis - x[mid, 1], x[mid, 2])
        f_v = np.linalg.norm(g, axis=1)
        loaded = f_v > 1e-6 * f_v.max()
        return {
            "tension_over_e_d0sq": tension / (youngs_modulus * d0**2),
            "force_per_length_mid": f_mid,
            "force_per_length_mid_over_e_d0": f_mid / (youngs_modulus * d0),
            "overlap_over_d0": (0.5 * d0 * stretch**-0.5 + 0.5 * d0 - dist) / d0,
            "approach_over_d0": (d0 - dist) / d0,
            "kappa_d0_mid": float(bergou_curvature(x, closed=False)[mid]) * d0,
            "contact_half_length_over_d0": float(np.abs(arc[loaded]).max()) / d0,
            "contact_force_total_over_2t_sin_theta":
                float(np.linalg.norm(g.sum(axis=0))) / (2.0 * tension * math.sin(theta)),
        }

    rows = _solve_levels(system, load, list(tension_levels), measure)
    return {"kernel": kernel, "footprint": footprint, "steps": rows,
            "wall_time_s": time.perf_counter() - start, "vertices": int(model.vertex_count)}
