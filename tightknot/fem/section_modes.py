"""The stiffness of a section's Fourier modes in the FEM's solid: the calibration of the
section energy of the sectioned contact level (:mod:`tightknot.contact.section_modes`).

A whole disk of the nearly incompressible neo-Hookean solid (:mod:`tightknot.fem.material`)
in plane strain is loaded on its boundary by a dead radial traction q cos n theta, which
does no work on the rigid modes (n >= 2) and no shear: the frictionless analogue of a
contact that flattens the section. The radial boundary displacement's n-th Fourier
coefficient a answers; the generalised force of the load on a is Q = pi R q (the traction's
work on u_r = a cos n theta), so the secant stiffness is k = Q / a [Pa], which the linear
closed form predicts as 2 pi mu (n^2 - 1) / n at small q.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from tightknot.contact.section_modes import mode_amplitudes, mode_stiffness

from ._backend import require_felupe
from .material import BULK_MODULUS, ROD_DIAMETER, SHEAR_MODULUS, nearly_incompressible_solid
from .solver import NewtonFailure, Problem

DISK_POINTS: dict[str, int] = {"coarse": 9, "medium": 13, "fine": 17}
"""Points per edge n of each quarter of FElupe's ``Circle``: 4 * 3 (n - 1)^2 quads and
8 (n - 1) boundary nodes (64, 96, 128)."""


def _boundary(points: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """Boundary node indices, sorted by angle, and their trapezoid arc weights [m]."""
    r = np.hypot(points[:, 0], points[:, 1])
    nodes = np.flatnonzero(np.isclose(r, radius, rtol=1e-9))
    theta = np.arctan2(points[nodes, 1], points[nodes, 0])
    order = np.argsort(theta)
    nodes, theta = nodes[order], theta[order]
    gaps = np.diff(np.concatenate([theta, [theta[0] + 2.0 * math.pi]]))
    return nodes, radius * 0.5 * (gaps + np.roll(gaps, 1))


def disk_mode_stiffness(n: int, amplitudes_over_r: list[float], mesh: str = "coarse",
                        diameter: float = ROD_DIAMETER,
                        shear_modulus: float = SHEAR_MODULUS) -> dict[str, Any]:
    """Secant stiffness of mode ``n`` of the FEM's plane-strain disk at each radial amplitude
    a / R in ``amplitudes_over_r`` (increasing, in (0, 0.5)), by load control.

    Each target amplitude is reached by a traction q, found by a secant iteration on a(q)
    from the linear prediction (the dead load is applied in steps from the last level).
    Returns a JSON-serialisable dict: per level ``amplitude_over_r``, ``traction_over_e``
    (q / E), ``stiffness_over_linear`` (k / k_n of the closed form), the ``sine_over_cosine``
    leak of the answer (mesh symmetry), ``area_ratio`` and ``newton_iterations``; and
    ``linear_stiffness_pa``, ``mesh``, ``wall_time_s``. Raises ValueError for bad input.
    """
    fem = require_felupe()
    if mesh not in DISK_POINTS:
        raise ValueError(f"mesh must be one of {tuple(DISK_POINTS)}, got {mesh!r}")
    levels = [float(v) for v in amplitudes_over_r]
    if not levels or any(not 0.0 < v < 0.5 for v in levels) or levels != sorted(levels):
        raise ValueError(f"amplitudes_over_r must be increasing values in (0, 0.5), got "
                         f"{amplitudes_over_r!r}")
    for name, value in (("diameter", diameter), ("shear_modulus", shear_modulus)):
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
    youngs = 3.0 * shear_modulus
    k_lin = mode_stiffness(n, youngs)
    start = time.perf_counter()
    radius = 0.5 * diameter
    body = fem.Circle(radius=radius, centerpoint=(0.0, 0.0), n=DISK_POINTS[mesh],
                      sections=[0, 90, 180, 270])
    field = fem.FieldContainer([fem.FieldPlaneStrain(fem.RegionQuad(body), dim=2)])
    solid = nearly_incompressible_solid(field, mu=shear_modulus,
                                        bulk=BULK_MODULUS / SHEAR_MODULUS * shear_modulus)
    pts = body.points
    nodes, weight = _boundary(pts, radius)
    theta = np.arctan2(pts[nodes, 1], pts[nodes, 0])
    # The load does no work on the rigid modes; fixing the centre node and the x-axis node's
    # y displacement removes them from the system without a reaction.
    centre = int(np.argmin(np.hypot(pts[:, 0], pts[:, 1])))
    axis = nodes[int(np.argmin(np.abs(theta)))]
    fixed = np.zeros((body.npoints, 2), dtype=bool)
    fixed[centre] = True
    fixed[axis, 1] = True
    unit = np.zeros((body.npoints, 2))
    unit[nodes, 0] = weight * np.cos(n * theta) * np.cos(theta)
    unit[nodes, 1] = weight * np.cos(n * theta) * np.sin(theta)
    problem = Problem(field=field, solid=solid, contacts=[], fixed=fixed.ravel(),
                      force_scale=youngs * radius, max_backtracks=4)

    def answer(q: float) -> tuple[float, float, int]:
        problem.external = q * unit.ravel()
        iterations = problem.newton()
        u = field[0].values[nodes]
        radial = u[:, 0] * np.cos(theta) + u[:, 1] * np.sin(theta)
        a, b = mode_amplitudes(theta, radial, n)
        return a, b, iterations

    rows = []
    q_last, a_last = 0.0, 0.0
    for level in levels:
        target = level * radius
        iterations = 0
        while True:
            q = q_last + (target - a_last) * k_lin / (math.pi * radius)
            checkpoint = solid.checkpoint()
            try:
                for _ in range(20):
                    solid.restore(checkpoint)
                    a, b, its = answer(q)
                    iterations += its
                    if abs(a - target) <= 1e-8 * radius:
                        break
                    # secant on a(q) through the last equilibrium
                    q = q_last + (q - q_last) * (target - a_last) / (a - a_last)
                else:
                    raise NewtonFailure(f"mode {n}: amplitude {level} R not reached by the "
                                        f"secant iteration")
                break
            except NewtonFailure:
                # too long a step for Newton: an intermediate equilibrium at half the
                # predicted load, then the target again from there
                solid.restore(checkpoint)
                q_half = 0.5 * (q_last + q_last + (target - a_last) * k_lin / (math.pi * radius))
                if abs(q_half - q_last) < 1e-6 * abs(q_last) + 1e-12:
                    raise
                a, _, its = answer(q_half)
                iterations += its
                q_last, a_last = q_half, a
        x = pts + field[0].values
        area = _polygon_area(x[nodes])
        rows.append({
            "amplitude_over_r": a / radius,
            "traction_over_e": q / youngs,
            "stiffness_over_linear": (math.pi * radius * q / a) / k_lin,
            "sine_over_cosine": abs(b) / abs(a),
            "area_ratio": area / _polygon_area(pts[nodes]),
            "newton_iterations": iterations,
        })
        q_last, a_last = q, a
    return {"mode": n, "mesh": mesh, "linear_stiffness_pa": k_lin,
            "boundary_nodes": int(nodes.size), "levels": rows,
            "wall_time_s": time.perf_counter() - start}


def _polygon_area(ring: np.ndarray) -> float:
    """Area [m^2] of the polygon through the boundary nodes in angular order."""
    x, y = ring[:, 0], ring[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


ROD_MESHES: dict[str, tuple[int, int]] = {"coarse": (5, 16), "medium": (7, 24), "fine": (9, 32)}
"""(points per quarter edge of the section, axial cells over the half rod) per mesh: 32,
48, 64 boundary nodes around the section."""


def rod_mode_decay(n: int, mesh: str = "coarse", patch_over_d0: float = 0.25,
                   half_length_over_d0: float = 4.0, diameter: float = ROD_DIAMETER,
                   shear_modulus: float = SHEAR_MODULUS) -> dict[str, Any]:
    """How far along a 3D rod a section mode spreads: the FEM's answer and the axial
    gradient stiffness g_n [N] of the 1D section model that matches it.

    A straight rod of the FEM's solid, symmetric about z = 0 (u_z = 0 there), free at
    z = ``half_length_over_d0`` D0, carries the dead radial traction q cos n theta on its
    lateral surface for |z| < ``patch_over_d0`` D0, small enough to be linear (a ~ 0.01 R
    at the centre). The section model's energy per unit length, (1/2) k_n a^2 +
    (1/2) g_n (da/dz)^2 with the plane-strain k_n, answers the same load (linear elements
    on the FEM's axial nodes); g_n is fitted to the FEM's a_n(z) by least squares.

    Returns ``mode``, ``mesh``, ``z_over_d0``, ``fem_amplitude_over_r`` and
    ``model_amplitude_over_r`` (profiles), ``gradient_stiffness_n`` (g_n [N]),
    ``decay_length_over_d0`` (sqrt(g_n / k_n) / D0), ``fit_rms_over_peak`` (the profile
    misfit), ``centre_amplitude_over_r``, ``dofs``, ``wall_time_s``.
    """
    fem = require_felupe()
    from scipy.optimize import minimize_scalar

    from .mesh import extrude, lateral_faces, lumped_face_weights

    if mesh not in ROD_MESHES:
        raise ValueError(f"mesh must be one of {tuple(ROD_MESHES)}, got {mesh!r}")
    youngs = 3.0 * shear_modulus
    k_n = mode_stiffness(n, youngs)
    if not 0.0 < patch_over_d0 < half_length_over_d0 / 4.0:
        raise ValueError(f"patch_over_d0 must lie in (0, half_length_over_d0 / 4), got "
                         f"{patch_over_d0!r}")
    start = time.perf_counter()
    radius = 0.5 * diameter
    points_per_edge, cells = ROD_MESHES[mesh]
    section = fem.Circle(radius=radius, centerpoint=(0.0, 0.0), n=points_per_edge,
                         sections=[0, 90, 180, 270])
    patch, length = patch_over_d0 * diameter, half_length_over_d0 * diameter
    # axial nodes: uniform at 1/4 of the patch over it, then growing geometrically to the end
    inner = np.linspace(0.0, patch, 5)
    outer = patch + (length - patch) * np.linspace(0.0, 1.0, cells - 3) ** 1.6
    z = np.concatenate([inner, outer[1:]])
    body = extrude(section, z)
    field = fem.FieldContainer([fem.Field(fem.RegionHexahedron(body), dim=3)])
    solid = nearly_incompressible_solid(field, mu=shear_modulus,
                                        bulk=BULK_MODULUS / SHEAR_MODULUS * shear_modulus)
    pts = body.points
    faces = lateral_faces(body, radius)
    loaded = faces[np.all(pts[faces, 2] <= patch * (1.0 + 1e-9), axis=1)]
    weight = lumped_face_weights(pts, loaded)
    theta = np.arctan2(pts[:, 1], pts[:, 0])
    load = np.zeros((body.npoints, 3))
    load[:, 0] = weight * np.cos(n * theta) * np.cos(theta)
    load[:, 1] = weight * np.cos(n * theta) * np.sin(theta)
    r = np.hypot(pts[:, 0], pts[:, 1])
    fixed = np.zeros((body.npoints, 3), dtype=bool)
    fixed[np.isclose(pts[:, 2], 0.0), 2] = True  # the symmetry plane
    axis = np.flatnonzero(r < 1e-12 * radius)
    fixed[axis, :2] = True  # no shift of the centerline (mode 1): the load has none
    on_x = np.flatnonzero(np.isclose(r, radius) & (np.abs(pts[:, 1]) < 1e-12 * radius)
                          & (pts[:, 0] > 0.0))
    fixed[on_x, 1] = True  # no rotation about the axis: the load has no torque
    problem = Problem(field=field, solid=solid, contacts=[], fixed=fixed.ravel(),
                      force_scale=youngs * radius**2)
    q = 0.01 * radius * k_n / (math.pi * radius)  # a ~ 0.01 R if the load were uniform
    problem.external = q * load.ravel()
    problem.newton()
    u = field[0].values
    surface = np.isclose(r, radius)
    fem_a = np.zeros(z.size)
    for i, zi in enumerate(z):
        ring = np.flatnonzero(surface & np.isclose(pts[:, 2], zi, atol=1e-9 * length))
        radial = u[ring, 0] * np.cos(theta[ring]) + u[ring, 1] * np.sin(theta[ring])
        fem_a[i] = mode_amplitudes(theta[ring], radial, n)[0]

    # The 1D section model on the same nodes: linear elements, the load pi R q on |z| < patch.
    h = np.diff(z)
    mass = np.zeros((z.size, z.size))
    stiff = np.zeros((z.size, z.size))
    force = np.zeros(z.size)
    for e, he in enumerate(h):
        idx = np.array([e, e + 1])
        mass[np.ix_(idx, idx)] += he / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
        stiff[np.ix_(idx, idx)] += 1.0 / he * np.array([[1.0, -1.0], [-1.0, 1.0]])
        if z[e + 1] <= patch * (1.0 + 1e-9):
            force[idx] += math.pi * radius * q * he / 2.0

    def model(g: float) -> np.ndarray:
        return np.linalg.solve(k_n * mass + g * stiff, force)

    peak = float(np.max(np.abs(fem_a)))

    def misfit(log_g: float) -> float:
        return float(np.sum((model(math.exp(log_g)) - fem_a) ** 2))

    g0 = k_n * diameter**2
    best = minimize_scalar(misfit, bounds=(math.log(g0 * 1e-4), math.log(g0 * 1e2)),
                           method="bounded", options={"xatol": 1e-6})
    g = math.exp(best.x)
    fitted = model(g)
    return {
        "mode": n, "mesh": mesh, "patch_over_d0": patch_over_d0,
        "z_over_d0": (z / diameter).tolist(),
        "fem_amplitude_over_r": (fem_a / radius).tolist(),
        "model_amplitude_over_r": (fitted / radius).tolist(),
        "gradient_stiffness_n": g,
        "decay_length_over_d0": math.sqrt(g / k_n) / diameter,
        "fit_rms_over_peak": float(np.sqrt(np.mean((fitted - fem_a) ** 2))) / peak,
        "centre_amplitude_over_r": float(fem_a[0]) / radius,
        "dofs": int(body.npoints * 3), "wall_time_s": time.perf_counter() - start,
    }
