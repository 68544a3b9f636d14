"""A soft cantilever bent by a tip load, against the elastica (solve_bvp).

Run: python examples/cantilever.py
"""

import numpy as np

from tightknot.rods.boundary import BoundaryConditions
from tightknot.rods.builder import RodBuilder
from tightknot.rods.material import Material, second_moment
from tightknot.rods.state import State
from tightknot.solvers.continuation import ContinuationOptions, continuation
from tightknot.solvers.system import RodSystem
from tightknot.verification.elastica import cantilever_tip


def main() -> float:
    length, diameter, modulus = 0.2, 8.5e-3, 1.25e6
    n = 81
    h = length / (n - 1.5)  # clamp at the middle of the first edge (second order)
    s = -0.5 * h + h * np.arange(n)
    b = RodBuilder()
    b.add_rod(np.c_[s, 0 * s, 0 * s], diameter, Material(modulus, 0.5, 1160.0))
    model = b.finalize("cpu")
    load = 2.0 * modulus * second_moment(diameter) / length**2  # F L^2/EI = 2
    bcs = BoundaryConditions(model).clamp(0, "start").force(0, -1, [0.0, -load, 0.0])
    system = RodSystem(model, State.initial(model), bcs)
    result = continuation(system, ContinuationOptions(steps=4)).run()
    x_ref, y_ref = cantilever_tip(2.0, length)
    tip = system.state.x[-1]
    err = float(np.hypot(tip[0] - x_ref, tip[1] - y_ref) / length)
    print(f"converged={result.converged}  tip={tip[:2]} m  elastica=({x_ref:.5f}, {y_ref:.5f}) m"
          f"  error/L={err:.2e}")
    return err


if __name__ == "__main__":
    main()
