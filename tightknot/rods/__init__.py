"""The rod model: builder, model, state, frames, material, boundary conditions and the
elastic energies (discrete elastic rods, Bergou et al. 2008, 2010), with the interface of
the energy terms added to them."""

from tightknot._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "RodBuilder": ".builder",
    "Model": ".model",
    "RodInfo": ".model",
    "State": ".state",
    "Material": ".material",
    "BoundaryConditions": ".boundary",
    "ElasticForces": ".elastic",
    "EnergyTerm": ".term",
})
