"""Benchmark of the FEM scenes: wall time, element count and headline outputs per mesh.

Usage: ``python bench/fem_scenes.py [--scenes squeeze indent wrap soft_wrap clasp]
[--meshes coarse medium] [--steps N] [--solver pardiso|cholmod|superlu] [--json out.json]``.
``--solver`` picks the FEM Newton's sparse solver (:mod:`tightknot.fem.linsolve`), so that
two runs measure its speed-up. Needs the optional extra (pip install "tightknot[fem]").
"""

from __future__ import annotations

import argparse
import json
import os
import time

from tightknot.fem import run_scene

CASES = {
    "squeeze": [dict(model="plane_strain"), dict(model="3d", ends="plane"),
                dict(model="3d", ends="free")],
    "indent": [dict()],
    "wrap": [dict()],  # force-controlled: tension up to 0.25 E D0^2, wrap angle 90 degrees
    # two soft rods (barrier contact), without their rigid counterparts
    "soft_crossing": [dict(compare=False)],
    "soft_wrap": [dict(compare=False)],
    "clasp": [dict()],
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=list(CASES))
    parser.add_argument("--meshes", nargs="+", default=["coarse", "medium"])
    parser.add_argument("--steps", type=int, default=None, help="load steps (scene default)")
    parser.add_argument("--solver", default=None, help="pardiso | cholmod | superlu | auto")
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    if args.solver is not None:
        from tightknot.fem.linsolve import ENV_VAR, check_solver

        os.environ[ENV_VAR] = check_solver(args.solver)
    rows = []
    for scene in args.scenes:
        for options in CASES[scene]:
            for mesh in args.meshes:
                start = time.perf_counter()
                result = run_scene(scene, mesh=mesh, steps=args.steps, convergence=False,
                                   **options)
                last = result["steps"][-1]
                from tightknot.fem.linsolve import resolve

                row = {"scene": scene, **options, "mesh": mesh, "solver": resolve(),
                       "elements": result["mesh"]["elements"],
                       "wall_time_s": round(time.perf_counter() - start, 2),
                       "newton_iterations": sum(s["newton_iterations"] for s in result["steps"]),
                       "last_step": {k: v for k, v in last.items() if isinstance(v, float)}}
                print(json.dumps(row), flush=True)
                rows.append(row)
    if args.json:
        with open(args.json, "w") as handle:
            json.dump(rows, handle, indent=2)


if __name__ == "__main__":
    main()
