"""Contact between rods: the calibrated radial-compliance law, the contact layer (the energy
term with its broad phase and step bound) and the per-vertex report (width, pressure,
area)."""

from tightknot._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "ContactLayer": ".layer",
    "SelfIntersectionError": ".layer",
    "ContactCapacityError": ".layer",
    "RadialComplianceLaw": ".law",
    "ContactReport": ".report",
    "contact_report": ".report",
})
