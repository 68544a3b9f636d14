"""Numerical stability at the extremes (issue 8): run every stress case, write a JSON and
print a markdown table (case, outcome with its message, wall time, Newton iterations, the
quantity that limits the case).

The cases are those of the stress suite (``tests/extremes/cases.py``), run here with the
``--run-extremes`` sizes. Usage, from the repository root::

    python bench/extremes.py [--json bench/extremes_results.json] [--quick] [--no-huge]

``--quick`` runs only the fast subset (a minute); ``--no-huge`` skips the 1e4- and
1e5-vertex cases (about 2 minutes of the total).
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("WARP_CACHE_PATH", str(ROOT / ".warp_cache"))

from tests.extremes import cases as C  # noqa: E402
from tightknot.atomic import write_json_atomic  # noqa: E402


def _cases(quick: bool, huge: bool) -> list[tuple[str, Callable[[], C.Outcome]]]:
    """(group, thunk) of every case, in table order."""
    tied: dict[str, object] = {}

    def dyn(dt: float) -> C.Outcome:
        if "k" not in tied:
            tied["k"] = C.tied_closed_trefoil(48)
        return C.dynamics(dt, tied=tied["k"], max_iterations=500)

    def f32() -> C.Outcome:
        from tightknot.knots.scenes import closed_trefoil
        from tightknot.loading.tie import tie

        start = time.perf_counter()
        scene = closed_trefoil(16.37, C.D0, 64)
        res = tie(scene, tighten_steps=40).run()
        floor = C.float32_floor(scene, res)
        ok = floor["residual_positions_rounded_to_float32"] > 1e-6
        return C.Outcome("float32 positions of the tied closed trefoil N=64",
                         "failed" if ok else "converged",
                         "kernels are float64 only; the float64 equilibrium rounded to float32 "
                         "has a residual above the 1e-6 tolerance" if ok else "",
                         time.perf_counter() - start, res.newton_iterations,
                         list(res.knot_types), floor, C.all_finite(floor))

    quick_cases = [
        ("slenderness", lambda: C.slenderness(5.0, 64)),
        ("slenderness", lambda: C.slenderness(5.0, 64, closed=False)),
        ("closed tightness", lambda: C.closed_tightness(12.0)),
        ("material", lambda: C.material(1.25e6, 0.5)),
        ("material", lambda: C.material(2e11, 0.5)),
        ("material", lambda: C.material(1.25e6, 0.0)),
        ("vertex count", lambda: C.vertex_count(24)),
        ("vertex count", lambda: C.vertex_count(36)),
        ("dynamics", lambda: dyn(1e-6)),
    ]
    if quick:
        return quick_cases
    full = [
        ("slenderness", lambda: C.slenderness(5.0, 64)),
        ("slenderness", lambda: C.slenderness(5.0, 64, closed=False)),
        ("slenderness", lambda: C.slenderness(10.0, 64)),
        ("slenderness", lambda: C.slenderness(100.0, 200)),
        ("slenderness", lambda: C.slenderness(1000.0, 2000)),
        ("slenderness", lambda: _renamed(C.slenderness(1000.0, 2000, residual_tol=1e-5),
                                         " residual_tol=1e-5")),
        ("slenderness", lambda: C.slenderness(1e4, 2000)),
    ]
    if huge:
        full.append(("slenderness", lambda: _renamed(
            C.slenderness(1e4, 13000, summary=False, relax_iterations=5),
            " (relax budget 5)")))
    # 64 vertices: the loose 40 D0 start needs >= 57 (edges <= pi/4 D0).
    full += [("closed tightness", (lambda r=r: C.closed_tightness(r, nodes=64)))
             for r in (40.0, 24.0, 16.37, 14.0, 12.0)]
    full += [("open pull", lambda: C.open_force_path(1e4)),
             ("open pull", lambda: C.open_force_path(1e-2))]
    full += [("material", (lambda e=e: C.material(e, 0.5))) for e in (1e4, 1.25e6, 1e11, 2e11)]
    full += [("material", (lambda nu=nu: C.material(1.25e6, nu))) for nu in (0.0, 0.3)]
    full += [("vertex count", (lambda n=n: C.vertex_count(n))) for n in (24, 36, 100, 400)]
    if huge:
        full += [("vertex count", _labelled(f"closed L0/D0=16.37 N={n} (relax budget 3)",
                                            lambda n=n: C.vertex_count(n, budget=3)))
                 for n in (10_000, 100_000)]
    full += [("dynamics", (lambda dt=dt: dyn(dt))) for dt in (1e-6, 1e-4, 1e-2, 1.0)]
    full.append(("float32", f32))
    return full


def _labelled(label: str, thunk: Callable[[], C.Outcome]) -> Callable[[], C.Outcome]:
    """``thunk`` carrying the case's name for the table when it raises."""
    thunk.label = label  # type: ignore[attr-defined]
    return thunk


