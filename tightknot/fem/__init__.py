"""tightknot.fem: the small 3D solid FEM cross-check and the contact-law calibration.

Nearly incompressible neo-Hookean solids (mixed u-p, Q1/P0) in FElupe with frictionless
penalty contact against rigid plates and cylinders. FElupe is GPL-3.0 and optional
(``pip install "tightknot[fem]"``); it is imported lazily, only when a scene runs.

Public API::

    run_scene(name, mesh="coarse", max_approach_over_d0=0.3, steps=None, **options) -> dict
    SCENES  # names of the scenes: "squeeze", "indent"
    calibration.calibrate(mesh="medium"), calibration.write_law(path)
    commands.register(subparsers)  # CLI subcommands "fem" and "calibrate"
"""

from __future__ import annotations

import inspect
import time
from typing import Any

from ._backend import INSTALL_HINT, FelupeMissingError, require_felupe

SCENES: tuple[str, ...] = ("squeeze", "indent")
"""Names of the implemented FEM scenes (``wrap`` is planned, not implemented)."""

PLANNED_SCENES: tuple[str, ...] = ("wrap",)
"""Scenes of the design that are not implemented yet (run_scene refuses them)."""

DEFAULT_STEPS: dict[str, int] = {"squeeze": 12, "indent": 10}
"""Default number of load steps per scene."""

__all__ = ["SCENES", "INSTALL_HINT", "FelupeMissingError", "run_scene", "require_felupe"]


def run_scene(name: str, mesh: str = "coarse", max_approach_over_d0: float = 0.3,
              steps: int | None = None, **options: Any) -> dict[str, Any]:
    """Run the FEM scene ``name`` and return its JSON-serialisable result.

    ``mesh`` is "coarse", "medium" or "fine"; ``max_approach_over_d0`` the total approach
    of the two rigid bodies over D0 (in (0, 1); 2 w per side); ``steps`` the number of
    load steps (default per scene). ``options`` go to the scene (squeeze: ``model``
    "plane_strain" | "3d", ``ends`` "plane" | "free", ``length_over_d0``; both:
    ``convergence`` (bool, default True: also run the three meshes for the
    ``mesh_convergence`` table), ``diameter``, ``youngs_modulus``).

    Result keys: ``scene``, ``mesh``, ``parameters``, ``steps`` (list of per-step dicts),
    ``hertz``, ``mesh_convergence``, ``wall_time_s``. Raises ValueError for bad input
    (unknown scene, approach outside (0, 1), non-positive sizes) and
    :class:`FelupeMissingError` (an ImportError) when FElupe is not installed.
    """
    if name in PLANNED_SCENES:
        raise ValueError(f"name: scene {name!r} is planned but not implemented; "
                         f"valid scenes: {SCENES}")
    if name not in SCENES:
        raise ValueError(f"name must be one of {SCENES}, got {name!r}")
    if steps is None:
        steps = DEFAULT_STEPS[name]
    from .scenes import indent, squeeze

    module = {"squeeze": squeeze, "indent": indent}[name]
    allowed = set(inspect.signature(module.run).parameters) - {"mesh", "max_approach_over_d0",
                                                                "steps"}
    unknown = sorted(set(options) - allowed)
    if unknown:
        raise ValueError(f"options {unknown} are not valid for scene {name!r}; "
                         f"valid options: {sorted(allowed)}")
    start = time.perf_counter()
    result = module.run(mesh=mesh, max_approach_over_d0=max_approach_over_d0, steps=steps,
                        **options)
    result["wall_time_s"] = time.perf_counter() - start  # all meshes included
    return result
