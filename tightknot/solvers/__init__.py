"""Solvers: the rod system (the one problem), its programs (the Newton loop, load
continuation, proximal steps; :mod:`tightknot.solvers.program`), implicit Euler, the linear
algebra, and the batched backend that runs many rods' programs together."""

from tightknot._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(__name__, {
    "RodSystem": ".system",
    "Inertia": ".system",
    "EnergySplit": ".system",
    "Program": ".program",
    "program": ".program",
    "Evaluate": ".program",
    "StepBound": ".program",
    "newton": ".newton",
    "NewtonOptions": ".newton",
    "NewtonResult": ".newton",
    "continuation": ".continuation",
    "ContinuationOptions": ".continuation",
    "StaticResult": ".continuation",
    "StepRecord": ".continuation",
    "proximal": ".dynamic",
    "implicit_euler_step": ".dynamic",
    "kinetic_energy": ".dynamic",
    "run_lockstep": ".lockstep",
    "BatchRod": ".lockstep",
})