def _renamed(out: C.Outcome, suffix: str) -> C.Outcome:
    out.case += suffix
    return out


#: The limiting quantity shown in the table, per group (the JSON has them all).
_SHOW = {
    "slenderness": ("stretch", "min_gap_over_D0", "min_vertex_gap_over_D0"),
    "closed tightness": ("stretch", "min_gap_over_D0", "min_vertex_gap_over_D0",
                         "kappa_D0_max"),
    "open pull": ("lambda_oc_min_on_path", "min_gap_over_D0", "min_vertex_gap_over_D0"),
    "material": ("stretch", "kappa_D0_max", "min_radius_over_r0"),
    "vertex count": ("stretch", "min_gap_over_D0", "min_vertex_gap_over_D0"),
    "dynamics": ("energy_growth_over_ke0", "ke_last_over_ke0"),
    "float32": ("residual_float64", "residual_positions_rounded_to_float32"),
}


def _limit_text(group: str, out: C.Outcome) -> str:
    parts = []
    for k in _SHOW.get(group, ()):
        v = out.limits.get(k)
        if v is not None:
            parts.append(f"{k} {v:.4g}")
    if group == "open pull" and out.data.get("path"):
        last = out.data["path"][-1]
        parts.append(f"last converged F {last['force_N']:.3g} N")
    return "; ".join(parts)


def _json_safe(obj):
    """``obj`` with every non-finite float replaced by None."""
    if isinstance(obj, dict):
        return {k: _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    return obj


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--json", default=str(ROOT / "bench" / "extremes_results.json"))
    p.add_argument("--quick", action="store_true", help="the fast subset only")
    p.add_argument("--no-huge", action="store_true", help="skip the 1e4/1e5-vertex cases")
    p.add_argument("--only", default="", help="run only the groups whose name holds this")
    args = p.parse_args(argv)
    rows = []
    cpu0 = time.process_time()
    wall0 = time.perf_counter()
    for group, thunk in _cases(args.quick, not args.no_huge):
        if args.only and args.only not in group:
            continue
        t0 = time.perf_counter()
        try:
            out = thunk()
            clean = True
            try:
                C.check_clean(out)
            except AssertionError as err:
                clean = False
                out.message += f" [NOT CLEAN: {err}]"
        except Exception as err:  # a case that raised is itself a finding: record it
            out = C.Outcome(getattr(thunk, "label", f"{group} #{len(rows)}") + ": raised",
                            "error",
                            f"{type(err).__name__}: {err}", time.perf_counter() - t0)
            clean = False
        row = dict(out.as_dict(), group=group, clean=clean, limit=_limit_text(group, out))
        rows.append(row)
        print(f"{row['case']}: {row['outcome']} ({row['wall_s']:.1f} s, "
              f"{row['newton_iterations']} it) {row['message'][:120]}", file=sys.stderr,
              flush=True)
    result = {
        "machine": {"platform": platform.platform(), "python": platform.python_version(),
                    "cpu_count": os.cpu_count()},
        "total_wall_s": time.perf_counter() - wall0,
        "total_cpu_s": time.process_time() - cpu0,
        "cases": rows,
    }
    # Finiteness is judged per case above; the file stays strict JSON (inf -> null).
    write_json_atomic(args.json, _json_safe(result))
    print("| group | case | outcome | message | wall [s] | Newton it. | limiting quantity |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        msg = r["message"].replace("|", "/")
        if len(msg) > 160:
            msg = msg[:157] + "..."
        print(f"| {r['group']} | {r['case']} | {r['outcome']}{'' if r['clean'] else ' (NOT CLEAN)'}"
              f" | {msg} | {r['wall_s']:.1f} | {r['newton_iterations']} | {r['limit']} |")
    print(f"\ntotal: {result['total_wall_s']:.0f} s wall, {result['total_cpu_s']:.0f} s CPU "
          f"(this process); JSON: {args.json}")
    return 0 if all(r["clean"] for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
