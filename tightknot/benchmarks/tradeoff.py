"""What speed costs in accuracy: ``tightknot bench tradeoff`` (JSON rows + a Pareto PNG).

Two knots: the closed trefoil (L0/D0 16.37, the scene default) and the tight open trefoil
(L0 = 125 mm pulled by a dead force of :data:`OPEN_PULL_FORCE_N`, the force that brought
it to Lambda_OC 10.15 at 300 vertices; a fixed force, so that Lambda_OC is an output whose
error means something). Each is tied at several vertex counts, model levels (compliant or
rigid-tube contact; twist on or off, :mod:`tightknot.knots.scenes` says what each
neglects) and two Newton tolerances (``residual_tol`` of :func:`tightknot.loading.tie.tie`).
Every run is compared with the finest one (the full model, most vertices, tightest
tolerance):

- kappa error: RMS over the rod of kappa D0 against the material coordinate (rest arc
  length over L0), the finest profile interpolated linearly at each run's vertices
  (periodically for the closed knot, whose profile is compared at the best shift along
  the rod: a closed knot may settle a little further along its own material);
- measure error: |L/D - ref| (closed) or |Lambda_OC - ref| (open);
- area error: |min A/A0 - ref|;
- wall time of the whole run (tie and measurements).

The recommendation per knot is the fastest converged run within :data:`ACCEPT` of the
reference on all three errors.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

#: Pulling force on the open trefoil [N] (tie_to_lambda reached Lambda_OC 10.15 with it).
OPEN_PULL_FORCE_N = 6.08
#: Open trefoil rest length [m] (the study's tight knot).
OPEN_REST_LENGTH = 0.125
#: Acceptance for the recommendation: kappa RMS 0.05 (5 % of the outer plateau kappa D0
#: ~ 1 of the closed trefoil, below the profile noise the study reads figures at);
#: L/D within 0.5 % (0.09 at L/D ~ 18, below the 0.1 between the study's reported
#: values) or Lambda_OC within 0.1 (tie_to_lambda's tolerance); min A/A0 within 0.01.
ACCEPT = {"kappa_rms": 0.05, "closed_measure_rel": 0.005, "open_measure_abs": 0.1,
          "area_abs": 0.01}

#: Full study and the quick one: per knot, the vertex counts of the full model, the other
#: levels and the vertex counts they run at. The closed trefoil has no rigid-tube run: its
#: L0/D0 16.37 is below the ideal 16.3715, so a rigid tube can only be tied by squeezing
#: the rod along its axis against a contact 1000 times stiffer, and the tie crawls.
FULL = {
    "closed_trefoil": {"nodes": (50, 100, 200, 400, 800), "levels": ("twist_flipped",),
                       "level_nodes": (50, 100, 200)},
    "open_trefoil": {"nodes": (100, 200, 400), "levels": ("rigid", "twist_flipped"),
                     "level_nodes": (100, 200)},
}
QUICK = {
    "closed_trefoil": {"nodes": (50, 100, 200), "levels": ("twist_flipped",),
                       "level_nodes": (50, 100)},
    "open_trefoil": {"nodes": (100, 150), "levels": ("rigid", "twist_flipped"),
                     "level_nodes": (100,)},
}
TOLERANCES = (1e-3, 1e-6)


@dataclass(frozen=True)
class Level:
    """A model level: contact law and twist (None: the scene's default twist)."""

    contact: str = "compliant"
    twist: bool | None = None

    def label(self, default_twist: bool) -> str:
        tw = default_twist if self.twist is None else self.twist
        return f"{self.contact}, twist {'on' if tw else 'off'}"


def _scene(knot: str, nodes: int, level: Level):  # noqa: ANN202 (KnotScene)
    from tightknot.knots.scenes import closed_trefoil, open_trefoil

    kw: dict = {"nodes": nodes, "contact": level.contact}
    if level.twist is not None:
        kw["twist"] = level.twist
    if knot == "closed_trefoil":
        return closed_trefoil(**kw)
    if knot == "open_trefoil":
        return open_trefoil(rest_length=OPEN_REST_LENGTH, **kw)
    raise ValueError(f"knot must be 'closed_trefoil' or 'open_trefoil', got {knot!r}")


def _default_twist(knot: str) -> bool:
    return knot == "closed_trefoil"  # scenes.py: closed on, open off


class _OverBudget(Exception):
    """A run went past its time budget (raised from the progress callback)."""


def run_case(knot: str, nodes: int, level: Level, residual_tol: float,
             budget_s: float = math.inf) -> dict:
    """Tie one knot and measure it; the row keeps the profile for the comparison. A run
    still going after ``budget_s`` [s] is stopped at its next converged load step and
    recorded as failed, with its time (the study must end in bounded time)."""
    from tightknot.study.run import run_knot

    t0 = time.perf_counter()
    scene = _scene(knot, nodes, level)
    opts: dict = {"residual_tol": residual_tol, "tighten_steps": 20}
    if not scene.closed:
        opts.update(pull_force=OPEN_PULL_FORCE_N, pull_steps=20)

    def watch(*_args: object) -> None:
        if time.perf_counter() - t0 > budget_s:
            raise _OverBudget

    try:
        run = run_knot(scene, progress=watch, **opts)
    except _OverBudget:
        wall = time.perf_counter() - t0
        return {"knot": knot, "vertices": nodes, "contact": level.contact,
                "twist": bool(scene.model.twist), "level": level.label(_default_twist(knot)),
                "residual_tol": residual_tol, "converged": False,
                "failure": f"stopped after {wall:.0f} s: over the time budget of "
                           f"{budget_s:g} s per run", "wall_time_s": wall,
                "newton_iterations": -1, "measure_name": "L_over_D" if scene.closed
                else "Lambda_OC", "measure": None, "min_area_ratio": math.nan,
                "_closed": scene.closed}
    wall = time.perf_counter() - t0
    s = run.summary
    rest = scene.model.edge_rest_length
    # Material coordinate of each vertex: rest arc length over the rod's rest length.
    sigma = np.r_[0.0, np.cumsum(rest)][: scene.model.vertex_count] / rest.sum()
    measure = s["L_over_D"] if scene.closed else s.get("lambda_oc")
    return {
        "knot": knot, "vertices": nodes, "contact": level.contact,
        "twist": bool(scene.model.twist), "level": level.label(_default_twist(knot)),
        "residual_tol": residual_tol, "converged": bool(s["converged"]),
        "failure": s["failure"], "wall_time_s": wall,
        "newton_iterations": int(s["newton_iterations"]),
        "measure_name": "L_over_D" if scene.closed else "Lambda_OC",
        "measure": None if measure is None else float(measure),
        "min_area_ratio": float(s["min_area_ratio"]),
        "_sigma": sigma, "_kappa": np.asarray(s["kappa"], dtype=float),
        "_closed": scene.closed,
    }


def _profile_error(row: dict, ref: dict) -> float:
    """RMS of kappa D0 minus the reference's, against the material coordinate."""
    sig, kap = row["_sigma"], row["_kappa"]
    rs, rk = ref["_sigma"], ref["_kappa"]
    if not row["_closed"]:
        return float(np.sqrt(np.mean((kap - np.interp(sig, rs, rk)) ** 2)))
    best = math.inf
    # Shifts of the reference along the closed rod, on the finer of the two grids.
    for shift in np.linspace(0.0, 1.0, max(len(rs), len(sig)), endpoint=False):
        ref_at = np.interp((sig + shift) % 1.0, np.r_[rs, 1.0], np.r_[rk, rk[0]])
        best = min(best, float(np.sqrt(np.mean((kap - ref_at) ** 2))))
    return best


def _finite_or_none(v: float | None) -> float | None:
    return None if v is None or not math.isfinite(v) else float(v)


def compare(rows: list[dict]) -> dict:
    """Errors of every row against its knot's reference; recommendations."""
    refs: dict[str, dict] = {}
    for knot in sorted({r["knot"] for r in rows}):
        full = [r for r in rows if r["knot"] == knot and r["contact"] == "compliant"
                and r["twist"] == _default_twist(knot) and r["converged"]]
        if not full:
            raise RuntimeError(f"no converged run of the full model for {knot}: no reference")
        refs[knot] = max(full, key=lambda r: (r["vertices"], -r["residual_tol"]))
    recommend = {}
    for r in rows:
        ref = refs[r["knot"]]
        r["reference"] = r is ref
        if not r["converged"] or r["measure"] is None or ref["measure"] is None:
            r.update(kappa_rms_error=None, measure_error=None, area_error=None)
            continue
        r["kappa_rms_error"] = _profile_error(r, ref)
        r["measure_error"] = abs(r["measure"] - ref["measure"])
        r["area_error"] = abs(r["min_area_ratio"] - ref["min_area_ratio"])
    for knot, ref in refs.items():
        limit = (ACCEPT["closed_measure_rel"] * ref["measure"] if ref["_closed"]
                 else ACCEPT["open_measure_abs"])
        ok = [r for r in rows if r["knot"] == knot and not r["reference"]
              and r["kappa_rms_error"] is not None
              and r["kappa_rms_error"] <= ACCEPT["kappa_rms"]
              and r["measure_error"] <= limit and r["area_error"] <= ACCEPT["area_abs"]]
        if ok:
            best = min(ok, key=lambda r: r["wall_time_s"])
            recommend[knot] = {k: best[k] for k in ("vertices", "level", "contact", "twist",
                                                    "residual_tol", "wall_time_s",
                                                    "kappa_rms_error", "measure_error",
                                                    "area_error")}
            recommend[knot]["speedup_vs_reference"] = ref["wall_time_s"] / best["wall_time_s"]
        else:
            recommend[knot] = None
    return {"references": {k: {"vertices": v["vertices"], "residual_tol": v["residual_tol"],
                               "level": v["level"], "wall_time_s": v["wall_time_s"],
                               v["measure_name"]: v["measure"],
                               "min_area_ratio": v["min_area_ratio"]}
                           for k, v in refs.items()},
            "recommended": recommend}


def _grid(spec: dict, tolerances: tuple[float, ...]) -> list[tuple[str, int, Level, float]]:
    """The runs: the full model at every size and tolerance; the other levels (rigid
    tube; twist flipped) at the smaller sizes, every tolerance."""
    runs = []
    for knot, s in spec.items():
        dt = _default_twist(knot)
        for n in s["nodes"]:
            for tol in tolerances:
                runs.append((knot, n, Level("compliant", None), tol))
        levels = {"rigid": Level("rigid", None), "twist_flipped": Level("compliant", not dt)}
        for name in s.get("levels", ()):
            if name not in levels:
                raise ValueError(f"levels must be among {sorted(levels)}, got {name!r}")
            lev = levels[name]
            for n in s.get("level_nodes", ()):
                for tol in tolerances:
                    runs.append((knot, n, lev, tol))
    return runs


def run(spec: dict | None = None, tolerances: tuple[float, ...] = TOLERANCES,
        progress=None, budget_s: float = math.inf) -> dict:  # noqa: ANN001 (print-like)
    """Run the study (``spec`` per knot: ``nodes`` of the full model, ``levels`` and the
    ``level_nodes`` they run at); the finest full-model run is each knot's reference;
    ``budget_s``: time budget per run [s]."""
    spec = FULL if spec is None else spec
    if not tolerances or any(not (math.isfinite(t) and t > 0) for t in tolerances):
        raise ValueError(f"tolerances must be finite and > 0, got {tolerances!r}")
    rows = []
    t_all = time.perf_counter()
    for knot, n, lev, tol in _grid(spec, tuple(sorted(tolerances))):
        row = run_case(knot, n, lev, tol, budget_s)
        rows.append(row)
        if progress is not None:
            progress(f"{knot:>15s} {n:>4d} vertices, {row['level']:>22s}, tol {tol:.0e}: "
                     f"{row['wall_time_s']:7.2f} s, {row['measure_name']} "
                     f"{row['measure'] if row['measure'] is not None else float('nan'):.3f}, "
                     f"min A/A0 {row['min_area_ratio']:.3f}"
                     + ("" if row["converged"] else f"  FAILED: {row['failure'][:80]}"))
    summary = compare(rows)
    clean = []
    for r in rows:
        c = {k: v for k, v in r.items() if not k.startswith("_")}
        for k in ("measure", "min_area_ratio", "kappa_rms_error", "measure_error",
                  "area_error"):
            c[k] = _finite_or_none(c.get(k))
        clean.append(c)
    return {"rows": clean, **summary, "accept": ACCEPT, "open_pull_force_N": OPEN_PULL_FORCE_N,
            "open_rest_length_m": OPEN_REST_LENGTH, "budget_per_run_s":
            None if math.isinf(budget_s) else budget_s,
            "total_wall_time_s": time.perf_counter() - t_all}


def plot(result: dict, path: Path) -> None:
    """Pareto plot: kappa-profile error against wall time, one panel per knot (PNG)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from tightknot.atomic import atomic_open

    knots = sorted({r["knot"] for r in result["rows"]})
    fig, axes = plt.subplots(1, len(knots), figsize=(6.0 * len(knots), 4.8), squeeze=False)
    markers = {"compliant": "o", "rigid": "s"}
    for ax, knot in zip(axes[0], knots, strict=True):
        rows = [r for r in result["rows"] if r["knot"] == knot
                and r["kappa_rms_error"] is not None and not r["reference"]]
        for r in rows:
            filled = r["residual_tol"] <= 1e-5
            color = "C0" if r["twist"] == _default_twist(knot) else "C1"
            ax.loglog(r["wall_time_s"], max(r["kappa_rms_error"], 1e-6),
                      markers.get(r["contact"], "^"), color=color,
                      mfc=color if filled else "none")
            ax.annotate(str(r["vertices"]), (r["wall_time_s"], max(r["kappa_rms_error"], 1e-6)),
                        fontsize=7, xytext=(3, 3), textcoords="offset points")
        # The Pareto front: no other run is both faster and more accurate.
        pts = sorted((r["wall_time_s"], max(r["kappa_rms_error"], 1e-6)) for r in rows)
        front, best = [], math.inf
        for t, e in pts:
            if e < best:
                front.append((t, e))
                best = e
        if front:
            ax.loglog(*zip(*front, strict=True), "k--", lw=0.8, label="Pareto front")
        ax.axhline(ACCEPT["kappa_rms"], color="grey", lw=0.8, ls=":",
                   label=f"accept {ACCEPT['kappa_rms']:g}")
        ax.set_title(knot.replace("_", " "))
        ax.set_xlabel("wall time [s]")
        ax.set_ylabel("RMS error of kappa D0 vs the finest run")
        ax.grid(True, which="both", alpha=0.3)
        from matplotlib.lines import Line2D
        handles = [Line2D([], [], marker="o", ls="", color="k", label="compliant contact"),
                   Line2D([], [], marker="s", ls="", color="k", label="rigid tube"),
                   Line2D([], [], marker="o", ls="", color="C0", label="default twist"),
                   Line2D([], [], marker="o", ls="", color="C1", label="twist flipped"),
                   Line2D([], [], marker="o", ls="", color="k", mfc="none",
                          label="loose tolerance")]
        ax.legend(handles=handles + ax.get_legend_handles_labels()[0], fontsize=7)
    fig.tight_layout()
    with atomic_open(path, "wb") as handle:
        fig.savefig(handle, format="png", dpi=120)
    plt.close(fig)


# -- command line (``tightknot bench tradeoff``) ---------------------------------------------
_EXAMPLES = """examples:
  tightknot bench tradeoff --json tradeoff.json     # also writes tradeoff.png
  tightknot bench tradeoff --quick --json quick.json
  tightknot fem crosscheck --json xc.json && tightknot bench tradeoff --fem xc.json \
      --levels-json bench/contact_levels_results.json     # each contact level against the FEM
  tightknot fem crosscheck --contact sectioned --fem-json xc.json --json xcs.json
  tightknot bench tradeoff --fem xc.json --fem-sectioned xcs.json   # with the sectioned level
"""


def register(subparsers) -> None:  # noqa: ANN001 (argparse's private subparsers type)
    """Add ``tightknot bench tradeoff``."""
    import argparse

    p = subparsers.add_parser(
        "tradeoff", help="speed against accuracy: vertices, model levels, tolerances",
        description="Tie the closed and the tight open trefoil at several vertex counts, "
        "model levels and two Newton tolerances; errors against the finest run and wall "
        "times as JSON rows, and a Pareto plot (PNG next to the JSON).",
        epilog=_EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--json", metavar="FILE", help="write the result as JSON (+ FILE.png)")
    p.add_argument("--quick", action="store_true", help="a small version (a few minutes)")
    p.add_argument("--fem", metavar="XC.json",
                   help="instead of the sweep: each contact level against the FEM, read from "
                   "a cross-check report (tightknot fem crosscheck --json XC.json)")
    p.add_argument("--fem-sectioned", metavar="XCS.json", nargs="+",
                   help="with --fem: the sectioned level's cross-check reports (tightknot fem "
                   "crosscheck --contact sectioned [--section-bend-shift] --json XCS.json), "
                   "a row each")
    p.add_argument("--levels-json", metavar="CL.json",
                   help="with --fem: the knots' cost per level (bench/contact_levels.py "
                   "--json CL.json)")
    p.add_argument("--budget", type=float, default=None, metavar="S",
                   help="time budget per run [s] (default 60 with --quick, 180 otherwise); "
                   "a run over it is recorded as failed")
    p.set_defaults(handler=_command)


def _command(args) -> int:  # noqa: ANN001
    from tightknot.atomic import writable_file, write_json_atomic

    out = writable_file(args.json)
    if args.fem is not None:
        return _truth_command(args.fem, args.levels_json, out, args.fem_sectioned)
    if args.levels_json is not None or args.fem_sectioned is not None:
        raise ValueError("--levels-json and --fem-sectioned go with --fem")
    budget = args.budget if args.budget is not None else (60.0 if args.quick else 180.0)
    if not (math.isfinite(budget) and budget > 0):
        raise ValueError(f"--budget must be finite and > 0 s, got {args.budget!r}")
    result = run(QUICK if args.quick else FULL, progress=print, budget_s=budget)
    for knot, rec in result["recommended"].items():
        if rec is None:
            print(f"{knot}: no run within the acceptance of the finest one")
        else:
            print(f"{knot}: recommended {rec['vertices']} vertices, {rec['level']}, tol "
                  f"{rec['residual_tol']:g} ({rec['wall_time_s']:.1f} s, "
                  f"{rec['speedup_vs_reference']:.1f}x faster than the finest run)")
    print(f"total {result['total_wall_time_s']:.0f} s")
    if out is not None:
        write_json_atomic(out, result)
        plot(result, out.with_suffix(".png"))
    return 0


def _truth_command(fem: str, levels_json: str | None, out: Path | None,
                   sectioned: list[str] | None = None) -> int:
    """``bench tradeoff --fem XC.json``: the contact levels against the FEM."""
    import json

    from tightknot.atomic import write_json_atomic
    from tightknot.benchmarks.level_truth import format_table, level_truth

    def read(path: str, what: str) -> dict:
        try:
            return json.loads(Path(path).read_text())
        except (OSError, ValueError) as exc:
            raise ValueError(f"{what} {path}: cannot read it as JSON ({exc})") from None

    table = level_truth(read(fem, "--fem"),
                        read(levels_json, "--levels-json") if levels_json else None,
                        [read(f, "--fem-sectioned") for f in sectioned] if sectioned
                        else None)
    print(format_table(table))
    if out is not None:
        write_json_atomic(out, table)
    return 0
