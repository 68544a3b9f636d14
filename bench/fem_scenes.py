"""Benchmark of the FEM scenes: wall time, element count and headline outputs per mesh.

Usage: ``python bench/fem_scenes.py [--scenes squeeze indent wrap] [--meshes coarse medium]
[--json out.json]``. Needs the optional extra (pip install "tightknot[fem]").
"""

from __future__ import annotations

import argparse
import json
import time

from tightknot.fem import run_scene

CASES = {
    "squeeze": [dict(model="plane_strain"), dict(model="3d", ends="plane"),
                dict(model="3d", ends="free")],
    "indent": [dict()],
    "wrap": [dict()],  # force-controlled: tension up to 0.25 E D0^2, wrap angle 90 degrees
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=list(CASES))
    parser.add_argument("--meshes", nargs="+", default=["coarse", "medium"])
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    rows = []
    for scene in args.scenes:
        for options in CASES[scene]:
            for mesh in args.meshes:
                start = time.perf_counter()
                result = run_scene(scene, mesh=mesh, convergence=False, **options)
                last = result["steps"][-1]
                row = {"scene": scene, **options, "mesh": mesh,
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
