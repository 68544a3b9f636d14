"""The three-case bit-identity check of refactors (ground rule 7).

Runs three canonical solves and records, for each, the final positions (every bit), the Newton
iteration counts and every scaled residual the solvers computed (all Newton iterations of all
load steps, failed attempts and proximal steps included, in the order they were computed):

* ``open``: a 101-vertex open trefoil (L0 = 185 mm) tied and pulled to 2 N;
* ``closed``: a 60-vertex closed trefoil tied to L0/D0 = 16.37;
* ``batch``: two closed trefoils (60 vertices, L0/D0 17 and 18) tied together in one model.

A fourth case, ``lambda``, pulls a 101-vertex 125 mm knot to Lambda_OC 10.1 (the force search
with its bracketing); ``smoothed`` ties the 60-vertex closed trefoil at the smoothed contact
level (the kernel's given-radius path); ``sectioned`` ties it at the sectioned level (its
section coefficients recorded too). The three run with ``--all``.

Usage::

    python bench/bit_identity.py --out before.json            # on the old tree
    python bench/bit_identity.py --out after.json --compare before.json

``--compare`` exits 1 and names the first difference when any recorded number differs in
any bit. The records depend on the machine and the Warp build, so compare two runs made on
one machine, never against a file from elsewhere.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import time
from pathlib import Path


def _residual_recorder():
    """Patch the rod system's residual norm so that every value it returns is recorded."""
    from tightknot.solvers.system import RodSystem
    log: list[float] = []
    original = RodSystem.residual_norm

    def recorded(self, g):
        r = original(self, g)
        log.append(r)
        return r

    RodSystem.residual_norm = recorded
    return log


def _ran(result):
    """A load path's result: programs (this tree) are run, results (older trees) kept."""
    return result.run() if hasattr(type(result), "run") else result


def _digest(*arrays) -> str:
    h = hashlib.sha256()
    for a in arrays:
        h.update(a.tobytes())
    return h.hexdigest()


def _case_open():
    from tightknot.knots.scenes import open_trefoil
    try:
        from tightknot.loading.tie import tie
    except ImportError:  # the tree before issue 16
        from tightknot.knots.tie import tie  # type: ignore[no-redef]
    res = _ran(tie(open_trefoil(rest_length=0.185, nodes=101), pull_force=2.0,
                   tighten_steps=20, pull_steps=10))
    st = res.system.state
    return res, [st.x, st.theta]


def _case_closed(contact: str = "compliant"):
    from tightknot.knots.scenes import closed_trefoil
    try:
        from tightknot.loading.tie import tie
    except ImportError:  # the tree before issue 16
        from tightknot.knots.tie import tie  # type: ignore[no-redef]
    res = _ran(tie(closed_trefoil(nodes=60, contact=contact), tighten_steps=20))
    st = res.system.state
    return res, [st.x, st.theta]


def _case_smoothed():
    return _case_closed("smoothed")


def _case_sectioned():
    res, arrays = _case_closed("sectioned")
    return res, [*arrays, res.system.state.extra]


def _case_batch():
    from tightknot.knots.scenes import closed_trefoil
    try:
        from tightknot.loading.batch import tie_batch
    except ImportError:  # the tree before issue 16
        from tightknot.knots.batch import tie_batch  # type: ignore[no-redef]
    res = tie_batch([closed_trefoil(l0_over_d0=v, nodes=60) for v in (17.0, 18.0)],
                    tighten_steps=20)
    return res, list(res.positions)


def _case_lambda():
    from tightknot.knots.scenes import open_trefoil
    try:
        from tightknot.loading.pull import tie_to_lambda
    except ImportError:  # the tree before issue 16
        from tightknot.knots.tie import tie_to_lambda  # type: ignore[no-redef]
    res = _ran(tie_to_lambda(open_trefoil(rest_length=0.125, nodes=101), 10.1))
    st = res.system.state
    return res, [st.x, st.theta]


CASES = {"open": _case_open, "closed": _case_closed, "batch": _case_batch,
         "lambda": _case_lambda, "smoothed": _case_smoothed, "sectioned": _case_sectioned}
DEFAULT = ("open", "closed", "batch")


def run(names) -> dict:
    out = {}
    for name in names:
        log = _residual_recorder()
        t0 = time.perf_counter()
        res, arrays = CASES[name]()
        out[name] = {
            "converged": bool(res.converged),
            "failure": res.failure,
            "newton_iterations": int(res.newton_iterations),
            "positions_sha256": _digest(*arrays),
            "residual_count": len(log),
            "residuals": [float(r).hex() for r in log],
            "wall_time_s": time.perf_counter() - t0,
        }
        print(f"{name:9s} converged={res.converged} iterations={res.newton_iterations} "
              f"residuals={len(log)} sha={out[name]['positions_sha256'][:16]} "
              f"{out[name]['wall_time_s']:.1f} s", flush=True)
    return out


def compare(now: dict, before: dict) -> list[str]:
    diffs = []
    for name, rec in now.items():
        old = before.get(name)
        if old is None:
            diffs.append(f"{name}: not in the reference file")
            continue
        for key in ("converged", "failure", "newton_iterations", "positions_sha256",
                    "residual_count"):
            if rec[key] != old[key]:
                diffs.append(f"{name}: {key} {old[key]!r} -> {rec[key]!r}")
        for i, (a, b) in enumerate(zip(old["residuals"], rec["residuals"], strict=False)):
            if a != b:
                diffs.append(f"{name}: residual {i} {float.fromhex(a)!r} -> "
                             f"{float.fromhex(b)!r}")
                break
    return diffs


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", required=True, help="write the records here (JSON)")
    ap.add_argument("--compare", help="a record file of the same cases to compare with")
    ap.add_argument("--all", action="store_true",
                    help="also the lambda, smoothed and sectioned cases")
    ap.add_argument("--case", action="append", choices=list(CASES), help="only this case")
    args = ap.parse_args(argv)
    names = args.case or (list(CASES) if args.all else list(DEFAULT))
    now = run(names)
    Path(args.out).write_text(json.dumps(now, indent=1))
    if args.compare:
        diffs = compare(now, json.loads(Path(args.compare).read_text()))
        if diffs:
            print("DIFFERENT:\n  " + "\n  ".join(diffs))
            return 1
        print("bit-identical: positions, iteration counts and every residual")
    return 0


if __name__ == "__main__":
    sys.exit(main())
