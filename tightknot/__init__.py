"""tightknot: tight physical knots in elastic rods.

Discrete elastic rods (Bergou et al. 2008, 2010) with kernels in NVIDIA Warp, a
radial-compliance self-contact layer, knot scenes and measurements of the reference
study (Johanns et al., Extreme Mech. Lett. 2021), and a small 3D solid FEM cross-check.
SI units everywhere inside; non-dimensional numbers only in measurements and plots.

The layers, each a subpackage, in the order they build on each other: ``rods`` (model,
state, elastic energies) -> ``contact`` (the contact law and layer) -> ``solvers`` (the rod
system and its programs) and ``knots`` (curves, topology, measurements, scenes) ->
``loading`` (tying and pulling) -> ``viz`` (logs and figures) -> ``study`` (one knot run) ->
``sweep``, ``fem``, ``verification``, ``benchmarks`` -> ``app`` (the command line). The
names below are the ones the README's tour uses; each subpackage exports its own.
"""

__version__ = "0.1.0"

from tightknot._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "RodBuilder": ".rods.builder",
    "BoundaryConditions": ".rods.boundary",
    "Material": ".rods.material",
    "State": ".rods.state",
    "ContactLayer": ".contact.layer",
    "contact_report": ".contact.report",
    "RodSystem": ".solvers.system",
    "newton": ".solvers.newton",
    "NewtonOptions": ".solvers.newton",
    "continuation": ".solvers.continuation",
    "ContinuationOptions": ".solvers.continuation",
    "implicit_euler_step": ".solvers.dynamic",
    "closed_trefoil": ".knots.scenes",
    "open_trefoil": ".knots.scenes",
    "closed_figure_eight": ".knots.scenes",
    "open_figure_eight": ".knots.scenes",
    "analyze_centerline": ".knots.measure",
    "read_centerline": ".knots.centerline_io",
    "knot_type": ".knots.topology",
    "tie": ".loading.tie",
    "tie_to_lambda": ".loading.pull",
    "tie_batch": ".loading.batch",
    "run_knot": ".study.run",
    "logging_hook": ".study.run",
    "RerunLogger": ".viz.rerun_log",
    "NullLogger": ".viz.rerun_log",
    "run_sweep": ".sweep.sweep",
    "grid": ".sweep.cases",
})
