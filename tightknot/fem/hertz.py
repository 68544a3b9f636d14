"""Small-strain elastic contact formulas (Hertz) used to check the FEM at small loads.

All for frictionless contact of an elastic body (Young's modulus E [Pa], Poisson ratio
nu) with a RIGID body, so the contact modulus is E* = E / (1 - nu^2) (Johnson, "Contact
Mechanics", Cambridge 1985, eq. (4.22) with the rigid body's compliance set to zero;
two identical elastic bodies would give E / (2 (1 - nu^2)) instead).
"""

from __future__ import annotations

import math

from scipy.optimize import brentq


def contact_modulus_rigid(youngs_modulus: float, poisson: float) -> float:
    """E* [Pa] of an elastic body on a rigid one, E / (1 - nu^2) (Johnson 1985, eq. 4.22)."""
    return youngs_modulus / (1.0 - poisson**2)


def line_half_width(force_per_length: float, radius: float, e_star: float) -> float:
    """Half-width b [m] of a cylinder on a flat, b = sqrt(4 P R / (pi E*)).

    Johnson (1985) eq. (4.43); P [N/m] the force per unit length, R [m] the radius.
    """
    return math.sqrt(4.0 * force_per_length * radius / (math.pi * e_star))


def line_peak_pressure(force_per_length: float, half_width: float) -> float:
    """Peak pressure p0 [Pa] of the line contact, p0 = 2 P / (pi b) (Johnson 1985, eq. 4.44)."""
    return 2.0 * force_per_length / (math.pi * half_width)


def line_approach_per_side(force_per_length: float, radius: float, youngs_modulus: float,
                           poisson: float) -> float:
    """Approach w [m] of the centre of a disk to a rigid flat it is pressed on (plane strain).

    w = P (1 - nu^2) / (pi E) (2 ln(4 R / b) - 1), b from eq. (4.43). This is the
    displacement of the centre of a circular cylinder relative to its contact line when
    it is compressed between two diametrically opposite line loads spread as Hertz
    pressures (Johnson 1985, sec. 5.6, eq. 5.36: the diameter of a cylinder between two
    plates shortens by twice this). The 2D approach is defined only relative to a
    chosen point of the body; here that point is the section centre, which is exactly the
    per-side overlap w used by the rod model.
    """
    if force_per_length <= 0.0:
        return 0.0
    e_star = contact_modulus_rigid(youngs_modulus, poisson)
    b = line_half_width(force_per_length, radius, e_star)
    return force_per_length * (1.0 - poisson**2) / (math.pi * youngs_modulus) * (
        2.0 * math.log(4.0 * radius / b) - 1.0
    )


def line_force_per_length(approach: float, radius: float, youngs_modulus: float,
                          poisson: float) -> float:
    """Inverse of :func:`line_approach_per_side`: P [N/m] for an approach w [m] per side."""
    if approach <= 0.0:
        return 0.0
    scale = youngs_modulus * radius

    def residual(p: float) -> float:
        return line_approach_per_side(p, radius, youngs_modulus, poisson) - approach

    # w(P) rises while b < 4R/e; bracket up to P = E R (b about 0.98 R), far beyond the
    # small-strain range where this formula means anything
    return brentq(residual, 1e-14 * scale, scale, xtol=1e-16 * scale, rtol=1e-13)


def sphere_force(approach: float, radius: float, e_star: float) -> float:
    """Hertz force F [N] of a sphere of radius R [m] on a flat at approach d [m].

    F = (4/3) E* R^(1/2) d^(3/2) (Johnson 1985, eq. 4.23). Two cylinders of equal radius R
    crossed at 90 degrees are equivalent to a sphere of radius R on a flat (Johnson 1985,
    sec. 4.2: the relative curvatures 1/(2R) are equal in both directions, so the contact
    is circular with equivalent radius sqrt(R' R'') = R).
    """
    return 4.0 / 3.0 * e_star * math.sqrt(radius) * max(approach, 0.0) ** 1.5


def sphere_contact_radius(approach: float, radius: float) -> float:
    """Contact radius a [m] = sqrt(R d) of the sphere-on-flat contact (Johnson 1985, eq. 4.22)."""
    return math.sqrt(radius * max(approach, 0.0))


def sphere_peak_pressure(force: float, contact_radius: float) -> float:
    """Peak pressure p0 [Pa] = 3 F / (2 pi a^2) (Johnson 1985, eq. 4.21)."""
    return 3.0 * force / (2.0 * math.pi * contact_radius**2)
