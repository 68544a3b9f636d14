"""Contact between rods: the law, the broad phase, the energy term, the step bound, the report.

``layer`` (the energy term :class:`~tightknot.contact.layer.ContactLayer`) is composed of
``broad_phase``, ``energy`` (with ``pair_kernel``, ``pair_law`` and ``pair_assembly``),
``step_bound`` and ``checks``; ``settings`` holds its settings, ``law`` the calibrated law,
``section_radius`` the stretch-smoothed radius, ``report`` the per-vertex outputs.
"""
