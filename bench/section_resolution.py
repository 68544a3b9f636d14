"""How the sectioned level's light contacts depend on the rod's resolution: the FEM
cross-check's indent and wrap (rod model only, :mod:`tightknot.fem.rod_sectioned`) at the
three lightest levels, over edges per D0, boundary samples M per section and Gauss points
per edge.

The cross-check runs 12 edges per D0, M = 64 and 2 Gauss points. Where a contact patch is
narrower than the samples' spacing (about 0.05 D0 both ways there) its force depends on
where the patch falls among the samples; this script measures by how much, and what the
finer resolutions converge to. With ``--fem-json`` (a cross-check report holding
``indent`` and ``wrap`` FEM results, ``tightknot fem crosscheck ... --json F``) each value
is also given relative to the FEM.

Usage: ``python bench/section_resolution.py [--edges 12 24 48] [--samples 64 128]
[--gauss 2 3] [--thinning edge|rod] [--fem-json F] [--json out.json]``.
"""

from __future__ import annotations

import argparse
import json
import time

from tightknot.atomic import write_json_atomic
from tightknot.contact.sectioned import SectionSettings
from tightknot.fem.material import ROD_DIAMETER, YOUNGS_MODULUS
from tightknot.fem.rod_sectioned import rod_indent_sectioned, rod_wrap_sectioned

#: The indent's three lightest approaches and the wrap's three lightest tensions of the
#: FEM cross-check (approach / D0; T / (E D0^2)).
APPROACHES = (0.003, 0.012, 0.027)
TENSIONS = (0.0069, 0.0278, 0.0625)


def _fem_levels(path: str | None) -> tuple[dict, dict]:
    """The FEM's indent force and wrap mid line load [over E D0^2, E D0] by level."""
    if path is None:
        return {}, {}
    with open(path) as f:
        rep = json.load(f)
    fem = rep.get("fem", rep)
    indent = {round(r["approach_over_d0"], 3): r["force_over_e_d0sq"]
              for r in fem["indent"]["steps"]}
    wrap = {round(r["tension_over_e_d0sq"], 4): r["force_per_length_mid_nominal_over_e_d0"]
            for r in fem["wrap"]["steps"]}
    return indent, wrap


def _rel(value: float, fem: dict, key: float, fmt: str) -> str:
    """``value`` formatted, with its relative difference to the FEM's where known."""
    text = format(value, fmt)
    return text + (f" ({value / fem[key] - 1.0:+.1%})" if key in fem else "")


def run(edges: int, samples: int, gauss: int, thinning: str = "edge") -> dict:
    """The indent and wrap rows at one resolution (``thinning``: the sections', see
    :class:`~tightknot.contact.sectioned.SectionSettings`)."""
    d0, e = ROD_DIAMETER, YOUNGS_MODULUS
    section = SectionSettings(samples=samples, thinning=thinning)
    t0 = time.perf_counter()
    ind = rod_indent_sectioned([0.5 * a * d0 for a in APPROACHES], section=section,
                               edges_per_d0=edges, gauss_points=gauss)
    wrap = rod_wrap_sectioned([t * e * d0**2 for t in TENSIONS], section=section,
                              edges_per_d0=edges, gauss_points=gauss)
    return {"edges_per_d0": edges, "samples": samples, "gauss_points": gauss,
            "thinning": thinning,
            "wall_time_s": time.perf_counter() - t0,
            "indent": [{"approach_over_d0": r["approach_over_d0"],
                        "force_over_e_d0sq": r["force_over_e_d0sq"],
                        "converged": r.get("converged", True)} for r in ind["steps"]],
            "wrap": [{"tension_over_e_d0sq": r["tension_over_e_d0sq"],
                      "line_load_mid_over_e_d0": r["force_per_length_mid_over_e_d0"],
                      "line_load_window_over_e_d0": r["force_per_length_mid_window_over_e_d0"],
                      "axial_over_across": r["contact_axial_over_across_mid"],
                      "converged": r.get("converged", True)} for r in wrap["steps"]]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--edges", type=int, nargs="+", default=[12, 24, 48])
    ap.add_argument("--samples", type=int, nargs="+", default=[64, 128])
    ap.add_argument("--gauss", type=int, nargs="+", default=[2, 3])
    ap.add_argument("--thinning", default="edge", choices=["edge", "rod"])
    ap.add_argument("--fem-json", help="a cross-check report with the FEM's indent and wrap")
    ap.add_argument("--json", help="write the rows here")
    args = ap.parse_args()
    fem_i, fem_w = _fem_levels(args.fem_json)
    rows = []
    print("edges/D0  M  gauss | indent F/(E D0^2) at approach 0.003 0.012 0.027 | wrap mid "
          "line load / window / axial:across at T 0.0069 0.0278 0.0625 | s")
    for edges in args.edges:
        for samples in args.samples:
            for gauss in args.gauss:
                row = run(edges, samples, gauss, args.thinning)
                rows.append(row)
                ind = " ".join(_rel(r["force_over_e_d0sq"], fem_i,
                                    round(r["approach_over_d0"], 3), ".3e")
                               for r in row["indent"])
                wr = " ".join(_rel(r["line_load_mid_over_e_d0"], fem_w,
                                   round(r["tension_over_e_d0sq"], 4), ".4f")
                              + f"/{r['line_load_window_over_e_d0']:.4f}"
                              f"/{r['axial_over_across']:.2f}"
                              for r in row["wrap"])
                print(f"{edges:8d} {samples:3d} {gauss:5d} | {ind} | {wr} | "
                      f"{row['wall_time_s']:.1f}", flush=True)
    if args.json:
        write_json_atomic(args.json, {"rows": rows, "fem_json": args.fem_json})


if __name__ == "__main__":
    main()
