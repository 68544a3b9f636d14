"""Contact between rods: the law, the broad phase, the energy term, the step bound, the report.

``layer`` (the energy term :class:`~tightknot.contact.layer.ContactLayer`) is composed of
``broad_phase``, ``energy`` (with ``pair_kernel``, ``pair_law`` and ``pair_assembly``),
``step_bound`` and ``checks``; ``settings`` holds its settings, ``law`` the calibrated law,
``section_radius`` the stretch-smoothed radius, ``report`` the per-vertex outputs.
"""

from tightknot._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "ContactLayer": ".layer",
    "ContactSettings": ".settings",
    "SelfIntersectionError": ".checks",
    "ContactCapacityError": ".broad_phase",
    "RadialComplianceLaw": ".law",
    "ContactReport": ".report",
    "contact_report": ".report",
})
