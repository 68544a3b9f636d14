"""The section field along a straight rod against the FEM's indent (issue 18).

Runs the FEM's ``indent`` scene (two rigid cylinders crossing the rod; ``--meshes``, default
coarse and medium) and :class:`tightknot.contact.section_field.StraightSectionedRod` at the
same per-side approaches, for several mode counts, edge counts and with the axial gradient
energy off, and prints the force and the mid section's A/A0 against the last (finest) mesh,
beside the FEM's own mesh spread (docs/sectioned_level.md).

Usage::

    python bench/section_field.py [--meshes coarse medium] [--soft] [--json F]
"""

from __future__ import annotations

import argparse
import json
import time

from tightknot.contact.section_field import StraightSectionedRod
from tightknot.fem.scenes import indent

VARIANTS = [  # (modes N, edges on the half rod of 1.5 D0, gradient energy)
    (4, 75, True), (8, 75, True), (8, 150, True), (12, 75, True), (16, 75, True),
    (8, 75, False),
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="+", default=["coarse", "medium"])
    ap.add_argument("--json", help="write everything to this file")
    ap.add_argument("--soft", action="store_true",
                    help="also two soft rods crossing, against the rigid indent")
    args = ap.parse_args()
    fem, fem_time = {}, {}
    for mesh in args.meshes:
        t = time.perf_counter()
        fem[mesh] = indent.run(mesh=mesh, convergence=False)["steps"]
        fem_time[mesh] = time.perf_counter() - t
    ref = fem[args.meshes[-1]]
    ws = [s["w_over_d0"] for s in ref]
    print(f"FEM indent, w/D0 = {', '.join(f'{w:.4f}' for w in ws)}; wall time "
          + ", ".join(f"{m} {fem_time[m]:.0f} s" for m in args.meshes))
    for mesh in args.meshes[:-1]:
        rel = [s["force_over_e_d0sq"] / r["force_over_e_d0sq"] - 1.0
               for s, r in zip(fem[mesh], ref, strict=True)]
        print(f"FEM {mesh} vs {args.meshes[-1]} force: "
              + ", ".join(f"{100 * x:+.1f}" for x in rel) + " %")
    print(f"| N | edges | gradient | force rel to FEM {args.meshes[-1]} [%] per level | "
          "A/A0 diff [points], max | wall time [s] |")
    print("|---|---|---|---|---|---|")
    rows = []
    for n, edges, grad in VARIANTS:
        t = time.perf_counter()
        states = StraightSectionedRod("cylinder", n, 1.5, edges, gradient=grad).path(ws)
        wall = time.perf_counter() - t
        rel = [s.force_over_e_d0sq / r["force_over_e_d0sq"] - 1.0
               for s, r in zip(states, ref, strict=True)]
        area = max(abs(s.area_ratio_mid - r["area_ratio_mid"]) for s, r in zip(states, ref,
                                                                               strict=True))
        rows.append({"max_mode": n, "edges": edges, "gradient": grad, "force_rel": rel,
                     "area_diff_max": area, "wall_time_s": wall,
                     "states": [s.__dict__ for s in states]})
        print(f"| {n} | {edges} | {'yes' if grad else 'no'} | "
              + ", ".join(f"{100 * x:+.1f}" for x in rel)
              + f" | {100 * area:.1f} | {wall:.1f} |")
    if args.soft:
        # two soft rods crossing (the FEM's soft_crossing stack) against the rigid indent
        t = time.perf_counter()
        soft = StraightSectionedRod("rod", 8, 1.5, 75).path(ws)
        wall = time.perf_counter() - t
        rigid = rows[[(r["max_mode"], r["edges"], r["gradient"]) for r in rows]
                     .index((8, 75, True))]["states"]
        ratio = [s.force_over_e_d0sq / r["force_over_e_d0sq"] for s, r in zip(soft, rigid,
                                                                              strict=True)]
        rows.append({"max_mode": 8, "edges": 75, "gradient": True, "body": "rod",
                     "soft_over_rigid": ratio, "wall_time_s": wall,
                     "states": [s.__dict__ for s in soft]})
        print("soft crossing (N = 8, 75 edges) over the rigid indent at the same per-rod w: "
              + ", ".join(f"{x:.3f}" for x in ratio) + f" ({wall:.0f} s)")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"w_over_d0": ws, "fem": fem, "fem_wall_time_s": fem_time, "rows": rows},
                      fh, indent=1)


if __name__ == "__main__":
    main()
