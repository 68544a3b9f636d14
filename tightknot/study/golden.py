"""Golden curvature profiles of the canonical runs (the demo's three knots).

``python -m tightknot.study.golden --write`` regenerates ``tests/golden/*.json``; the test
``tests/study/test_golden.py`` recomputes the runs and compares. Regenerate only on purpose
(a physics or solver change whose effect you have checked), and say so in the commit.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from tightknot.atomic import write_json_atomic
from tightknot.knots.scenes import closed_trefoil, open_trefoil
from tightknot.study.run import KnotRun, run_knot

#: name -> (builder, tie options): the demo's three knots. The open ones are pulled by the
#: fixed force that brings them to the study's Lambda_OC (15.0 and 10.1; the test checks it
#: within the issue's 0.2): a fixed force has one equilibrium, whereas a run to a target
#: Lambda_OC stops anywhere in its tolerance band, wherever round-off steers the force
#: search (a 1e-9 relative change of the contact Hessian moved Lambda_OC by 0.13).
CANONICAL = {
    "closed_trefoil": (lambda: closed_trefoil(nodes=100), {"tighten_steps": 40}),
    "open_185mm": (lambda: open_trefoil(rest_length=0.185, nodes=150),
                   {"pull_force": 1.8, "tighten_steps": 20, "pull_steps": 20}),
    "open_125mm": (lambda: open_trefoil(rest_length=0.125, nodes=100),
                   {"pull_force": 7.43, "tighten_steps": 20, "pull_steps": 20}),
}
#: The study's Lambda_OC of the open canonical knots.
TARGET_LAMBDA = {"open_185mm": 15.0, "open_125mm": 10.1}


def run_canonical(name: str) -> KnotRun:
    """Run one canonical knot."""
    build, options = CANONICAL[name]
    return run_knot(build(), **dict(options))


def profile(run: KnotRun) -> dict:
    """The stored profile: s, kappa*D0 and the headline numbers."""
    s = run.summary
    out = {"s": s["s"], "kappa": s["kappa"], "stretch": s["stretch"], "L_over_D": s["L_over_D"]}
    if s.get("lambda_oc") is not None:
        out["lambda_oc"] = s["lambda_oc"]
        out["pull_force_N"] = s["pull_force_N"]
    return out


def main(argv: list[str] | None = None) -> int:
    """Regenerate the golden files (``--write``), or print how far the runs are from them."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--write", action="store_true", help="overwrite tests/golden/*.json")
    ap.add_argument("--folder", default="tests/golden", help="golden folder")
    args = ap.parse_args(argv)
    folder = Path(args.folder)
    if not folder.is_dir():
        print(f"golden folder does not exist: {folder}", file=sys.stderr)
        return 2
    for name in CANONICAL:
        prof = profile(run_canonical(name))
        path = folder / f"{name}.json"
        if args.write:
            write_json_atomic(path, prof)
            print(f"wrote {path}")
        elif path.exists():
            import json

            old = json.loads(path.read_text())
            dk = float(np.max(np.abs(np.asarray(old["kappa"]) - np.asarray(prof["kappa"]))))
            print(f"{name}: max |kappa D0 - golden| = {dk:.3g}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
