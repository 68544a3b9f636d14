"""Fourier modes of a rod's cross-section: its boundary, its area and its plane-strain energy.

The section of the sectioned contact level (issue 18) is described in its material frame by
the radius of its boundary,

    r(theta) = R + sum_{n=2..N} (a_n cos n theta + b_n sin n theta),

mode 1 being a rigid shift of the centerline and mode 0 the mean radius R, which an
incompressible rod does not choose freely: the area (1/2) int r^2 dtheta must equal A0 /
lambda at axial stretch lambda (Johanns et al. 2021 and physics.md: the material is
incompressible), so R follows from lambda and the modes.

The energy of a mode, per unit rod length, is that of an incompressible linear-elastic disk
in plane strain whose boundary moves radially by a cos n theta with no shear traction (a
frictionless contact). With the displacement u = curl(psi e_z), divergence-free, equilibrium
makes psi biharmonic; psi = (A r^n + B r^(n+2)) sin n theta, u_r(R) = a cos n theta and
sigma_r theta(R) = 0 give (derivation in docs/sectioned_level.md)

    W_n = pi mu a^2 (n^2 - 1) / n          (mu = E / 3),

independent of R; it vanishes for the rigid shift n = 1. :func:`mode_energy` is this closed
form; :func:`tightknot.fem.section_modes.disk_mode_stiffness` measures the same stiffness in
the FEM's neo-Hookean solid, linear and at finite amplitude, which is what calibrates it.
"""

from __future__ import annotations

import math

import numpy as np


def _check_mode(n: int) -> None:
    if int(n) != n or n < 2:
        raise ValueError(f"mode number n must be an integer >= 2 (0 is the mean radius, 1 "
                         f"a shift of the centerline), got {n}")


def mode_stiffness(n: int, youngs_modulus: float) -> float:
    """Stiffness k_n [Pa] = [N/m per m^2] of mode ``n`` of an incompressible disk in plane
    strain: the energy per unit length is W_n = (1/2) k_n a^2 for a radial boundary
    amplitude a [m], so k_n = 2 pi mu (n^2 - 1) / n with mu = E / 3 (module docstring)."""
    _check_mode(n)
    if not youngs_modulus > 0.0:
        raise ValueError(f"youngs_modulus must be > 0 Pa, got {youngs_modulus}")
    mu = youngs_modulus / 3.0
    return 2.0 * math.pi * mu * (n * n - 1) / n


def mode_energy(n: int, amplitude: float, youngs_modulus: float) -> float:
    """Plane-strain energy per unit rod length [J/m] of mode ``n`` at radial boundary
    amplitude ``amplitude`` [m] (cosine and sine parts add: use sqrt(a^2 + b^2))."""
    return 0.5 * mode_stiffness(n, youngs_modulus) * amplitude**2


def mean_radius(area: float, modes: np.ndarray) -> float:
    """Mean radius R [m] of a section of area ``area`` [m^2] whose boundary carries the
    mode amplitudes ``modes`` [m] (shape (N - 1, 2): (a_n, b_n) for n = 2..N): the area of
    r(theta) is pi R^2 + (pi/2) sum (a_n^2 + b_n^2) exactly (Parseval). Raises ValueError
    when the modes alone hold more area than ``area``."""
    modes = np.asarray(modes, dtype=float).reshape(-1, 2)
    rest = area / math.pi - 0.5 * float(np.sum(modes**2))
    if not rest > 0.0:
        raise ValueError(f"mode amplitudes (sum of squares {float(np.sum(modes**2)):.3g} m^2) "
                         f"leave no mean radius for the area {area:.3g} m^2")
    return math.sqrt(rest)


def boundary_radius(theta: np.ndarray, radius: float, modes: np.ndarray) -> np.ndarray:
    """Radius r(theta) [m] of the section boundary at material angles ``theta`` [rad], mean
    radius ``radius`` [m], mode amplitudes ``modes`` [m] (shape (N - 1, 2), n = 2..N)."""
    theta = np.asarray(theta, dtype=float)
    modes = np.asarray(modes, dtype=float).reshape(-1, 2)
    r = np.full_like(theta, radius)
    for k, (a, b) in enumerate(modes):
        n = k + 2
        r = r + a * np.cos(n * theta) + b * np.sin(n * theta)
    return r


def mode_amplitudes(theta: np.ndarray, radial: np.ndarray, n: int) -> tuple[float, float]:
    """Fourier coefficients (a_n, b_n) [m] of radial boundary displacements ``radial`` [m]
    sampled at angles ``theta`` [rad] around the whole boundary (any spacing: trapezoid
    weights of the periodic samples)."""
    _check_mode(n)
    theta = np.asarray(theta, dtype=float)
    order = np.argsort(theta)
    t, u = theta[order], np.asarray(radial, dtype=float)[order]
    gaps = np.diff(np.concatenate([t, [t[0] + 2.0 * math.pi]]))
    weight = 0.5 * (gaps + np.roll(gaps, 1))
    return (float(np.sum(weight * u * np.cos(n * t)) / math.pi),
            float(np.sum(weight * u * np.sin(n * t)) / math.pi))
