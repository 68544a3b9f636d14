"""Material and geometry of the reference rod, and the nearly incompressible solid.

Values from the reference study (Johanns et al., Extreme Mech. Lett. 2021, Table in
docs/physics.md section 1): vinyl polysiloxane, E = 1.25 MPa, incompressible
neo-Hookean, D0 = 8.5 mm.

The solid is the mixed displacement-pressure (u, p, J-bar) three-field formulation with
cell-wise constant pressure and volume ratio (Q1/P0 "mean dilatation", the analogue of
ABAQUS C3D8H hybrid hexahedra), as implemented by FElupe's
``SolidBodyNearlyIncompressible``: the isochoric neo-Hookean energy
psi = mu/2 (J^(-2/3) I1 - 3) plus U(J-bar) = K/2 (J-bar - 1)^2 (Bonet, Gil & Wood 2016,
"Nonlinear Solid Mechanics", sec. 8.6; FElupe docs of SolidBodyNearlyIncompressible).
"""

from __future__ import annotations

from typing import Any

from ._backend import require_felupe

YOUNGS_MODULUS: float = 1.25e6
"""Young's modulus E [Pa] of the rod (small-strain)."""

ROD_DIAMETER: float = 8.5e-3
"""Rest diameter D0 [m] of the rod."""

SHEAR_MODULUS: float = YOUNGS_MODULUS / 3.0
"""Shear modulus mu [Pa]; E = 3 mu for an incompressible solid (nu = 1/2)."""

BULK_RATIO: float = 5000.0
"""Bulk-to-shear modulus ratio K/mu [-] of the nearly incompressible penalty."""

BULK_MODULUS: float = BULK_RATIO * SHEAR_MODULUS
"""Bulk modulus K [Pa] = 5000 mu = 2.083e9 Pa: Poisson ratio 0.49990 at small strain."""


def poisson_ratio(bulk: float = BULK_MODULUS, mu: float = SHEAR_MODULUS) -> float:
    """Small-strain Poisson ratio [-] of the solid, nu = (3K - 2mu) / (2 (3K + mu))."""
    return (3.0 * bulk - 2.0 * mu) / (2.0 * (3.0 * bulk + mu))


def nearly_incompressible_solid(field: Any, mu: float = SHEAR_MODULUS,
                                bulk: float = BULK_MODULUS) -> Any:
    """FElupe ``SolidBodyNearlyIncompressible`` with an isochoric neo-Hookean material.

    ``field`` is a FElupe ``FieldContainer`` (3D ``Field`` or ``FieldPlaneStrain``);
    ``mu`` and ``bulk`` in Pa. The pressure and volume-ratio fields are condensed per
    cell, so only the displacement unknowns enter the global system.
    """
    fem = require_felupe()
    # NeoHooke without bulk modulus is the isochoric (distortional) part only; the
    # volumetric part lives on the condensed cell-wise fields of the solid body.
    umat = fem.NeoHooke(mu=mu)
    return fem.SolidBodyNearlyIncompressible(umat=umat, field=field, bulk=bulk)
