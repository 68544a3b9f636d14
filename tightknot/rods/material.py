"""Rod material: Young's modulus, Poisson ratio, density, and the section laws they imply.

The stretch law is the incompressible neo-Hookean solid in uniaxial tension
(shear modulus mu = E/3, Treloar 1975; Ogden 1997 sec. 7.2): its energy density
W(lambda) = mu/2 (lambda^2 + 2/lambda - 3) reduces to E eps^2/2 for small strain
for any Poisson ratio. The Poisson ratio sets how the section thins with stretch,
r = r0 lambda^(-nu) (nu = 1/2: r0/sqrt(lambda), volume conserved), the shear modulus
G = E/(2(1+nu)) of the twist stiffness, and the study's reduced diameter
D = D0 [1 - nu (L - L0)/L0] (physics.md sec. 2).
"""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Material:
    """Isotropic elastic material of a rod.

    Attributes:
        youngs_modulus: E [Pa], > 0.
        poisson_ratio: nu [-], in (-1, 0.5].
        density: rho [kg/m^3], >= 0 (only inertia and gravity use it).
    """

    youngs_modulus: float = 1.25e6
    poisson_ratio: float = 0.5
    density: float = 1160.0

    def __post_init__(self) -> None:
        check_positive("youngs_modulus", self.youngs_modulus, "Pa")
        nu = _as_float("poisson_ratio", self.poisson_ratio, "in (-1, 0.5]")
        if not math.isfinite(nu) or not (-1.0 < nu <= 0.5):
            raise ValueError(f"poisson_ratio must be in (-1, 0.5], got {self.poisson_ratio!r}")
        rho = _as_float("density", self.density, ">= 0 kg/m^3")
        if not math.isfinite(rho) or rho < 0.0:
            raise ValueError(f"density must be a finite value >= 0 kg/m^3, got {self.density!r}")

    @property
    def shear_modulus(self) -> float:
        """G = E / (2 (1 + nu)) [Pa] (twist stiffness GJ)."""
        return self.youngs_modulus / (2.0 * (1.0 + self.poisson_ratio))

    @property
    def neo_hookean_mu(self) -> float:
        """Shear modulus of the incompressible neo-Hookean stretch law, mu = E/3 [Pa]."""
        return self.youngs_modulus / 3.0

    @property
    def thinning_exponent(self) -> float:
        """Exponent q of the bend/twist stiffness factor (l/l_bar)^(-q), q = 4 nu + 1.

        EI scales with r^4 = r0^4 lambda^(-4 nu); the energy per deformed Voronoi length
        adds one more power of lambda (see ``tightknot.rods.elastic_kernels``).
        """
        return 4.0 * self.poisson_ratio + 1.0


def _as_float(name: str, value: object, valid: str) -> float:
    """``float(value)`` or a ValueError naming the parameter and its valid range."""
    try:
        return float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number {valid}, got {value!r}") from None


def check_positive(name: str, value: float, unit: str) -> float:
    """Return ``float(value)`` or raise ValueError naming ``name`` when not finite and > 0."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number > 0 {unit}, got {value!r}") from None
    if not math.isfinite(v) or v <= 0.0:
        raise ValueError(f"{name} must be finite and > 0 {unit}, got {value!r}")
    return v


def section_area(diameter: float) -> float:
    """A0 = pi D^2 / 4 [m^2]."""
    return math.pi * diameter**2 / 4.0


def second_moment(diameter: float) -> float:
    """I = pi D^4 / 64 [m^4] of a circular section."""
    return math.pi * diameter**4 / 64.0
