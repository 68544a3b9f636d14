"""tightknot.fem: the small 3D solid FEM cross-check and the contact-law calibration.

Nearly incompressible neo-Hookean solids (mixed u-p, Q1/P0) in FElupe with frictionless
penalty contact against rigid plates and cylinders, and barrier contact (ipctk, the IPC
Toolkit) between two deformable rods in the ``soft_*`` scenes. FElupe is GPL-3.0 and optional
(``pip install "tightknot[fem]"``); it is imported lazily, only when a scene runs.

Public API::

    run_scene(name, mesh="coarse", max_approach_over_d0=None, steps=None, **options) -> dict
    SCENES  # "squeeze", "indent", "wrap", "soft_squeeze", "soft_crossing", "soft_wrap", "clasp"
    calibration.calibrate(mesh="medium"), calibration.write_law(path)
    crosscheck.crosscheck(mesh="coarse")  # FEM vs rod model: indent, wrap, soft_wrap, clasp
    commands.register(subparsers)  # CLI subcommands "fem", "calibrate", "fem crosscheck"
"""

from __future__ import annotations

import inspect
import time
from typing import Any

from ._backend import INSTALL_HINT, FelupeMissingError, require_felupe

SCENES: tuple[str, ...] = ("squeeze", "indent", "wrap", "soft_squeeze", "soft_crossing",
                           "soft_wrap", "clasp")
"""Names of the implemented FEM scenes."""

SOFT_SCENES: tuple[str, ...] = ("soft_squeeze", "soft_crossing", "soft_wrap", "clasp")
"""Scenes with two deformable rods in barrier contact (need ipctk as well as FElupe)."""

DEFAULT_STEPS: dict[str, int] = {"squeeze": 12, "indent": 10, "wrap": 6, "soft_squeeze": 4,
                                 "soft_crossing": 4, "soft_wrap": 6, "clasp": 6}
"""Default number of load steps per scene."""

__all__ = ["SCENES", "INSTALL_HINT", "FelupeMissingError", "run_scene", "require_felupe"]


DEFAULT_APPROACH: float = 0.3
"""Default total approach over D0 of the displacement-controlled scenes."""


def run_scene(name: str, mesh: str = "coarse", max_approach_over_d0: float | None = None,
              steps: int | None = None, **options: Any) -> dict[str, Any]:
    """Run the FEM scene ``name`` and return its JSON-serialisable result.

    ``mesh`` is "coarse", "medium" or "fine"; ``max_approach_over_d0`` the total approach
    of the two bodies over D0 (in (0, 1); 2 w per side; default 0.3; squeeze, indent,
    soft_squeeze and soft_crossing only: ``wrap`` and ``soft_wrap`` are force-controlled
    and take ``max_tension_over_e_d0sq`` instead, ``clasp`` takes ``max_pull_over_d0``);
    ``steps`` the number of load steps (default per scene). ``options`` go to the scene
    (squeeze: ``model`` "plane_strain" | "3d", ``ends`` "plane" | "free",
    ``length_over_d0``; wrap, soft_wrap: ``max_tension_over_e_d0sq``, ``wrap_angle_deg``,
    ``length_over_d0``; clasp: ``max_pull_over_d0``, ``bend_radius_over_d0``,
    ``leg_length_over_d0``; soft_squeeze, soft_crossing, soft_wrap: ``compare`` (bool,
    default True: also run the rigid counterpart, ``squeeze``, ``indent`` or ``wrap``);
    the two-soft-body scenes: ``dhat_over_d0``; all: ``convergence`` (bool, default True,
    False for the two-soft-body scenes: also run the three meshes for the
    ``mesh_convergence`` table), ``diameter``, ``youngs_modulus``).

    Result keys: ``scene``, ``mesh``, ``parameters``, ``steps`` (list of per-step dicts),
    ``hertz``, ``mesh_convergence``, ``wall_time_s``. Raises ValueError for bad input
    (unknown scene, approach outside (0, 1), non-positive sizes) and
    :class:`FelupeMissingError` (an ImportError) when FElupe is not installed.
    """
    if name not in SCENES:
        raise ValueError(f"name must be one of {SCENES}, got {name!r}")
    if steps is None:
        steps = DEFAULT_STEPS[name]
    from .scenes import clasp, indent, soft_crossing, soft_squeeze, soft_wrap, squeeze, wrap

    module = {"squeeze": squeeze, "indent": indent, "wrap": wrap,
              "soft_squeeze": soft_squeeze, "soft_crossing": soft_crossing,
              "soft_wrap": soft_wrap, "clasp": clasp}[name]
    loads: dict[str, Any] = {}
    if name in ("wrap", "soft_wrap"):
        if max_approach_over_d0 is not None:
            raise ValueError("max_approach_over_d0 is not a parameter of the force-controlled "
                             f"scene {name!r}: give max_tension_over_e_d0sq (tension over "
                             "E D0^2) instead")
    elif name == "clasp":
        if max_approach_over_d0 is not None:
            raise ValueError("max_approach_over_d0 is not a parameter of the scene 'clasp': "
                             "give max_pull_over_d0 (the clamps' separation change over D0) "
                             "instead")
    else:
        loads["max_approach_over_d0"] = (DEFAULT_APPROACH if max_approach_over_d0 is None
                                         else max_approach_over_d0)
    allowed = set(inspect.signature(module.run).parameters) - {"mesh", "max_approach_over_d0",
                                                                "steps"}
    unknown = sorted(set(options) - allowed)
    if unknown:
        raise ValueError(f"options {unknown} are not valid for scene {name!r}; "
                         f"valid options: {sorted(allowed)}")
    start = time.perf_counter()
    result = module.run(mesh=mesh, steps=steps, **loads, **options)
    result["wall_time_s"] = time.perf_counter() - start  # all meshes included
    return result
